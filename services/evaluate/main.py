"""``pfusion evaluate``: score the global tracks against the simulator truth, live and
at the end: GOSPA (with switching term) and OSPA, track number switches and breaks
(common.evaluation.metrics; per step, and on the assignment minimised over the whole
run, common.evaluation.trajectory_gospa), position RMSE against the PCRLB and NEES (common.evaluation.pcrlb).

Subscribes radar/gtracks (in a partitioned deployment every radar/gtracks/<p>, scoring
their union: common.wire.gtracks_union), sim/truth/radar and sim/status; pairs tracks and truth by
message time (common.evaluation.pairing); only confirmed global tracks are scored; with
no step scored it says so and exits 1. Stops on SIGTERM/SIGINT, or
once sim/status says "done" and nothing arrived for --quiet seconds; then prints the
final table on stdout. The PCRLB needs the scenario part ([sim.radar]) of the config
for the channel accuracies and detection probabilities.

With ``--truth-adsb`` the truth is recorded ADS-B (readsb / tar1090 aircraft.json
snapshots, common.evaluation.adsb) in a geodetic deployment, the tracks come from
radar/gtracks live or from a recording (``--tracks``); tracks on no ADS-B aircraft are
reported as unverified, not scored (docs/networks.md).
"""

from __future__ import annotations

import argparse
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import Config, section
from common.deploy.deployment import partitions
from common.evaluation.adsb import AdsbScoring, AdsbTruth
from common.evaluation.metrics import count_switches
from common.evaluation.pairing import StepPairing
from common.evaluation.pcrlb import Evaluation, base_information, score_targets
from common.radar.fusion.params import FusionParams
from common.sim.scenario import radar_scene
from common.wire import protocol
from common.wire.gtracks_union import GtracksUnion, partition_of
from common.wire.radar_messages import confirmed_tracks
from common.wire.sim_messages import truth_state
from services.evaluate.adsb_input import read_fixes, recorded_gtracks


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--cutoff", type=float, default=2000.0, help="GOSPA/OSPA cutoff c (m)")
    p.add_argument("--settle", type=float, default=20.0,
                   help="seconds after a target's first pairing before RMSE/NEES count")
    p.add_argument("--quiet", type=float, default=2.0,
                   help="stop this many seconds after sim done with no new message")
    p.add_argument("--every", type=int, default=10, help="print a live line every N steps")
    p.add_argument("--truth-adsb", metavar="DIR_OR_FILE",
                   help="score against recorded ADS-B aircraft.json snapshots, not the simulator")
    p.add_argument("--baro-offset", type=float, default=None, metavar="M",
                   help="with --truth-adsb: use alt_baro + M metres (ellipsoidal) where alt_geom "
                        "is missing (default: such positions are rejected)")
    p.add_argument("--adsb-max-gap", type=float, default=10.0, metavar="S",
                   help="with --truth-adsb: no interpolation between fixes further apart")
    p.add_argument("--tracks", metavar="FILE.pfrec",
                   help="with --truth-adsb: radar/gtracks of a recording instead of live")


def report(ev: Evaluation, cfg: Config, settle: float, names: dict[int, str] | None = None) -> str:
    """The final table; ``names``: how to print the truth ids (ADS-B addresses)."""
    names = names or {}
    s = ev.metrics.summary()
    lines = [f"steps {s.steps}  mean GOSPA {s.mean_gospa:.1f} m  mean OSPA {s.mean_ospa:.1f} m  "
             f"GOSPA {s.gospa:.1f} (loc {s.localisation:.3g} missed {s.missed:.3g} "
             f"false {s.false:.3g} switching {s.switching:.3g})  switches {s.switches}  "
             f"breaks {s.breaks}"]
    joint = count_switches(ev.metrics.joint_associations())
    lines.append(f"assignment minimised over the run (trajectory GOSPA): switches {joint.switches}  "
                 f"breaks {joint.breaks}")
    radar = radar_scene(cfg)
    info = base_information(radar, cfg.bases) if radar is not None else None
    if info is None:
        return "\n".join(lines + ["(no [sim.radar] in the config: no PCRLB)"])
    p = section(cfg, "radar.fusion", FusionParams)
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    P0 = np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2])
    scores = score_targets(ev, tx, rx, info, p.q, p.q_z, P0, settle)
    lines.append(f"{'truth':>6} {'n':>5} {'RMSE m':>9} {'PCRLB m':>9} {'ratio':>6} "
                 f"{'NEES3':>6} {'NEES6':>6}")
    for i, sc in sorted(scores.items()):
        lines.append(f"{names.get(i, str(i)):>6} {sc.n:>5} {sc.rmse:>9.1f} {sc.bound:>9.1f} "
                     f"{sc.rmse / sc.bound:>6.2f} {sc.nees_pos:>6.2f} {sc.nees_state:>6.2f}")
    lines.append("NEES3 / NEES6: mean position / state NEES of this run (3 / 6 if the "
                 "covariance is honest); one run's samples are correlated in time, so its "
                 "mean is no test: benchmarks/global_consistency.py averages over runs")
    return "\n".join(lines)


def _live(svc: Service, quiet: float) -> Callable[[], None]:
    """Stop ``svc`` once sim/status said done and nothing arrived for ``quiet`` s; the
    function returned notes an arrival."""
    state = {"done": False, "last": time.monotonic()}

    def on_status(key: str, payload: bytes) -> None:
        state["done"] = protocol.decode("sim_status", payload)["state"] == "done"
        state["last"] = time.monotonic()

    def watchdog() -> None:
        while not (state["done"] and time.monotonic() - state["last"] > quiet):
            time.sleep(0.2)
        svc.stop()

    def seen() -> None:
        state["last"] = time.monotonic()

    svc.subscribe("sim/status", on_status)
    threading.Thread(target=watchdog, daemon=True).start()
    return seen


def adsb_report(scoring: AdsbScoring, rejects: Counter[str]) -> str:
    """The ADS-B lines: truth quality, rejects, unverified tracks."""
    lower = Counter(scoring.truth.lower.values())
    return (f"ADS-B truth: {len(scoring.truth.paths)} aircraft, lower-quality "
            f"{dict(lower) or 'none'}; rejected {dict(rejects) or 'none'}\n"
            f"unverified (no ADS-B aircraft within the cutoff, not scored): "
            f"{len(scoring.unverified)} tracks {sorted(scoring.unverified)}, "
            f"{scoring.unverified_steps} track-steps")


def main_adsb(args: argparse.Namespace, cfg: Config) -> int:
    """``--truth-adsb``: the global tracks against recorded ADS-B."""
    if cfg.origin is None:
        print("pfusion evaluate: --truth-adsb needs a geodetic deployment ([radar.origin])", flush=True)
        return 2
    rejects: Counter[str] = Counter()
    truth = AdsbTruth(cfg.origin, args.adsb_max_gap)
    truth.add(read_fixes(Path(args.truth_adsb), rejects, args.baro_offset))
    if not truth.paths:
        print(f"no usable ADS-B position in {args.truth_adsb} (rejected: {dict(rejects)})", flush=True)
        return 1
    scoring = AdsbScoring(truth, Evaluation(c=args.cutoff, gamma=args.cutoff))

    def score(g: dict[str, Any]) -> None:
        times = scoring.ev.metrics.times
        if times and g["t"] <= times[-1]:
            raise Rejected("out_of_order", f"gtracks t={g['t']} not after the last scored t={times[-1]}")
        scoring.add(g["t"], *confirmed_tracks(g))

    code = 0
    if args.tracks:
        for g in recorded_gtracks(Path(args.tracks), rejects):
            try:
                score(g)
            except Rejected as e:
                rejects[e.reason] += 1
    else:
        svc = Service("evaluate", "main", cfg)
        seen = _live(svc, args.quiet)

        union = GtracksUnion(partitions(cfg))

        def on_gtracks(key: str, payload: bytes) -> None:
            seen()
            for g in union.push(partition_of(key, svc.root), protocol.decode("gtracks", payload)):
                score(g)

        svc.subscribe(gtracks_key(cfg), on_gtracks)
        code = svc.run()
        rejects.update(svc.rejected)
    if not scoring.ev.metrics.times:
        print(f"no step scored: no radar/gtracks (rejected: {dict(rejects) or 'none'})", flush=True)
        return code or 1
    print(report(scoring.ev, cfg, args.settle, truth.hexes) + "\n" + adsb_report(scoring, rejects), flush=True)
    return code


def gtracks_key(cfg: Config) -> str:
    """The global tracks' key: each partition's (their union is scored) or the one."""
    return "radar/gtracks/*" if partitions(cfg) else "radar/gtracks"


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    if args.truth_adsb:
        return main_adsb(args, cfg)
    ev = Evaluation(c=args.cutoff, gamma=args.cutoff)
    svc = Service("evaluate", "main", cfg)
    pairing: StepPairing[dict[str, Any], dict[str, Any]] = StepPairing()

    def score(step: tuple[float, dict[str, Any], dict[str, Any]] | None) -> None:
        if step is None:
            return
        t, m, g = step
        ids, tx, tP = confirmed_tracks(g)
        ev.add(t, m["id"], truth_state(m), ids, tx, tP)
        svc.last_t = t
        k = len(ev.metrics.times)
        if k % args.every == 0:
            r = ev.metrics.gospa_series[-1]
            print(f"t={t:8.1f} truths={len(m['id'])} confirmed={len(ids)} GOSPA={r.distance:8.1f} "
                  f"OSPA={ev.metrics.ospa_series[-1]:8.1f}", flush=True)

    seen = _live(svc, args.quiet)

    def on_truth(key: str, payload: bytes) -> None:
        m = protocol.decode("truth_radar", payload)
        seen()
        score(pairing.truth(m["t"], m))

    union = GtracksUnion(partitions(cfg))

    def on_gtracks(key: str, payload: bytes) -> None:
        g = protocol.decode("gtracks", payload)
        seen()
        for u in union.push(partition_of(key, svc.root), g):
            score(pairing.tracks(u["t"], u))

    svc.subscribe(gtracks_key(cfg), on_gtracks)
    svc.subscribe("sim/truth/radar", on_truth)
    code = svc.run()
    if not ev.metrics.times:
        print("no step scored: no radar/gtracks and sim/truth/radar of one time arrived "
              f"(rejected: {dict(svc.rejected) or 'none'}); is the deployment running and the "
              "simulator publishing its truth?", flush=True)
        return code or 1
    print(report(ev, cfg, args.settle), flush=True)
    return code
