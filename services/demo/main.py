"""``pfusion demo``: the built-in radar and sonar scenarios through every service that
exists, on a router of its own on a free loopback port; then a metrics table and two
pictures (out/radar.png, out/sonar.png).

The demo is a client like any user tool: it subscribes to the public keys, checks that
nothing published was lost, and scores the tracks against the simulator's truth.
"""

from __future__ import annotations

import argparse
import socket
import sys
import time
import tomllib
from collections import defaultdict
from pathlib import Path
from typing import Any

from common.bus.procs import Child, start_router
from common.bus.transport import Inbox, free_port, open_session, wait_port
from common.cli import COMMANDS, add_common
from common.deploy.config import ZenohConfig, load
from common.deploy.deployment import ChildSpec, plan
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.protocol import kind_of
from services.demo.report import Collected, radar_table, sonar_table

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
BAR = 30
QUIET_S = 2.0
VIEW_PORT = 8080
VIEW_SPEED = {"radar": 2.0, "sonar": 60.0}  # ~1 min each, slow enough to watch


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("--radar", default=str(SCENARIOS / "two_targets.toml"))
    p.add_argument("--sonar", default=str(SCENARIOS / "sonar_tma.toml"))
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="out", help="folder for logs and pictures")
    p.add_argument("--view", action="store_true",
                   help=f"serve the live view (pfusion view) on port {VIEW_PORT} (or a free one) "
                        "while the demo runs; the simulators then run at "
                        + ", ".join(f"{k} {v:g}x" for k, v in VIEW_SPEED.items()) + " real time")


class Collector:
    """Decodes every message under the root; counts per-key order and losses."""

    def __init__(self, root: str) -> None:
        self.root = root
        self.inbox = Inbox()
        self.by_kind: dict[str, list[dict[str, Any]]] = defaultdict(list)
        self.invalid = 0
        self.out_of_order = 0
        self.last_seq: dict[str, int] = {}
        self.published: list[int] = []
        self.sim_data = 0
        self.last_arrival = time.monotonic()

    def drain(self) -> None:
        while (env := self.inbox.get(0.0)) is not None:
            self.take(env.key, env.payload)

    def take(self, key: str, payload: bytes) -> None:
        kind = kind_of(key, self.root)
        if kind is None:
            return
        self.last_arrival = time.monotonic()
        try:
            msg = protocol.decode(kind, payload)
        except protocol.DecodeError:
            self.invalid += 1
            return
        if kind == "sim_status":
            self.published.append(msg["published"])
            return
        self.by_kind[kind].append(msg)
        if kind in ("plots", "detections") or kind.startswith("truth_"):
            self.sim_data += 1
        if "seq" in msg:
            if msg["seq"] != self.last_seq.get(key, -1) + 1:
                self.out_of_order += 1
            self.last_seq[key] = msg["seq"]


def horizon(path: str) -> float:
    """Duration of a scenario file (scenario seconds)."""
    return load_scenario(tomllib.loads(Path(path).read_text())).duration


def progress(col: Collector, durations: dict[str, float]) -> str:
    parts = []
    for name, kind in (("radar", "truth_radar"), ("sonar", "truth_sonar")):
        msgs = col.by_kind.get(kind, [])
        frac = min(1.0, (msgs[-1]["t"] / durations[name]) if msgs else 0.0)
        n = int(frac * BAR)
        parts.append(f"{name} [{'#' * n}{'.' * (BAR - n)}] {100 * frac:3.0f}%")
    return "  ".join(parts)


def main(args: argparse.Namespace) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("*.log"):
        old.unlink()
    radar_cfg, sonar_cfg = load(args.radar), load(args.sonar)
    root = radar_cfg.zenoh.root
    durations = {"radar": horizon(args.radar), "sonar": horizon(args.sonar)}
    router, endpoint = start_router(log=out / "router.log")
    specs: list[ChildSpec] = (plan(radar_cfg, args.radar, COMMANDS, [endpoint])
                              + plan(sonar_cfg, args.sonar, COMMANDS, [endpoint]))
    children: list[Child] = []
    col = Collector(root)
    t0 = time.monotonic()
    try:
        with open_session(ZenohConfig([endpoint], [], root)) as session:
            sub = session.declare_subscriber(f"{root}/**", col.inbox.on_sample)
            token = session.liveliness().declare_token(f"{root}/alive/demo/collector")
            children += [Child(s.name, *s.argv, log=out / f"{s.name.replace('/', '-')}.log")
                         for s in specs]
            waits = ["demo/collector", *[s.alive for s in specs]]
            if args.view:
                children.append(start_view(args.radar, endpoint, out))
            for name, scenario in (("radar", args.radar), ("sonar", args.sonar)):
                argv = ["simulate", "--config", scenario, "--scenario", scenario,
                        "--connect", endpoint, "--seed", str(args.seed), "--wait-timeout", "120"]
                if args.view:
                    argv += ["--speed", str(VIEW_SPEED[name])]
                for w in waits:
                    argv += ["--wait-alive", w]
                children.append(Child("simulate", *argv, log=out / f"simulate-{Path(scenario).stem}.log"))
            sims = children[-2:]
            while any(s.alive() for s in sims) or len(col.published) < len(sims):
                col.drain()
                if sys.stderr.isatty():
                    print(f"\r{progress(col, durations)}", end="", file=sys.stderr, flush=True)
                if not any(s.alive() for s in sims) and time.monotonic() - col.last_arrival > 10:
                    break
                time.sleep(0.1)
            while time.monotonic() - col.last_arrival < QUIET_S:
                col.drain()
                time.sleep(0.05)
            print(f"\r{progress(col, durations)}", file=sys.stderr)
            token.undeclare()
            sub.undeclare()
    finally:
        for c in reversed(children):
            c.stop()
        router.stop()
    wall = time.monotonic() - t0
    data = Collected(radar_cfg, sonar_cfg, col.by_kind)
    return report(col, data, wall, [s.name for s in specs], out,
                  [c.proc.returncode for c in children[-2:]])


def start_view(config: str, endpoint: str, out: Path) -> Child:
    """``pfusion view`` on VIEW_PORT (a free port if it is taken); prints its address."""
    port = VIEW_PORT
    try:
        socket.create_server(("127.0.0.1", port)).close()
    except OSError:
        port = free_port()
    view = Child("view", "view", "--config", config, "--connect", endpoint, "--port", str(port),
                 log=out / "view.log")
    wait_port(port, 60)
    print(f"live view: http://127.0.0.1:{port}/ (open it now: it is served while the demo runs)",
          flush=True)
    return view


def report(col: Collector, data: Collected, wall: float, services: list[str],
           out: Path, sim_codes: list[int]) -> int:
    """Print the summary and draw the pictures; non-zero if anything was lost."""
    from services.demo.pictures import radar_picture, sonar_picture

    published = sum(col.published)
    print(f"passive-fusion demo: {wall:.1f} s wall; services: {', '.join(services) or 'none'}")
    print(f"simulator published {published} messages, received {col.sim_data}, "
          f"lost {published - col.sim_data}, out of order {col.out_of_order}, "
          f"invalid {col.invalid}")
    print(f"{'message kind':<14}{'messages':>10}")
    for kind in sorted(col.by_kind):
        print(f"{kind:<14}{len(col.by_kind[kind]):>10}")
    print()
    print(radar_table(data))
    print()
    print(sonar_table(data))
    radar_picture(data.radar_cfg, data.of("truth_radar"), data.of("gtracks"), out / "radar.png")
    sonar_picture(data.of("detections"), data.of("btracks"), data.of("truth_sonar"),
                  data.of("tma"), out / "sonar.png")
    print(f"\npictures: {out / 'radar.png'}, {out / 'sonar.png'}; logs in {out}/")
    ok = published == col.sim_data and col.out_of_order == 0 and col.invalid == 0
    return 0 if ok and all(c == 0 for c in sim_codes) else 1
