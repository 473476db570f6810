"""``pfusion demo``: the built-in scenarios through everything that exists, on a router
of its own on a free loopback port, then a short summary.

Stage 1 (foundation): simulator -> router -> a collector that decodes and counts every
message, checks per-key order and reports losses.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter, defaultdict
from pathlib import Path

from common import protocol
from common.bus import Inbox, open_session
from common.cli import add_common
from common.config import ZenohConfig, load
from common.procs import Child, start_router
from services.watch.main import kind_of

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("--radar", default=str(SCENARIOS / "two_targets.toml"))
    p.add_argument("--sonar", default=str(SCENARIOS / "sonar_tma.toml"))
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="out", help="folder for logs and pictures")


class Collector:
    """Decodes every message under the root, counts per kind, checks seq order per key."""

    def __init__(self, root: str) -> None:
        self.root = root
        self.inbox = Inbox()
        self.count: Counter[str] = Counter()
        self.invalid = 0
        self.out_of_order = 0
        self.last_seq: dict[str, int] = {}
        self.published: list[int] = []
        self.keys: dict[str, set[str]] = defaultdict(set)

    def drain(self) -> None:
        while (env := self.inbox.get(0.0)) is not None:
            self.take(env.key, env.payload)

    def take(self, key: str, payload: bytes) -> None:
        kind = kind_of(key, self.root)
        if kind is None:
            return
        try:
            msg = protocol.decode(kind, payload)
        except protocol.DecodeError:
            self.invalid += 1
            return
        if kind == "sim_status":
            self.published.append(msg["published"])
            return
        self.count[kind] += 1
        self.keys[kind].add(key)
        if "seq" in msg:
            if msg["seq"] != self.last_seq.get(key, -1) + 1:
                self.out_of_order += 1
            self.last_seq[key] = msg["seq"]


def main(args: argparse.Namespace) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    router, endpoint = start_router(log=out / "router.log")
    root = load(args.radar).zenoh.root
    col = Collector(root)
    sims: list[Child] = []
    t0 = time.monotonic()
    try:
        with open_session(ZenohConfig([endpoint], [], root)) as session:
            sub = session.declare_subscriber(f"{root}/**", col.inbox.on_sample)
            token = session.liveliness().declare_token(f"{root}/alive/demo/collector")
            for scenario in (args.radar, args.sonar):
                sims.append(Child(
                    "simulate", "simulate", "--config", scenario, "--scenario", scenario,
                    "--connect", endpoint, "--seed", str(args.seed),
                    "--wait-alive", "demo/collector", log=out / f"simulate-{Path(scenario).stem}.log",
                ))
            for sim in sims:
                while sim.alive():
                    col.drain()
                    time.sleep(0.05)
            deadline = time.monotonic() + 10
            while len(col.published) < len(sims) and time.monotonic() < deadline:
                col.drain()
                time.sleep(0.05)
            col.drain()
            token.undeclare()
            sub.undeclare()
    finally:
        for sim in sims:
            sim.stop()
        router.stop()
    return report(col, time.monotonic() - t0, [s.proc.returncode for s in sims])


def report(col: Collector, wall: float, codes: list[int]) -> int:
    """Print the summary; non-zero exit if anything was lost or a child failed."""
    received = sum(col.count.values())
    published = sum(col.published)
    print(f"passive-fusion demo: {wall:.1f} s wall, router on loopback")
    print(f"{'message kind':<14}{'keys':>6}{'messages':>10}")
    for kind in sorted(col.count):
        print(f"{kind:<14}{len(col.keys[kind]):>6}{col.count[kind]:>10}")
    print(f"published {published}, received {received}, lost {published - received}, "
          f"out of order {col.out_of_order}, invalid {col.invalid}")
    ok = published == received and col.out_of_order == 0 and col.invalid == 0
    return 0 if ok and all(c == 0 for c in codes) else 1
