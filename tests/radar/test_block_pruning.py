"""Pruning of module 62's blocks (common.radar.geometry.localisation.block_localise): the Taylor
bounds of `_keep` prune no block whose reach (the box of its leaf centres) holds a point
within k sigma of every measurement (exhaustive grid of points in random blocks), and
the blocks kept at the last level, hence the zones [36]-[41], are those of 001's bounds
alone (random geometries)."""

from __future__ import annotations

import numpy as np
import pytest

from common.radar.geometry import localisation
from common.radar.geometry.localisation import Constraints, block_localise, residuals

K_SIGMA = 3.0


def _geometry(rng: np.random.Generator, n: int) -> tuple[np.ndarray, Constraints]:
    """n targets (N, 3): far, near the receiver (small rho) and low (near z_min), seen by
    3 bases of random transmitters around one receiver; noisy ranges and azimuths."""
    rx = np.tile([rng.uniform(-1e3, 1e3), rng.uniform(-1e3, 1e3), 30.0], (n, 3, 1))
    tx = rx + np.concatenate([rng.uniform(-6e4, 6e4, (n, 3, 2)),
                              rng.uniform(0.0, 800.0, (n, 3, 1))], axis=2)
    r = np.exp(rng.uniform(np.log(300.0), np.log(8e4), n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    truth = rx[:, 0] + np.stack([r * np.sin(a), r * np.cos(a), rng.uniform(-30.0, 1.2e4, n)], 1)
    srb = rng.uniform(20.0, 300.0, (n, 3))
    saz = np.radians(rng.uniform(0.2, 3.0, (n, 3)))
    valid = rng.random((n, 3)) < 0.85
    valid[:, :2] = True
    c = Constraints(np.zeros((n, 3)), srb, np.zeros((n, 3)), saz, valid, tx, rx)
    rb, az, _ = residuals(truth, c)  # -(true ranges), -(true azimuths)
    c = Constraints(srb * rng.standard_normal((n, 3)) - rb, srb,
                    (saz * rng.standard_normal((n, 3)) - az) % (2 * np.pi), saz, valid, tx, rx)
    return truth, c


def _cov(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random covariances (N, 3, 3), sigmas 30 m to 5 km along random axes."""
    Q, _ = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    s = np.exp(rng.uniform(np.log(30.0), np.log(5e3), (n, 3)))
    return (Q * s[:, None, :] ** 2) @ np.swapaxes(Q, 1, 2)


def _keep_001(pos: np.ndarray, c: Constraints, k: float, z_min: float, z_max: float,
              h: np.ndarray | None = None, V: np.ndarray | None = None,
              reach: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The test of 001's bounds alone (|grad r_b| <= 2, |grad theta| <= 1 / rho) on the
    whole block, with `_keep`'s signature (blocks (M, J, 3) of the M rows of c)."""
    M, J, _ = pos.shape
    rows = np.repeat(np.arange(M), J)
    res_rb, res_az, rho = residuals(pos.reshape(-1, 3), c.take(rows))
    diag = np.zeros(M * J) if h is None else np.linalg.norm(h, axis=1)[rows]
    d = diag[:, None]
    ok_rb = np.abs(res_rb) <= k * c.srb[rows] + 2.0 * d
    ok_az = np.abs(res_az) <= k * c.saz[rows] + d / np.maximum(rho, 1.0)
    z = pos.reshape(-1, 3)[:, 2]
    ok_z = (z >= z_min - diag) & (z <= z_max + diag)
    ok = np.all((ok_rb & ok_az) | ~c.valid[rows], axis=1) & ok_z
    return ok.reshape(M, J), np.abs(res_rb).reshape(M, J, -1), np.abs(res_az).reshape(M, J, -1)


@pytest.mark.parametrize("seed", range(4))
def test_pruned_blocks_hold_no_passing_point(seed: int) -> None:
    """Blocks that 001's bounds keep and `_keep` prunes, against an exhaustive grid of
    9^3 points in the box of each block's reach (corners included): none of the points
    passes the centre test.
    (001's azimuth bound d / rho, rho at the centre, is itself not a bound near the
    receiver: seed 0 has one such block; it is pruned with or without the Taylor bounds.)"""
    rng = np.random.default_rng(seed)
    n = 3000
    truth, c = _geometry(rng, n)
    V, _ = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    h = np.exp(rng.uniform(np.log(5.0), np.log(4e3), (n, 3)))
    reach = h * rng.uniform(0.3, 1.0, (n, 1))
    centre = truth + rng.standard_normal((n, 3)) * 3.0 * h
    kept = localisation._keep(centre[:, None], c, K_SIGMA, 0.0, 2e4, h, V, reach)[0][:, 0]
    grid = np.stack(np.meshgrid(*[np.linspace(-1.0, 1.0, 9)] * 3, indexing="ij"), -1).reshape(-1, 3)
    pruned = np.flatnonzero(_keep_001(centre[:, None], c, K_SIGMA, 0.0, 2e4, h, V)[0][:, 0] & ~kept)
    pts = centre[pruned, None, :] + (grid[None] * reach[pruned, None, :]) @ np.swapaxes(V[pruned], 1, 2)
    passing = localisation._keep(pts, c.take(pruned), K_SIGMA, 0.0, 2e4)[0]
    assert pruned.size > n // 10 and kept.sum() > n // 20  # both cases are exercised
    assert not passing.any()


@pytest.mark.parametrize("seed, levels", [(0, 3), (1, 4), (2, 4)])
def test_same_blocks_as_001_bounds(seed: int, levels: int, monkeypatch: pytest.MonkeyPatch
                                   ) -> None:
    """block_localise with the Taylor bounds gives exactly the zones (mean, covariance,
    number of blocks) of the descent with 001's bounds alone, on random geometries."""
    rng = np.random.default_rng(10 + seed)
    n = 400
    truth, c = _geometry(rng, n)
    C0 = _cov(rng, n)
    x0 = truth + (np.linalg.cholesky(C0) @ rng.standard_normal((n, 3, 1)))[..., 0]
    prior = (3000.0, 4000.0)
    new = block_localise(x0, C0, c, K_SIGMA, levels, z_prior=prior)
    monkeypatch.setattr(localisation, "_keep", _keep_001)
    ref = block_localise(x0, C0, c, K_SIGMA, levels, z_prior=prior)
    assert (ref[2] > 0).sum() > n // 4 and (ref[2] == 0).sum() > n // 20
    for a, b in zip(new, ref):
        np.testing.assert_array_equal(a, b)
