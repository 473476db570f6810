"""Tests of the leave-one-out test of the v_b rows of 001 [49] (common.radar.fusion.ekf.
vb_deletion_residuals, common.radar.fusion.track_filter.MixtureFilter.locate): an elementary
track that swapped to a neighbour's target at the base whose v_b alone observes vz is
left out and dissociated (benchmarks/dense_scale.py, dense1000)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from common.core import kalman
from common.core.gating import chi2_gate
from common.radar.fusion.assoc import distance, projections
from common.radar.fusion.ekf import observation, vb_deletion_residuals
from common.radar.fusion.params import FusionParams
from common.radar.fusion.track_filter import MixtureFilter
from common.radar.geometry.bistatic import POS, project

RX = np.array([0.0, 0.0, 30.0])
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0],
               [5000.0, -52000.0, 400.0], [-22000.0, -18000.0, 250.0]])  # dense1000.toml
B = TX.shape[0]
RXS = np.tile(RX, (B, 1))
X = np.array([45000.0, 2.0, -20000.0, -120.0, 8700.0, 0.0])  # 868 of dense1000, 30 km from b2's Tx
P = np.diag([40.0, 6.0, 40.0, 6.0, 100.0, 3.0]) ** 2
POS_COV = np.diag([30.0, 30.0, 150.0]) ** 2
VB_VAR = 1.5**2


def test_residual_is_the_explicit_leave_one_out_innovation() -> None:
    """r_j^2 = innovation of row j against the update with every other row of [49], over
    its variance H_j P' H_j' + R_j."""
    rng = np.random.default_rng(1)
    pos = X[POS] + rng.normal(0.0, 50.0, 3)
    vb = observation(X[None], TX, RXS)[0][0, 3:] + rng.normal(0.0, 2.0, B)
    active = np.array([True, True, False, True])
    r2 = vb_deletion_residuals(X[None], P[None], pos[None], POS_COV[None], vb[None],
                               np.full((1, B), VB_VAR), active[None], TX, RXS)[0]
    h, H = observation(X[None], TX, RXS)
    for j in np.flatnonzero(active):
        keep = np.r_[[0, 1, 2], 3 + np.flatnonzero(active & (np.arange(B) != j))]
        R = np.zeros((keep.size, keep.size))
        R[:3, :3] = POS_COV
        R[3:, 3:] = np.eye(keep.size - 3) * VB_VAR
        z = np.r_[pos, vb][keep]
        x1, P1, _, _ = kalman.update(X[None], P[None], (z - h[0, keep])[None], H[:, keep], R[None])
        nu = vb[j] - h[0, 3 + j] - H[0, 3 + j] @ (x1[0] - X)
        np.testing.assert_allclose(r2[j], nu**2 / (H[0, 3 + j] @ P1[0] @ H[0, 3 + j] + VB_VAR),
                                   rtol=1e-6)
    assert r2[2] == 0.0


def test_residual_is_chi2_1_when_every_row_is_the_target() -> None:
    """Monte Carlo: state, position fix and v_b drawn from the model; mean of r_j^2 = 1."""
    rng = np.random.default_rng(2)
    n = 4000
    xt = X + rng.multivariate_normal(np.zeros(6), P, n)
    pos = xt[:, POS] + rng.multivariate_normal(np.zeros(3), POS_COV, n)
    vb = observation(xt, TX, RXS)[0][:, 3:] + rng.normal(0.0, np.sqrt(VB_VAR), (n, B))
    r2 = vb_deletion_residuals(np.tile(X, (n, 1)), np.tile(P, (n, 1, 1)), pos,
                               np.tile(POS_COV, (n, 1, 1)), vb, np.full((n, B), VB_VAR),
                               np.ones((n, B), bool), TX, RXS)
    np.testing.assert_allclose(r2.mean(axis=0), 1.0, atol=0.08)


def test_swapped_elementary_track_is_left_out_by_module_64() -> None:
    """A track with four contributors whose base b2 reports a neighbour's v_b (15 m/s off,
    the swap of 868 / 444 in dense1000): b2 is dropped; without the offset nothing is.
    The gate [48] of each elementary track alone lets such a swap through."""
    p = FusionParams()
    f = MixtureFilter(p, TX, RXS)
    K = f.A * f.M
    xl, Pl, cl = np.tile(X, (1, K, 1)), np.tile(P, (1, K, 1, 1)), np.zeros((1, K))
    cl[0, 0] = 1.0
    y = project(np.tile(X, (B, 1)), TX, RXS)
    Rz = np.tile(np.diag([100.0**2, VB_VAR, np.radians(1.0) ** 2]), (B, 1, 1))
    r, active = np.arange(B)[None], np.ones((1, B), bool)
    for offset, dropped in ((0.0, [False] * 4), (15.0, [False, True, False, False])):
        z = y.copy()
        z[1, 1] += offset
        E = SimpleNamespace(z=z, Rz=Rz)
        fix = f.locate(xl, Pl, cl, np.ones(1, bool), r, active, E)
        assert fix.dropped[0].tolist() == dropped
        assert fix.located[0]
        y_pred, GPG = projections(X[None], P[None], TX[1:2], RX[None])
        assert distance(y_pred, GPG, z[1:2], Rz[1:2])[0] <= chi2_gate(p.gate_prob, 3)  # [48]
