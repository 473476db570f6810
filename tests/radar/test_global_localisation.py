"""Module 64 during tracking (common.radar.geometry.localisation.linearised_position): the scan's
position measurement is honest (NEES against truth) and, once the position is known,
its information is the Jacobian's."""

from __future__ import annotations

import numpy as np
import pytest

from common.evaluation.pcrlb import mean_nees_interval
from common.radar.geometry.localisation import Constraints, linearised_position, residuals

TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0], [5000.0, -52000.0, 400.0]])
RX = np.array([[0.0, 0.0, 30.0]] * 3)  # crossing.toml
SRB, SAZ = 100.0, np.radians(1.0)


def _scan(truth: np.ndarray, rng: np.random.Generator) -> Constraints:
    """Noisy ranges [36] and azimuths of the three bases for positions truth (N, 3)."""
    n = truth.shape[0]
    c = Constraints(np.zeros((n, 3)), np.full((n, 3), SRB), np.zeros((n, 3)),
                    np.full((n, 3), SAZ), np.ones((n, 3), bool), TX, RX)
    rb, az, _ = residuals(truth, c)  # -(true ranges), -(true azimuths)
    return Constraints(SRB * rng.standard_normal((n, 3)) - rb,
                       c.srb, (SAZ * rng.standard_normal((n, 3)) - az) % (2 * np.pi),
                       c.saz, c.valid, TX, RX)


@pytest.mark.parametrize("truth, sig, slack", [
    ([5000.0, 40000.0, 8000.0], [200.0, 200.0, 1000.0], 1.0),  # high target
    ([20000.0, 36000.0, 1500.0], [100.0, 100.0, 1000.0], 1.05),  # low, z barely observed
])
def test_scan_measurement_nees(truth: list[float], sig: list[float], slack: float) -> None:
    """Predictions drawn around the truth with their covariance: the scan measurement
    (z, R) has mean NEES in the 99 % interval of chi-square(3), and so has the
    posterior, up to `slack` on the upper bound for the low target (a Gaussian cannot
    follow the curved likelihood of its altitude: measured 3.21, 7 % over 3)."""
    rng = np.random.default_rng(3)
    n = 1000
    tr = np.tile(truth, (n, 1))
    Pp = np.diag(np.square(sig))
    xp = tr + rng.standard_normal((n, 3)) * sig
    z, R, chi2, post, _ = linearised_position(xp, np.tile(Pp, (n, 1, 1)), _scan(tr, rng))
    lo, hi = mean_nees_interval(3, n, 0.99)
    e = z - tr
    assert lo <= np.mean(np.einsum("ni,ni->n", e, np.linalg.solve(R, e[..., None])[..., 0])) <= hi
    S = np.linalg.inv(np.linalg.inv(R) + np.linalg.inv(Pp))
    e = post - tr
    assert lo <= np.mean(np.einsum("ni,ni->n", e, np.linalg.solve(S, e[..., None])[..., 0])) <= hi * slack
    lo6, hi6 = mean_nees_interval(6, n, 0.99)
    assert lo6 <= np.mean(chi2) <= hi6  # 2 x 3 constraints


def test_information_tends_to_jacobian() -> None:
    """With a prediction known to 1 m, R^-1 equals J' W J of the ranges and azimuths
    (J by central differences) at the posterior."""
    x = np.array([[20000.0, 36000.0, 1500.0]])
    c = _scan(x, np.random.default_rng(1))
    _, R, _, post, _ = linearised_position(x, np.eye(3)[None], c)
    J = np.zeros((6, 3))
    for i in range(3):
        d = np.zeros((1, 3))
        d[0, i] = 0.5
        rp, ap, _ = residuals(post + d, c)
        rm, am, _ = residuals(post - d, c)
        J[:, i] = -np.concatenate([rp - rm, ap - am], axis=1)[0]
    W = np.diag(np.concatenate([np.full(3, SRB**-2), np.full(3, SAZ**-2)]))
    np.testing.assert_allclose(np.linalg.inv(R[0]), J.T @ W @ J, rtol=1e-3, atol=1e-12)


def test_singular_prediction_does_not_raise() -> None:
    """A prediction with an exactly singular covariance (a degenerate track) gives a
    finite answer instead of stopping the cycle."""
    c = _scan(np.array([[20000.0, 40000.0, 5000.0]]), np.random.default_rng(0))
    P = np.diag([1e4, 1e4, 0.0])[None]
    z, _, _, post, _ = linearised_position(np.array([[20000.0, 40000.0, 5000.0]]), P, c)
    assert np.isfinite(z).all() and np.isfinite(post).all()
