"""``pfusion simulate``: publish a scenario's channel plots, sonar detections and truth
in scenario time, as fast as possible or at ``--speed`` times real time.

``--repeat K --gap G`` publishes K seeded runs back to back (for swap statistics): run i
uses seed + i and times shifted by i * (duration + G); each run is followed by G seconds
of scans of the same scenario without targets (clutter only), in which trackers delete
the run's tracks. Truth ids are the scenario's in every run; sequence numbers go on.

``--adsb-out DIR`` also writes the radar truth as readsb aircraft.json snapshots, one
file a scan (common.wire.adsb_snapshot), for ``pfusion evaluate --truth-adsb``."""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import logging
import time
import tomllib
from pathlib import Path

import zenoh

from common.bus.refusal import silence_causes
from common.bus.transport import Publisher, linger, open_session, stop_on_signals, wait_alive
from common.cli import add_common, load_config
from common.sim.simulator import load_scenario
from common.wire import protocol
from common.wire.adsb_snapshot import aircraft_json
from common.wire.sim_messages import repeated

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
    p.add_argument("--repeat", type=int, default=1, metavar="K",
                   help="publish K runs back to back: run i uses seed + i, times shifted by "
                        "i * (duration + gap); truth ids repeat, sequence numbers go on")
    p.add_argument("--gap", type=float, default=0.0, metavar="SECONDS",
                   help="with --repeat: target-free scans (clutter only) after each run, so "
                        "that trackers delete the run's tracks")
    p.add_argument("--adsb-out", metavar="DIR", default=None,
                   help="also write the radar truth as aircraft.json snapshots to DIR "
                        "(geodetic deployments)")


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    path = Path(args.scenario)
    try:
        scn = load_scenario(tomllib.loads(path.read_text()))
    except (OSError, tomllib.TOMLDecodeError, ValueError) as e:
        log.error("scenario %s: %s", path, e)
        return 2
    if args.repeat < 1 or args.gap < 0:
        log.error("--repeat must be >= 1 and --gap >= 0")
        return 2
    if args.adsb_out and cfg.origin is None:
        log.error("--adsb-out needs a geodetic deployment ([radar.origin])")
        return 2
    adsb = Path(args.adsb_out) if args.adsb_out else None
    if adsb is not None:
        adsb.mkdir(parents=True, exist_ok=True)
    if args.scans:
        period = min(s.scan_period for s in (scn.radar, scn.sonar) if s is not None)
        scn = dataclasses.replace(scn, duration=max(scn.duration, args.scans * period))
    stop = stop_on_signals()
    root = cfg.zenoh.root
    with open_session(cfg.zenoh) as session:
        token = session.liveliness().declare_token(f"{root}/alive/simulate/{path.stem}")
        scans_iter = repeated(scn, cfg, args.seed, args.scans, args.repeat, args.gap)
        first = next(scans_iter, None)
        # the first scan's publishers are declared before waiting for the subscribers, so
        # the routing of every key is settled before the first sample
        pubs = {suffix: Publisher(session, f"{root}/{suffix}") for suffix, _ in (first or (0, []))[1]}
        wait_alive(session, root, args.wait_alive, args.wait_timeout, stop,
                   silence_causes(cfg.zenoh) if cfg.zenoh.auth is not None else "")
        published = scans = 0
        t_first = t = 0.0
        wall0 = time.monotonic()
        for t, messages in itertools.chain([first] if first else [], scans_iter):
            if stop.is_set():
                break
            if scans == 0:
                t_first = t
            if args.speed > 0:
                delay = wall0 + (t - t_first) / args.speed - time.monotonic()
                if delay > 0 and stop.wait(delay):
                    break
            for suffix, msg in messages:
                if suffix not in pubs:
                    pubs[suffix] = Publisher(session, f"{root}/{suffix}")
                pubs[suffix].put(protocol.encode(msg))
                published += 1
                if adsb is not None and cfg.origin is not None and suffix == "sim/truth/radar":
                    (adsb / f"aircraft-{scans:06d}.json").write_text(json.dumps(aircraft_json(msg, cfg.origin)))
            scans += 1
        status = {"v": protocol.VERSION, "t": float(t), "state": "done",
                  "scans": scans, "published": published}
        session.put(f"{root}/sim/status", protocol.encode(status),
                    congestion_control=zenoh.CongestionControl.BLOCK)
        linger()
        log.info("published %d messages in %d scans (%.1f s wall)",
                 published, scans, time.monotonic() - wall0)
        token.undeclare()
    return 0
