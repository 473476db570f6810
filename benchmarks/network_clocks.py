"""Unsynchronised nodes: what a reference clock buys (docs/networks.md, Limits).

Run: .venv/bin/python benchmarks/network_clocks.py [--seeds 1 2 3] [--clock 0.2]

The synthetic network of tests/radar/network_scene.py (20 aircraft, 45 s), every base's
clock off by U(-clock, clock) s except two bases whose clock is exact; the network
fusion centre run without, then with those two declared as `clock_reference`
([radar.network]). Prints per seed the mean position NEES (common.radar.network via
network_scene.score), missed and false, and the error of the offset estimates: its mean
over the bases (the common part, which ranges cannot observe) and its largest. A
measurement, no goal (exit 0).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from common.radar.network.fusion import NetworkFusion  # noqa: E402
from common.radar.network.params import NetworkParams  # noqa: E402
from tests.radar import network_scene as ns  # noqa: E402

REFERENCE = (0, 1)  # bases with exact clocks


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--clock", type=float, default=0.2)
    a = ap.parse_args(argv)
    print("| seed | references | NEES | missed | false | common offset error s | largest s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for seed in a.seeds:
        rng = np.random.default_rng(seed)
        bases = ns.network(rng)
        off = np.random.default_rng(seed + 1000).uniform(-a.clock, a.clock, len(bases))
        off[list(REFERENCE)] = 0.0
        bases = [dataclasses.replace(b, clock=float(c)) for b, c in zip(bases, off)]
        p0, v = ns.aircraft(rng, 20)
        scene = ns.simulate(rng, bases, p0, v, 45.0)
        for refs in ((), tuple(bases[i].id for i in REFERENCE)):
            fusion = NetworkFusion(bases, NetworkParams(clock_reference=refs))
            out = []
            for b, t, rep in scene.reports:
                out += fusion.push(bases[b].id, t, rep)
            s = ns.score(scene, out + fusion.flush())
            err = fusion.clocks.c - off
            print(f"| {seed} | {len(refs)} | {s.nees:.2f} | {s.missed} | {s.false} | {err.mean():+.3f} | "
                  f"{np.abs(err).max():.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
