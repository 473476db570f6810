"""``pfusion simulate``: publish a scenario's channel plots, sonar detections and truth
in scenario time, as fast as possible or at ``--speed`` times real time."""

from __future__ import annotations

import argparse
import dataclasses
import logging
import signal
import threading
import time
import tomllib
from pathlib import Path

import zenoh

from common import protocol
from common.bus import open_session
from common.cli import add_common, load_config
from common.simulator import load_scenario, run_scenario

log = logging.getLogger("simulate")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--scenario", required=True, help="scenario TOML file (scenarios/*.toml)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--speed", type=float, default=0.0,
                   help="times real time; 0 (default) publishes as fast as possible")
    p.add_argument("--scans", type=int, default=None,
                   help="number of scans (extends the scenario's duration if needed)")
    p.add_argument("--wait-alive", action="append", default=[], metavar="SERVICE/INSTANCE",
                   help="wait until this service's liveliness token exists (repeatable)")
    p.add_argument("--wait-timeout", type=float, default=60.0)


def wait_alive(session: zenoh.Session, root: str, names: list[str], timeout: float) -> None:
    """Block until every root/alive/<name> liveliness token is present."""
    deadline = time.monotonic() + timeout
    missing = set(names)
    while missing:
        for name in list(missing):
            if any(r.ok for r in session.liveliness().get(f"{root}/alive/{name}", timeout=1.0)):
                missing.discard(name)
        if missing and time.monotonic() > deadline:
            raise TimeoutError(f"services not alive after {timeout} s: {sorted(missing)}")
        if missing:
            time.sleep(0.1)
    time.sleep(0.3)  # let subscriber declarations reach every router on the path


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    path = Path(args.scenario)
    try:
        scn = load_scenario(tomllib.loads(path.read_text()))
    except (OSError, tomllib.TOMLDecodeError, ValueError) as e:
        log.error("scenario %s: %s", path, e)
        return 2
    if args.scans:
        period = min(s.scan_period for s in (scn.radar, scn.sonar) if s is not None)
        scn = dataclasses.replace(scn, duration=max(scn.duration, args.scans * period))
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    root = cfg.zenoh.root
    with open_session(cfg.zenoh) as session:
        token = session.liveliness().declare_token(f"{root}/alive/simulate/{path.stem}")
        wait_alive(session, root, args.wait_alive, args.wait_timeout)
        pubs: dict[str, zenoh.Publisher] = {}
        published = scans = 0
        t_first = t = 0.0
        wall0 = time.monotonic()
        for t, messages in run_scenario(scn, cfg.bases, cfg.arrays, args.seed, args.scans):
            if stop.is_set():
                break
            if scans == 0:
                t_first = t
            if args.speed > 0:
                delay = wall0 + (t - t_first) / args.speed - time.monotonic()
                if delay > 0 and stop.wait(delay):
                    break
            for suffix, msg in messages:
                pub = pubs.get(suffix)
                if pub is None:
                    pub = pubs[suffix] = session.declare_publisher(
                        f"{root}/{suffix}", congestion_control=zenoh.CongestionControl.BLOCK,
                        reliability=zenoh.Reliability.RELIABLE)
                pub.put(protocol.encode(msg))
                published += 1
            scans += 1
        status = {"v": protocol.VERSION, "t": float(t), "state": "done",
                  "scans": scans, "published": published}
        session.put(f"{root}/sim/status", protocol.encode(status),
                    congestion_control=zenoh.CongestionControl.BLOCK)
        log.info("published %d messages in %d scans (%.1f s wall)",
                 published, scans, time.monotonic() - wall0)
        for pub in pubs.values():
            pub.undeclare()
        token.undeclare()
    return 0
