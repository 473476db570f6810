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

from common.radar.network.fusion import NetworkFusion, NetworkReport
from tests.radar import network_scene as ns

WARM_UP, NEAR = 15.0, 2000.0


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
        q = ns.score(scene, out, WARM_UP, NEAR)
        c = np.array(cost) * 1e3
        per = 100.0 / (n * q.scans)
        sw = 100.0 * q.switches / n
        ratio = q.rmse_over_crlb()
        print(f"{n:>8} {len(bases):>5} {len(cost):>7} {c.mean():>9.2f} {np.percentile(c, 99):>7.1f} "
              f"{q.missed * per:>8.2f} {q.false * per:>7.2f} {sw:>6.1f} "
              f"{ratio:>9.2f} {q.nees:>6.2f}{'' if n <= a.goal_max else '  (cost only)'}")
        ok &= n > a.goal_max or (q.missed * per < 1 and q.false * per < 1 and sw < 1
                                 and ratio <= 1.3 and q.nees <= 4.5)
    print("goals:", "met" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
