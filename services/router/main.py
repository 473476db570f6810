"""``pfusion router``: a Zenoh router in a Python process (the Rust core routes)."""

from __future__ import annotations

import argparse
import logging

import zenoh

from common.bus.transport import stop_on_signals, zenoh_config

log = logging.getLogger("router")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--listen", action="append", required=True,
                   help="endpoint to listen on, e.g. tcp/127.0.0.1:7447 (repeatable)")
    p.add_argument("--connect", action="append", default=[],
                   help="another router to connect to (repeatable)")


def main(args: argparse.Namespace) -> int:
    stop = stop_on_signals()
    with zenoh.open(zenoh_config(args.connect, args.listen, mode="router")):
        log.info("router listening on %s", ", ".join(args.listen))
        while not stop.wait(0.2):
            pass
    log.info("router stopped")
    return 0
