"""Benchmark of the global fusion (001 step 24).

Run: .venv/bin/python benchmarks/global_fusion.py [--no-chain]

1. Core driven directly: N = 100, 300 targets spread over 20-80 km and 1-12 km
   altitude, the four bases of scenarios/dense.toml; plots = truth through g [47] plus
   white noise (sigma 60 m, 0.7 m/s, 0.5 deg, 3 channels), one real elementary tracker
   per base (its reports are what global fusion decorrelates); 40 cycles; the
   initialisation cycle (the first with confirmed elementary tracks: every global track
   initialised, module 62) and the median steady cycle (modules 63-65, from cycle 5)
   are reported, with the position RMSE of the steady cycles.
2. The whole chain over Zenoh on scenarios/dense.toml (router, simulator, 4 plotters,
   4 elementary trackers, global fusion, separate processes): wall time against the
   120 s of scenario time, and the RMSE / PCRLB ratio of the confirmed global tracks.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from common.bus.local_run import Deployment
from common.core.angles import wrap_2pi
from common.deploy.config import load, section
from common.evaluation.pcrlb import Evaluation, score_targets
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.radar.geometry.bistatic import POS, project
from common.radar.plots.channel_fusion import Plots
from common.wire.radar_messages import gtracks_message

DENSE = Path(__file__).resolve().parents[1] / "scenarios" / "dense.toml"
SIG = np.array([60.0, 0.7, np.radians(0.5)])


def core_benchmark(n: int, cycles: int = 40) -> tuple[float, float, float]:
    """(first cycle ms, median steady cycle ms, steady position RMSE m) for n targets."""
    cfg = load(DENSE)
    rng = np.random.default_rng(n)
    rho, az = rng.uniform(20e3, 80e3, n), rng.uniform(0, 2 * np.pi, n)
    p0 = np.column_stack([rho * np.sin(az), rho * np.cos(az), rng.uniform(1e3, 12e3, n)])
    course, speed = rng.uniform(0, 2 * np.pi, n), rng.uniform(150, 250, n)
    v = np.column_stack([speed * np.sin(course), speed * np.cos(course), np.zeros(n)])
    gf = GlobalFusion(cfg.bases, FusionParams())
    trk = {b.id: ElementaryTracker(ElementaryParams(), RadarCrossingParams(enabled=False))
           for b in cfg.bases}
    times, err = [], []
    for k in range(cycles):
        s = np.zeros((n, 6))
        s[:, POS], s[:, [1, 3, 5]] = p0 + v * k, v
        msgs = []
        for b in cfg.bases:
            y = project(s, b.tx, b.rx) + rng.standard_normal((n, 3)) * SIG
            sig = np.tile(SIG, (n, 1))
            r = trk[b.id].step(float(k), Plots(y[:, 0], y[:, 1], wrap_2pi(y[:, 2]), sig[:, 0],
                                               sig[:, 1], sig[:, 2], np.full(n, 3)))
            msgs.append((b.id, r))
        for m in msgs[:-1]:
            gf.push(*m)
        t0 = time.perf_counter()
        out = gtracks_message(gf.push(*msgs[-1])[0])
        times.append(time.perf_counter() - t0)
        if k >= 10:
            x = np.array([tr["x"] for tr in out["tracks"] if tr["status"] == "confirmed"])
            d = np.linalg.norm(s[:, POS][:, None, :] - x[:, POS][None, :, :], axis=2)
            err.append(d.min(axis=1))
    return 1e3 * times[2], 1e3 * float(np.median(times[5:])), float(np.sqrt(np.mean(np.square(err))))


def chain_benchmark() -> None:
    cfg = load(DENSE)
    with tempfile.TemporaryDirectory() as tmp, Deployment(Path(tmp)) as d:
        d.collect("radar/gtracks")
        d.collect("sim/truth/radar")
        alive = d.start_services(DENSE, ("channel-plotter", "elementary-tracker", "global-fusion"))
        d.wait_alive(alive)
        t0 = time.monotonic()
        d.simulate(DENSE, seed=1, wait_alive=alive)
        truth = sorted(d.of("sim/truth/radar"), key=lambda m: m["t"])
        t_last = truth[-1]["t"]
        d.wait_for(lambda: any(m["t"] == t_last for m in d.of("radar/gtracks")), timeout=600)
        wall = time.monotonic() - t0
        gtracks = {m["t"]: m for m in d.of("radar/gtracks")}
    print(f"chain on dense.toml: {t_last + 1:.0f} s of scenario in {wall:.1f} s wall "
          f"= {(t_last + 1) / wall:.1f}x real time; {len(gtracks)} fusion cycles")
    ev = Evaluation(c=2000.0, gamma=2000.0)
    for m in truth:
        conf = [k for k in gtracks.get(m["t"], {"tracks": []})["tracks"] if k["status"] == "confirmed"]
        ev.add(m["t"], m["id"], np.column_stack([m["x"], m["vx"], m["y"], m["vy"], m["z"], m["vz"]]),
               np.array([k["id"] for k in conf], dtype=np.int64),
               np.array([k["x"] for k in conf]).reshape(-1, 6),
               np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
    from common.evaluation.pcrlb import base_information
    from common.sim.scenario import radar_scene

    p = section(cfg, "radar.fusion", FusionParams)
    sc = score_targets(ev, np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
                       base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z,
                       np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]), 30.0)
    ratio = np.array([v.rmse / v.bound for v in sc.values()])
    s = ev.metrics.summary()
    print(f"  confirmed-track GOSPA mean {s.mean_gospa:.0f} m, switches {s.switches}, breaks "
          f"{s.breaks}; RMSE/PCRLB over {len(sc)} targets: median {np.median(ratio):.2f}, "
          f"90th pct {np.percentile(ratio, 90):.2f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--no-chain", action="store_true")
    args = ap.parse_args()
    for n in (100, 300):
        first, steady, rmse = core_benchmark(n)
        print(f"core, {n} targets x 4 bases: first cycle (init) {first:.0f} ms, steady cycle "
              f"{steady:.1f} ms (median), position RMSE {rmse:.0f} m")
    if not args.no_chain:
        chain_benchmark()


if __name__ == "__main__":
    main()
