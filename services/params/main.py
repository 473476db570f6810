"""``pfusion params``: print the configuration reference (every parameter table, its
keys, types, defaults and meaning), or check a deployment file with ``--check F``
(every table, [sim] with the simulator's own checks)."""

from __future__ import annotations

import argparse

from common.deploy.config import load
from common.deploy.sections import check_all, markdown
from common.sim.scenario import load_scenario


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--check", metavar="F", help="validate deployment file F and exit")


def check(path: str) -> None:
    """Raise ConfigError for the first problem of deployment file ``path``."""
    cfg = load(path)
    check_all(cfg)
    if "sim" in cfg.doc:
        load_scenario(cfg.doc)


def main(args: argparse.Namespace) -> int:
    if args.check:
        check(args.check)
        print(f"{args.check}: valid")
        return 0
    print(markdown(), end="")
    return 0
