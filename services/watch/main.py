"""``pfusion watch KEYEXPR``: print decoded messages live, one readable line each."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from common.bus.transport import Inbox, open_session, stop_on_signals
from common.cli import add_common, load_config
from common.wire import protocol


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("keyexpr", help="key expression under the root, e.g. 'radar/**'")
    p.add_argument("--count", type=int, default=0, help="exit after this many messages")


def summary(key: str, msg: dict[str, Any]) -> str:
    """One line: time, key, then list lengths and track ids."""
    parts = [f"t={msg.get('t', float('nan')):.3f}", key]
    for name, value in msg.items():
        if name in ("v", "t"):
            continue
        if name == "tracks":
            ids = [tr["id"] for tr in value]
            parts.append(f"tracks={len(ids)} ids={ids}")
        elif hasattr(value, "__len__") and not isinstance(value, str):
            parts.append(f"{name}[{len(value)}]")
        else:
            parts.append(f"{name}={value}")
    return " ".join(parts)


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    root = cfg.zenoh.root
    stop = stop_on_signals()
    inbox = Inbox()
    n = 0
    with open_session(cfg.zenoh) as session:
        sub = session.declare_subscriber(f"{root}/{args.keyexpr}", inbox.on_sample)
        while not stop.is_set() and (args.count == 0 or n < args.count):
            env = inbox.get(0.1)
            if env is None:
                continue
            n += 1
            kind = protocol.kind_of(env.key, root)
            try:
                msg = protocol.decode(kind, env.payload) if kind else protocol.unpack(env.payload)
                print(summary(env.key, msg), flush=True)
            except protocol.DecodeError as e:
                print(f"{env.key} INVALID {e}", file=sys.stderr, flush=True)
        sub.undeclare()
    return 0
