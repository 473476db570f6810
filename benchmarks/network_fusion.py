"""Benchmark of the network fusion centre (common.radar.network, docs/networks.md).

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_fusion.py [--seed N] [--duration S]

The synthetic network of tests/radar/network_scene.py (8 receivers, >= 20 range-Doppler
bases over ~150 km, unsynchronised, pd 0.9, elementary reports from per-base Kalman
filters) with 20, 100 and 300 aircraft (--sizes). Prints the cost per base report
(mean, p99) and, after a 15 s warm-up, the quality: missed (aircraft-reports without a
confirmed track within 2 km) and false (confirmed tracks farther than 2 km from every
aircraft), both in % of the aircraft-reports, switches (changes of the track number
holding an aircraft) per 100 aircraft, RMSE / CRLB (position, single-snapshot CRLB of
all bases) and the mean position NEES. Exits 1 when a goal fails at a size up to
--goal-max (100): missed < 1 %, false < 1 %, switches < 1 per 100 aircraft,
RMSE / CRLB <= 1.3, NEES <= 4.5 (1.5 x its dimension 3); larger sizes print cost only.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from common.core.gating import quadratic_form
from common.core.track_table import Status
from common.radar.network.fusion import NetworkFusion, NetworkReport
from tests.radar import network_scene as ns

WARM_UP, NEAR = 15.0, 2000.0


def quality(scene: ns.Scene, reports: list[NetworkReport]) -> dict[str, float]:
    n = scene.p0.shape[0]
    missed = false = switches = scans = 0
    err2 = crlb2 = 0.0
    nees: list[np.ndarray] = []
    holder = np.full(n, -1)
    for rep in reports:
        if rep.t < WARM_UP:
            continue
        scans += 1
        pos, vel = scene.truth(rep.t)
        conf = rep.status != Status.TENTATIVE
        X = rep.x[conf][:, [0, 2, 4]]
        d = np.linalg.norm(X[:, None] - pos[None], axis=2) if X.size else np.full((0, n), np.inf)
        near = d.min(axis=1) if X.size else np.zeros(0)
        false += int((near > NEAR).sum())
        best = d.argmin(axis=0) if X.size else np.zeros(n, dtype=int)
        held = d[best, np.arange(n)] <= NEAR if X.size else np.zeros(n, dtype=bool)
        missed += int((~held).sum())
        ids = np.where(held, rep.id[conf][best], -1)
        switches += int(((holder >= 0) & (ids >= 0) & (ids != holder)).sum())
        holder = np.where(ids >= 0, ids, holder)
        e = X[best[held]] - pos[held]
        err2 += float(np.sum(e ** 2))
        crlb2 += float(np.sum(ns.crlb_position(scene.bases, pos[held], vel[held]) ** 2))
        C = rep.P[conf][best[held]][:, [0, 2, 4]][:, :, [0, 2, 4]]
        nees.append(quadratic_form(e, C))
    return {"missed": missed, "false": false, "switches": switches, "scans": scans,
            "rmse/crlb": float(np.sqrt(err2 / max(crlb2, 1e-300))),
            "nees": float(np.concatenate(nees).mean()) if nees else float("nan")}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=45.0)
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 100, 300])
    ap.add_argument("--goal-max", type=int, default=100)
    a = ap.parse_args()
    ok = True
    print(f"{'aircraft':>8} {'bases':>5} {'reports':>7} {'ms/report':>9} {'p99 ms':>7} "
          f"{'missed %':>8} {'false %':>7} {'sw/100':>6} {'rmse/crlb':>9} {'nees':>6}")
    for n in a.sizes:
        rng = np.random.default_rng(a.seed)
        bases = ns.network(rng)
        p0, v = ns.aircraft(rng, n)
        scene = ns.simulate(rng, bases, p0, v, a.duration)
        fusion = NetworkFusion(bases)
        out: list[NetworkReport] = []
        cost = []
        for b, t, rep in scene.reports:
            t0 = time.perf_counter()
            out += fusion.push(bases[b].id, t, rep)
            cost.append(time.perf_counter() - t0)
        out += fusion.flush()
        q = quality(scene, out)
        c = np.array(cost) * 1e3
        per = 100.0 / (n * q["scans"])
        sw = 100.0 * q["switches"] / n
        print(f"{n:>8} {len(bases):>5} {len(cost):>7} {c.mean():>9.2f} {np.percentile(c, 99):>7.1f} "
              f"{q['missed'] * per:>8.2f} {q['false'] * per:>7.2f} {sw:>6.1f} "
              f"{q['rmse/crlb']:>9.2f} {q['nees']:>6.2f}{'' if n <= a.goal_max else '  (cost only)'}")
        ok &= n > a.goal_max or (q["missed"] * per < 1 and q["false"] * per < 1 and sw < 1
                                 and q["rmse/crlb"] <= 1.3 and q["nees"] <= 4.5)
    print("goals:", "met" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
