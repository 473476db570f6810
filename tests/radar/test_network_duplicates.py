"""Two global tracks of one aircraft (common.radar.network.duplicates): found and
merged; two aircraft near each other are never merged."""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status
from common.radar.geometry.bistatic import POS, project
from common.radar.network.duplicates import candidate_pairs, merged
from common.radar.network.initiation import Leftovers, Sites
from common.radar.network.params import NetworkParams
from tests.radar import network_scene as ns

P = NetworkParams()


def _sites(bases: list[ns.Base]) -> Sites:
    rx = np.array([b.rx for b in bases])
    _, rec = np.unique(np.round(rx, 3), axis=0, return_inverse=True)
    return Sites(np.array([b.tx for b in bases]), rx, rec.ravel())


def _reports(bases: list[ns.Base], states: np.ndarray, rng: np.random.Generator) -> Leftovers:
    """Aircraft k's measurement on every base, elementary id k (noisy, with its R)."""
    base, eid, z, R = [], [], [], []
    for b, s in enumerate(bases):
        h = project(states, s.tx, s.rx)[:, :2]
        cov = np.diag([s.sigma_r ** 2, s.sigma_v ** 2])
        for k in range(states.shape[0]):
            base.append(b)
            eid.append(k)
            z.append(h[k] + rng.normal(0.0, [s.sigma_r, s.sigma_v]))
            R.append(cov)
    return Leftovers(np.array(base), np.array(eid), np.array(z), np.array(R))


def _scene(seed: int) -> tuple[list[ns.Base], Sites, np.random.Generator]:
    rng = np.random.default_rng(seed)
    bases = ns.network(rng)
    return bases, _sites(bases), rng


def test_one_aircraft_split_over_two_tracks_is_merged_at_its_position() -> None:
    for seed in range(1, 6):
        bases, sites, rng = _scene(seed)
        truth = np.array([[20e3, 150.0, -10e3, 80.0, 6e3, 0.0]])
        left = _reports(bases, truth, rng)
        B = len(bases)
        members = [{b: 0 for b in range(0, B, 2)}, {b: 0 for b in range(1, B, 2)}]
        x = np.vstack([truth, truth + [3e3, 0, -2e3, 0, 9e3, 0]])
        pairs = candidate_pairs(x, np.full(2, Status.CONFIRMED), members, P.merge_distance)
        assert pairs.tolist() == [[0, 1]]
        fix, ok = merged(pairs, x, members, left, sites, P)
        assert ok.tolist() == [True]
        assert np.linalg.norm(fix.x[0, POS] - truth[0, POS]) < 200.0


def test_two_aircraft_are_never_merged() -> None:
    """Near in the plane at altitudes 3 km apart: each track holds its own elementary
    track of the common bases (no pair); the bases split between the two tracks with
    each aircraft's own measurements: the union is refused by the acceptance tests."""
    for seed in range(1, 6):
        bases, sites, rng = _scene(seed)
        truth = np.array([[20e3, 150.0, -10e3, 80.0, 6e3, 0.0],
                          [21e3, -120.0, -9e3, 60.0, 9e3, 0.0]])
        left = _reports(bases, truth, rng)
        B = len(bases)
        both = [{b: 0 for b in range(B)}, {b: 1 for b in range(B)}]
        status = np.full(2, Status.CONFIRMED)
        assert candidate_pairs(truth, status, both, P.merge_distance).shape == (0, 2)
        split = [{b: 0 for b in range(0, B, 2)}, {b: 1 for b in range(1, B, 2)}]
        pairs = candidate_pairs(truth, status, split, P.merge_distance)
        assert pairs.tolist() == [[0, 1]]
        _, ok = merged(pairs, truth, split, left, sites, P)
        assert ok.tolist() == [False]


def test_far_apart_or_tentative_tracks_are_not_tested() -> None:
    x = np.zeros((3, 6))
    x[1, 0] = P.merge_distance + 1.0
    members = [{0: 1}, {1: 1}, {2: 1}]
    status = np.array([Status.CONFIRMED, Status.CONFIRMED, Status.TENTATIVE])
    assert candidate_pairs(x, status, members, P.merge_distance).shape == (0, 2)
