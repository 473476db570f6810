"""Can range-only voting tell an aircraft's cell from any other, and can the range rates?
(docs/networks.md, Goals, "Why 300 and 1000 aircraft failed"; docs/decisions/
019-network-vote-floor.md, 021-network-doppler-seeding.md)

Run: .venv/bin/python benchmarks/network_votes.py [--aircraft 20 100 300 1000] [--cells 20000]
     [--doppler-cells 3000]

On the goal scenes of benchmarks/network_scene.py (seed 1, positions at t = 0), the votes
[V] of common.radar.network.voting at the finest cell (cell_coarse / 2^5) from the truth
ranges alone (no clutter, every base seeing every aircraft, shell half-width k sigma_r of
the base's channel): at the aircraft, and at random cells of the surveillance volume.
Then the velocity vote [D] of common.radar.network.velocity_vote (the truth range
rates, sigma_v of the channel; velocity grid of the first Doppler level over every
velocity) at cells of 1250, 625 and 312 m containing an aircraft (at a uniform offset)
and at random cells: the score (bases agreeing on one velocity) against the bases that
see the aircraft. Prints the tables; a measurement, no goal (exit 0).
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
from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate  # noqa: E402
from common.radar.network.params import NetworkParams  # noqa: E402
from common.radar.network.velocity_vote import Shells, vote  # noqa: E402
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


def doppler_rows(n: int, cells: int, rng: np.random.Generator, p: NetworkParams) -> list[str]:
    """The velocity vote's rows of one scene (module doc)."""
    doc = scene_doc(n, seed=1, duration=10.0)
    cfg, scn = parse(doc), load_scenario(doc)
    assert scn.radar is not None
    pos = np.array([m.pos for m in scn.radar.targets])
    vel = np.array([m.states(np.zeros(1))[1][0] for m in scn.radar.targets])
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    _, rec = np.unique(np.round(rx, 3), axis=0, return_inverse=True)
    parts = [(np.full(n, i), bistatic_range(pos, tx[i], rx[i]), bistatic_range_rate(pos, vel, tx[i], rx[i]),
              np.full(n, scn.radar.channel(b.channels[0]).srb), np.full(n, scn.radar.channel(b.channels[0]).svb))
             for i, b in enumerate(cfg.bases)]
    sh = Shells(*(np.concatenate(c) for c in zip(*parts)))
    sites = np.vstack([tx, rx])
    lo = np.r_[sites[:, :2].min(axis=0) - p.volume_margin, p.z_min]
    hi = np.r_[sites[:, :2].max(axis=0) + p.volume_margin, p.z_max]
    out = []
    for size in (1250.0, 625.0, 312.5):
        at = pos + rng.uniform(-size / 2, size / 2, pos.shape)
        rand = lo + rng.random((cells, 3)) * (hi - lo)
        score = [vote(c, size, sh, tx, rx, rec.ravel(), np.zeros((c.shape[0], 2)),
                      np.full(c.shape[0], p.doppler_speed), p.doppler_grid, p).score for c in (at, rand)]
        q = np.percentile(score[1], [50, 90, 99])
        out.append(f"| {n} | {size:.0f} | {np.median(score[0]):.0f} of {len(cfg.bases)} | {q[0]:.0f} | "
                   f"{q[1]:.0f} | {q[2]:.0f} |")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--aircraft", type=int, nargs="+", default=[20, 100, 300, 1000])
    ap.add_argument("--cells", type=int, default=20000)
    ap.add_argument("--doppler-cells", type=int, default=3000)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    print("| aircraft | votes at an aircraft | random cell: mean votes | P(>= 6) | P(>= 15) | fine cells |")
    print("| --- | --- | --- | --- | --- | --- |")
    for n in a.aircraft:
        print(row(n, a.cells, rng, NetworkParams()), flush=True)
    print("\n| aircraft | cell (m) | velocity score at an aircraft (median) | random cell: median | 90 % | 99 % |")
    print("| --- | --- | --- | --- | --- | --- |")
    for n in a.aircraft:
        for line in doppler_rows(n, a.doppler_cells, rng, NetworkParams()):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
