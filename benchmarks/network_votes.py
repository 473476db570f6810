"""Can range-only voting tell an aircraft's cell from any other? (docs/networks.md, Goals,
"Why 300 and 1000 aircraft fail"; docs/decisions/019-network-vote-floor.md)

Run: .venv/bin/python benchmarks/network_votes.py [--aircraft 20 100 300 1000] [--cells 20000]

On the goal scenes of benchmarks/network_scene.py (seed 1, positions at t = 0), the votes
[V] of common.radar.network.voting at the finest cell (cell_coarse / 2^5) from the truth
ranges alone (no clutter, every base seeing every aircraft, shell half-width k sigma_r of
the base's channel): at the aircraft, and at random cells of the surveillance volume.
Prints the table; a measurement, no goal (exit 0).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.network_scene import scene_doc  # noqa: E402
from common.core.gating import chi2_gate  # noqa: E402
from common.deploy.config import parse  # noqa: E402
from common.radar.geometry.bistatic import bistatic_range  # noqa: E402
from common.radar.network.params import NetworkParams  # noqa: E402
from common.radar.network.voting import votes  # noqa: E402
from common.sim.scenario import load_scenario  # noqa: E402


def row(n: int, cells: int, rng: np.random.Generator, p: NetworkParams) -> str:
    doc = scene_doc(n, seed=1, duration=10.0)
    cfg, scn = parse(doc), load_scenario(doc)
    assert scn.radar is not None
    pos = np.array([m.pos for m in scn.radar.targets])
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    _, rec = np.unique(np.round(rx, 3), axis=0, return_inverse=True)
    k = np.sqrt(chi2_gate(p.gate_prob, 1))
    shells = [(np.sort(bistatic_range(pos, tx[i], rx[i])), k * scn.radar.channel(b.channels[0]).srb)
              for i, b in enumerate(cfg.bases)]
    sites = np.vstack([tx, rx])
    lo = np.r_[sites[:, :2].min(axis=0) - p.volume_margin, p.z_min]
    hi = np.r_[sites[:, :2].max(axis=0) + p.volume_margin, p.z_max]
    size = p.cell_coarse / 2 ** 5
    at, *_ = votes(pos, size, shells, tx, rx, rec.ravel())
    rand, *_ = votes(lo + rng.random((cells, 3)) * (hi - lo), size, shells, tx, rx, rec.ravel())
    return (f"| {n} | {at.mean():.1f} of {len(cfg.bases)} | {rand.mean():.1f} | {np.mean(rand >= 6):.2f} | "
            f"{np.mean(rand >= 15):.4f} | {np.prod((hi - lo) / size):.2e} of {size:.0f} m |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--aircraft", type=int, nargs="+", default=[20, 100, 300, 1000])
    ap.add_argument("--cells", type=int, default=20000)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    print("| aircraft | votes at an aircraft | random cell: mean votes | P(>= 6) | P(>= 15) | fine cells |")
    print("| --- | --- | --- | --- | --- | --- |")
    for n in a.aircraft:
        print(row(n, a.cells, rng, NetworkParams()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
