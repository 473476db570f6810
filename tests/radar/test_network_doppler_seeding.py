"""Initiation's velocity (Doppler) vote (common.radar.network.velocity_vote, voting):
the range rates pick an aircraft's members where range alone picks another
aircraft's, and a dense snapshot opens many aircraft in one round.

Snapshots of truth elementary tracks (every base of tests/radar/network_scene.py's
network, [r_b, v_b] of each aircraft it detects, pd 0.9, noise of half the base's
sigmas), no Kalman filtering: initiation alone.
"""

from __future__ import annotations

import numpy as np

from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate
from common.radar.network.initiation import Leftovers, Sites, _nearest_members, initiate
from common.radar.network.params import NetworkParams
from common.radar.network.velocity_vote import Shells, vote
from common.radar.network.voting import vote_cells
from tests.radar import network_scene as ns


def _sites(bases: list[ns.Base]) -> Sites:
    tx, rx = np.array([b.tx for b in bases]), np.array([b.rx for b in bases])
    _, rec = np.unique(np.round(rx, 3), axis=0, return_inverse=True)
    return Sites(tx, rx, rec.ravel())


def _leftovers(rows: list[tuple[int, int, float, float, float, float]]) -> Leftovers:
    """rows: base, aircraft id, r_b, v_b, sigma_r, sigma_v."""
    a = np.array(rows, dtype=float)
    R = np.zeros((len(rows), 2, 2))
    R[:, 0, 0], R[:, 1, 1] = a[:, 4] ** 2, a[:, 5] ** 2
    return Leftovers(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2:4], R)


def _snapshot(n: int, seed: int = 1) -> tuple[Leftovers, Sites, np.ndarray]:
    rng = np.random.default_rng(seed)
    bases = ns.network(rng)
    p0, v = ns.aircraft(rng, n)
    rows = []
    for b, base in enumerate(bases):
        r = bistatic_range(p0, base.tx, base.rx) + rng.normal(0, base.sigma_r / 2, n)
        vb = bistatic_range_rate(p0, v, base.tx, base.rx) + rng.normal(0, base.sigma_v / 2, n)
        rows += [(b, a, r[a], vb[a], base.sigma_r / 2, base.sigma_v / 2)
                 for a in np.flatnonzero(rng.random(n) < 0.9)]
    return _leftovers(rows), _sites(bases), p0


def _shells(left: Leftovers) -> Shells:
    s = np.sqrt(left.R[:, :2, :2].diagonal(axis1=1, axis2=2))
    return Shells(left.base, left.z[:, 0], left.z[:, 1], s[:, 0], s[:, 1])


def test_crossing_shells_doppler_picks_the_aircraft() -> None:
    """Aircraft 0 is 150 m from a fine cell's centre; at every base the shell of another
    aircraft (1 or 2, flying other courses) passes through the centre itself. Range alone
    takes the other aircraft's track at most bases; the velocity vote takes aircraft 0's
    at every base, and initiation opens aircraft 0 with exactly its tracks."""
    bases = ns.network(np.random.default_rng(3))
    sites = _sites(bases)
    p = NetworkParams()
    c = np.array([[5e3, -8e3, 7e3]])
    pa = c + [[90.0, -100.0, 70.0]]
    va = np.array([[180.0, 60.0, 0.0]])
    others = np.array([[-120.0, 170.0, 0.0], [30.0, -210.0, 0.0]])
    rows = []
    for b, base in enumerate(bases):
        rows.append((b, 0, float(bistatic_range(pa, base.tx, base.rx)[0]),
                     float(bistatic_range_rate(pa, va, base.tx, base.rx)[0]), base.sigma_r, base.sigma_v))
        o = b % 2
        rows.append((b, 1 + o, float(bistatic_range(c, base.tx, base.rx)[0]),
                     float(bistatic_range_rate(c, others[o:o + 1], base.tx, base.rx)[0]),
                     base.sigma_r, base.sigma_v))
    left = _leftovers(rows)
    B = len(bases)
    nearest = _nearest_members(c, left, sites, p)[0]
    assert (left.eid[nearest] != 0).sum() >= B // 2  # range alone: another aircraft's
    v = vote(c, p.cell_fine * 1.05, _shells(left), sites.tx, sites.rx, sites.receiver,
             np.zeros((1, 2)), np.full(1, p.doppler_speed), p.doppler_grid, p)
    assert v.score[0] == B
    assert (left.eid[v.members[0]] == 0).all()
    np.testing.assert_allclose(v.velocity[0], va[0, :2], atol=v.step[0])
    opened, _ = initiate(left, sites, 6, p, 1)
    assert opened.members.shape[0] == 1
    assert (left.eid[opened.members[0]] == 0).all() and (opened.members[0] >= 0).all()
    assert np.linalg.norm(opened.fix.x[0, [0, 2, 4]] - pa[0]) < 100.0


def test_dense_snapshot_one_round() -> None:
    """150 aircraft, 21 bases, one round with 8000 cells voted on per level: >= 15
    aircraft opened, each within 2 km of its aircraft with all members of it, none
    twice. (Range votes alone, today's seeding: 4 opened in one round of 20000 cells.)"""
    left, sites, p0 = _snapshot(150)
    p = NetworkParams(doppler_cells=8000)
    opened, _ = initiate(left, sites, 6, p, 1)
    ids = []
    for c in range(opened.members.shape[0]):
        m = opened.members[c][opened.members[c] >= 0]
        a = np.unique(left.eid[m])
        assert a.size == 1, a
        assert np.linalg.norm(opened.fix.x[c, [0, 2, 4]] - p0[a[0]]) < 2000.0
        ids.append(int(a[0]))
    assert len(set(ids)) == len(ids) >= 15, ids


def test_extent_votes_only_the_slab() -> None:
    """A partition's initiation (`extent`: x in [-inf, 0)) votes only cells that reach
    its slab and opens aircraft there; without the slab it opens aircraft on both sides."""
    left, sites, p0 = _snapshot(40, seed=2)
    p = NetworkParams(doppler_cells=4000)
    sigma = np.sqrt(left.R[:, :2, :2].diagonal(axis1=1, axis2=2))
    pts, _, _ = vote_cells(left.base, left.z[:, 0], sigma[:, 0], sites.tx, sites.rx,
                           sites.receiver, 6, p, 1, _shells(left), (0, -np.inf, 0.0))
    assert pts.shape[0] > 0 and (pts[:, 0] < p.cell_coarse).all()
    whole, _ = initiate(left, sites, 6, p, 1)
    slab, _ = initiate(left, sites, 6, p, 1, (0, -np.inf, 0.0))
    assert (whole.fix.x[:, 0] > 0).any() and (whole.fix.x[:, 0] < 0).any()
    assert slab.fix.x.shape[0] > 0 and (slab.fix.x[:, 0] < p.cell_coarse).all()
