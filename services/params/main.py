"""``pfusion params``: print the configuration reference (every parameter table, its
keys, types, defaults and meaning), or check a deployment file with ``--check F``."""

from __future__ import annotations

import argparse

from common.deploy.config import load
from common.deploy.sections import check_all, markdown


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--check", metavar="F", help="validate deployment file F and exit")


def main(args: argparse.Namespace) -> int:
    if args.check:
        check_all(load(args.check))
        print(f"{args.check}: valid")
        return 0
    print(markdown(), end="")
    return 0
