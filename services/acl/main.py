"""``pfusion acl --config F``: print the Zenoh ``access_control`` section generated from
deployment F (common.deploy.acl), the one ``pfusion router --config F`` applies."""

from __future__ import annotations

import argparse

from common.cli import load_config
from common.deploy.acl import access_control, to_json5


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", required=True, help="deployment TOML file")


def main(args: argparse.Namespace) -> int:
    args.connect = None
    print(to_json5(access_control(load_config(args))))
    return 0
