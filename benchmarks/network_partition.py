"""Benchmark of global fusion partitioned by region (common.radar.network.partition,
docs/networks.md "Partitions") against one fusion centre.

Run: PYTHONPATH=. .venv/bin/python benchmarks/network_partition.py [--seed N] [--duration S]

The synthetic network of tests/radar/network_scene.py with 20 and 100 aircraft (--sizes)
in random directions, fused by one NetworkFusion and by two partitions split at x = 0
with a 3 km margin (in one process, tests/radar/partition_run.py). Prints, after a 15 s
warm-up, missed, false (% of the aircraft-reports), duplicates, switches (per 100
aircraft) of each, the handovers, and the CPU per base report of the single centre and
of each partition (process time), and the busier partition's CPU over the single
centre's. Exits 1 when the partitions score worse than the single centre (missed or false
more than 0.5 % points above, more duplicates or switches), or hand over fewer tracks
than the aircraft that crossed (on one side of x = 0 at 5 s, more than the margin plus
1 km on the other at the end). The CPU is printed, not a goal (docs/networks.md,
"Partitions", Limits).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from common.radar.network.fusion import NetworkFusion, NetworkReport
from common.radar.network.params import NetworkParams
from tests.radar import network_scene as ns
from tests.radar import partition_run

WARM_UP, NEAR = 15.0, 2000.0
PARAMS = NetworkParams(partitions=("west", "east"), partition_splits=(0.0,), partition_margin=3e3)


def quality(scene: ns.Scene, reports: list[NetworkReport], n: int) -> tuple[float, float, int, float]:
    """missed %, false %, duplicates, switches per 100 aircraft."""
    q = ns.score(scene, reports, WARM_UP, NEAR)
    per = 100.0 / (n * max(q.scans, 1))
    return q.missed * per, q.false * per, q.duplicates, 100.0 * q.switches / n


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 100])
    a = ap.parse_args()
    ok = True
    print(f"{'aircraft':>8} {'run':>10} {'missed %':>8} {'false %':>7} {'dup':>4} {'sw/100':>6} "
          f"{'handed':>6} {'crossed':>7} {'ms/report':>9} {'cpu ratio':>9}")
    for n in a.sizes:
        rng = np.random.default_rng(a.seed)
        bases = ns.network(rng)
        p0, v = ns.aircraft(rng, n)
        scene = ns.simulate(rng, bases, p0, v, a.duration)
        single = NetworkFusion(bases)
        c = time.process_time()
        out: list[NetworkReport] = []
        for b, t, rep in scene.reports:
            out += single.push(bases[b].id, t, rep)
        out += single.flush()
        cpu1 = time.process_time() - c
        two, parts, cpu = partition_run.run(scene, PARAMS)
        q1, q2 = quality(scene, out, n), quality(scene, two, n)
        handed = sum(p.counts["handed"] for p in parts.values())
        x5, x1 = scene.truth(5.0)[0][:, 0], scene.truth(a.duration)[0][:, 0]
        crossed = int(np.sum((np.sign(x5) != np.sign(x1))
                             & (np.abs(x1) > PARAMS.partition_margin + 1e3)))
        per = 1e3 / len(scene.reports)
        print(f"{n:>8} {'single':>10} {q1[0]:>8.2f} {q1[1]:>7.2f} {q1[2]:>4} {q1[3]:>6.1f} "
              f"{'':>6} {'':>7} {cpu1 * per:>9.2f}")
        for name in parts:
            print(f"{n:>8} {name:>10} {'':>8} {'':>7} {'':>4} {'':>6} "
                  f"{parts[name].counts['handed']:>6} {'':>7} {cpu[name] * per:>9.2f} "
                  f"{cpu[name] / cpu1:>9.2f}")
        print(f"{n:>8} {'partitions':>10} {q2[0]:>8.2f} {q2[1]:>7.2f} {q2[2]:>4} {q2[3]:>6.1f} "
              f"{handed:>6} {crossed:>7}")
        worse = (q2[0] > q1[0] + 0.5 or q2[1] > q1[1] + 0.5 or q2[2] > q1[2] or q2[3] > q1[3])
        if worse or handed < crossed:
            print(f"FAILED at {n} aircraft: " + ("partitions score worse than one centre"
                                                 if worse else "fewer handovers than crossings"))
            ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
