"""``pfusion status``: the live services (liveliness tokens under ``<root>/alive/``) and
their latest counters (``<root>/metrics/**``, published every 2 s), as a table."""

from __future__ import annotations

import argparse
import time
from typing import Any

from common.bus.liveliness import alive, take
from common.bus.transport import Inbox, open_session, stop_on_signals
from common.cli import add_common, load_config

LISTEN_S = 2.5
COLUMNS = ("service", "instance", "in", "out", "rejected", "missed", "p50_ms", "p99_ms", "queue", "last_t")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("--watch", action="store_true", help=f"refresh every {LISTEN_S} s until Ctrl-C")


def table(live: list[tuple[str, str]], metrics: dict[tuple[str, str], dict[str, Any]]) -> str:
    """One row per live service; '-' where it publishes no counters; rejections by reason
    after the columns."""
    rows = [list(COLUMNS)]
    reasons: list[str] = [""]
    for svc in live:
        m = metrics.get(svc)
        if m is None:
            rows.append([*svc, *["-"] * (len(COLUMNS) - 2)])
            reasons.append("")
            continue
        rej = m.get("rejected", {})
        rows.append([*svc, str(m["in"]), str(m["out"]), str(sum(rej.values())),
                     str(sum(m.get("missed", {}).values())),
                     f"{m['p50_ms']:.2f}", f"{m['p99_ms']:.2f}", str(m["queue"]), f"{m['t']:.3f}"])
        reasons.append(", ".join(f"{k}={v}" for k, v in sorted(rej.items())))
    widths = [max(len(r[i]) for r in rows) for i in range(len(COLUMNS))]
    lines = []
    for row, why in zip(rows, reasons):
        cells = [c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(row, widths))]
        lines.append(("  ".join(cells) + ("  " + why if why else "")).rstrip())
    return "\n".join(lines)


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    root = cfg.zenoh.root
    stop = stop_on_signals()
    inbox = Inbox()
    metrics: dict[tuple[str, str], dict[str, Any]] = {}
    with open_session(cfg.zenoh) as session:
        sub = session.declare_subscriber(f"{root}/metrics/**", inbox.on_sample)
        while True:
            start = time.monotonic()
            live = alive(session, root)
            stop.wait(max(0.0, LISTEN_S - (time.monotonic() - start)))
            take(inbox, metrics)
            if args.watch:
                print(time.strftime("%H:%M:%S"), f"{len(live)} live under {root}")
            print(table(live, metrics) if live else f"no live services under {root}", flush=True)
            if not args.watch or stop.is_set():
                break
            print(flush=True)
        sub.undeclare()
    return 0
