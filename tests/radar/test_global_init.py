"""Tests of module 62 (common.radar.fusion.initiation) and the block localisation
(common.radar.geometry.localisation)."""

from __future__ import annotations

import numpy as np
import pytest

from common.core.angles import wrap_pi
from common.radar.fusion.initiation import (
    azimuth_pairs,
    coarse_intersection,
    initial_state,
    pair_velocity,
    select,
)
from common.radar.geometry.bistatic import azimuth, bistatic_range, bistatic_range_rate, ellipsoid_point
from common.radar.geometry.localisation import Constraints, block_localise, gauss_newton

RX = np.array([0.0, 0.0, 0.0])
TX = np.array([[-35000.0, 20000.0, 0.0], [45000.0, 10000.0, 0.0], [5000.0, -52000.0, 0.0]])


def geometry(tx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = tx - RX
    return np.linalg.norm(d, axis=-1), np.arctan2(d[..., 0], d[..., 1])


@pytest.mark.parametrize("target", [[-30000.0, 50000.0, 9000.0], [50000.0, -20000.0, 7000.0],
                                    [12000.0, 30000.0, 2500.0]])
def test_coarse_intersection_matches_brute_force(target: list[float]) -> None:
    pos = np.array(target)
    az = azimuth(pos, RX)
    L, az_tx = geometry(TX[:2])
    rb = np.array([bistatic_range(pos, TX[k], RX) for k in range(2)])
    rel, cos_phi = coarse_intersection(rb[:1], rb[1:], np.array([az]), L[:1], L[1:],
                                       az_tx[:1], az_tx[1:])  # [32]-[35]
    # brute force: walk the elevation along the azimuth, where the two ellipsoids'
    # receiver distances are equal
    el = np.linspace(0.0, np.radians(60.0), 200001)
    p_i = ellipsoid_point(np.full(el.size, rb[0]), np.full(el.size, az), TX[0], RX, el)
    p_j = ellipsoid_point(np.full(el.size, rb[1]), np.full(el.size, az), TX[1], RX, el)
    k = np.argmin(np.abs(np.linalg.norm(p_i, axis=1) - np.linalg.norm(p_j, axis=1)))
    assert np.linalg.norm(rel[0] - p_i[k]) < 5.0
    assert np.linalg.norm(rel[0] - pos) < 1e-6 * np.linalg.norm(pos)
    assert cos_phi[0] == pytest.approx(np.cos(el[k]), abs=1e-5)


def test_coarse_intersection_reports_no_crossing() -> None:
    L, az_tx = geometry(TX[:2])
    pos = np.array([-30000.0, 50000.0, 9000.0])
    rb = [bistatic_range(pos, TX[k], RX) for k in range(2)]
    # azimuth 90 degrees off: the ellipsoids do not meet there above the horizon
    _, cos_phi = coarse_intersection(np.array([rb[0]]), np.array([rb[1] + 20000.0]),
                                     np.array([azimuth(pos, RX) + np.pi / 2]), L[:1], L[1:],
                                     az_tx[:1], az_tx[1:])
    assert not (0.0 <= cos_phi[0] <= 1.0)


def test_azimuth_pairs_equal_brute_force() -> None:
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 2 * np.pi, 300)
    b = np.concatenate([rng.uniform(0, 2 * np.pi, 300), [0.001, 2 * np.pi - 0.001]])
    gate = np.radians(3.0)
    ia, ib = azimuth_pairs(a, b, gate)
    brute = np.argwhere(np.abs(wrap_pi(a[:, None] - b[None, :])) <= gate)
    assert sorted(zip(ia.tolist(), ib.tolist())) == sorted(map(tuple, brute.tolist()))
    assert len(brute) > 5


def _constraints(truth: np.ndarray, n: int, K: int, rng: np.random.Generator,
                 srb: float = 60.0, saz: float = np.radians(0.5)) -> Constraints:
    rb = np.stack([bistatic_range(truth, TX[k], RX) for k in range(K)])
    az = azimuth(truth, RX)
    return Constraints(rb + srb * rng.standard_normal((n, K)), np.full((n, K), srb),
                       az + saz * rng.standard_normal((n, K)), np.full((n, K), saz),
                       np.ones((n, K), bool), TX[:K], np.tile(RX, (K, 1)))


def test_block_covariance_contains_truth_at_expected_rate() -> None:
    """Monte Carlo, 3 bases: NEES of the block mean [41] with the block covariance."""
    rng = np.random.default_rng(7)
    truth = np.array([-30000.0, 50000.0, 9000.0])
    n = 1500
    c = _constraints(truth, n, 3, rng)
    xg, Cg = gauss_newton(np.tile(truth + [400.0, -300.0, 800.0], (n, 1)), c)
    mean, cov, nb = block_localise(xg, Cg, c, k=3.0, levels=3)
    ok = nb > 0
    assert ok.mean() >= 0.98  # empty: the 6 constraints disagree beyond 3 sigma
    e = mean[ok] - truth
    cov = cov[ok]
    nees = np.einsum("ni,ni->n", e, np.linalg.solve(cov, e[..., None])[..., 0])
    inside = np.mean(nees <= 7.815)  # chi-square(3) 95 %
    assert 0.92 <= inside <= 0.975, inside
    assert 2.7 <= nees.mean() <= 3.5, nees.mean()


def test_blocks_report_empty_intersection() -> None:
    rng = np.random.default_rng(1)
    truth = np.array([-30000.0, 50000.0, 9000.0])
    c = _constraints(truth, 2, 3, rng)
    rb = c.rb.copy()
    rb[:, 2] += 5000.0  # third range inconsistent by 80 sigma
    bad = Constraints(rb, c.srb, c.az, c.saz, c.valid, c.tx, c.rx)
    mean, cov, nb = block_localise(np.tile(truth, (2, 1)), np.tile(np.eye(3) * 1e4, (2, 1, 1)), bad)
    assert np.all(nb == 0) and np.isnan(mean).all() and np.isnan(cov).all()


def test_pair_velocity_exact_on_noiseless_data() -> None:
    pos = np.array([[-30000.0, 50000.0, 9000.0], [20000.0, -30000.0, 3000.0]])
    vel = np.array([[200.0, -50.0, 0.0], [-120.0, 160.0, 0.0]])
    tx = np.stack([TX[:2], TX[1:]])
    vb = np.stack([[bistatic_range_rate(pos[i], vel[i], tx[i, k], RX) for k in range(2)]
                   for i in range(2)])
    v, cov = pair_velocity(pos, vb, np.full((2, 2), 1.0), tx, np.zeros((2, 2, 3)))  # [42]
    np.testing.assert_allclose(v, vel[:, :2], atol=1e-8)
    assert np.all(np.linalg.eigvalsh(cov) > 0)  # [46]


def test_pair_velocity_least_squares_over_valid_rows() -> None:
    """K bases with a validity mask: exact on noiseless data with three valid rows, a
    wrong v_b in an invalid row is ignored, and two valid rows give [42] and [46]."""
    pos = np.array([[-30000.0, 50000.0, 9000.0]])
    vel = np.array([200.0, -50.0, 0.0])
    tx = TX[None]
    vb = np.array([[bistatic_range_rate(pos[0], vel, TX[k], RX) for k in range(3)]])
    sig = np.array([[1.0, 2.0, 1.5]])
    v, cov = pair_velocity(pos, vb, sig, tx, np.zeros((1, 3, 3)), np.ones((1, 3), bool))
    np.testing.assert_allclose(v[0], vel[:2], atol=1e-8)
    vb[0, 2] += 500.0
    valid = np.array([[True, True, False]])
    v, cov = pair_velocity(pos, vb, sig, tx, np.zeros((1, 3, 3)), valid)
    v2, cov2 = pair_velocity(pos, vb[:, :2], sig[:, :2], tx[:, :2], np.zeros((1, 2, 3)))
    np.testing.assert_allclose(v, v2, atol=1e-8)
    np.testing.assert_allclose(cov, cov2, rtol=1e-8)


def test_initial_state_layout() -> None:
    pos_cov = np.array([[[4.0, 1.0, 0.5], [1.0, 9.0, 0.2], [0.5, 0.2, 16.0]]])
    v_cov = np.array([[[2.0, 0.3], [0.3, 3.0]]])
    x, P = initial_state(np.array([[1.0, 2.0, 3.0]]), pos_cov, np.array([[10.0, 20.0]]), v_cov, 5.0)
    np.testing.assert_allclose(x[0], [1, 10, 2, 20, 3, 0])  # [44]
    # [45], with the z-(x, y) terms of [41] removed (stated deviation of initial_state)
    np.testing.assert_allclose(P[0][np.ix_([0, 2, 4], [0, 2, 4])],
                               [[4.0, 1.0, 0.0], [1.0, 9.0, 0.0], [0.0, 0.0, 16.0]])
    np.testing.assert_allclose(P[0][np.ix_([1, 3], [1, 3])], v_cov[0])
    assert P[0, 5, 5] == 25.0 and P[0, 0, 1] == 0.0 and P[0, 1, 2] == 0.0


def test_select_equals_sequential_greedy() -> None:
    rng = np.random.default_rng(5)
    for _ in range(50):
        C = int(rng.integers(1, 40))
        members = rng.integers(0, 25, size=(C, 2))
        members[rng.random((C, 2)) < 0.1] = -1
        prio = rng.permutation(C).astype(float)
        used: set[int] = set()
        expect = []
        for c in np.argsort(prio):
            et = {int(e) for e in members[c] if e >= 0}
            if not et & used:
                expect.append(int(c))
                used |= et
        assert sorted(select(members, prio).tolist()) == sorted(expect)
