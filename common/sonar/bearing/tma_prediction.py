"""Bearing and bearing rate predicted from a contact's TMA solution (issue 31, contacts that
pass close; docs/equations.md "TMA-predicted bearing"; docs/decisions/026-tma-predicted-bearing.md).

Choice (stated; 000 predicts with its straight-line-segment model only): near a closest
approach the bearing of a straight relative track, theta(t) = atan2(d_x, d_y) with
d(t) = p + v (t - t_h) - o(t), moves tens of degrees per sample while 000's model
extrapolates its last rate. A track given its contact's converged TMA solution (p, v, P of
002 at t_h) predicts [theta, theta'] at t from it,

  theta = atan2(d_x, d_y),  theta' = (d_y w_x - d_x w_y) / r^2,  w = v - u (u: own velocity),
  C = J P J' + Q_theta(T),  J = d[theta, theta'] / d[p, v],

Q_theta the bearing block of 000's Q over the cycle. When the range is observable the
mean and C come from the unscented transform of (p, v; P) instead (the spread is far from
linear near the approach). theta and theta' are invariant along d -> k d, w -> k w, the
direction bearings alone leave open before an own-ship manoeuvre, so J P J' stays finite
when the range is not observable.

When (the switch): only when the solution's own bearing change over the cycle departs from
a constant rate by more than the track's bearing sigma, |theta_1 - theta_0 - T theta'_0| >
sigma_theta; elsewhere 000's model predicts as before (far from the approach the two agree).

Guards (a stale or wrong solution cannot capture a track): a solution is used for
``max_age`` seconds after its time (RangeNoise) and only by the track number it was solved
for (a deleted number drops it); it must be converged (002's stop rule); its predicted
bearing sigma must be at most MAX_SIGMA; its [theta, theta'] at the previous cycle must
agree with the track's estimate there (chi-square 99.7 %, 2 dof) and its bearing at t with
the model's prediction (1 dof, both covariances): a solution on another contact, or one
that drifted, fails these and the model predicts. It replaces the bearing block of the
prediction only, and a detection must still pass the 000 gate with that covariance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import quadratic_form

GATES = (9.0, 11.8)  # chi-square 99.7 %, 1 and 2 degrees of freedom
MAX_SIGMA = float(np.pi / 4.0)  # rad: a wider bearing prediction is no prediction


@dataclass(frozen=True)
class TmaHint:
    """A contact's TMA solution as the tracker uses it: time, position, velocity (ENU m, m/s),
    whether its range is usable (converged and range observable), its covariance P (4, 4)
    of [x, y, vx, vy] and whether the solve converged (002's stop rule)."""

    t: float
    x: float
    y: float
    vx: float
    vy: float
    usable: bool = True
    P: np.ndarray | None = None
    converged: bool = False


def bearing_and_rate(p: np.ndarray, v: np.ndarray, t_h: float, t: float,
                     own: np.ndarray, own_v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[theta, theta'] at t of the solution (p, v at t_h) seen from own (velocity own_v),
    and J (2, 4) = d[theta, theta'] / d[p, v] (module docstring)."""
    tau = t - t_h
    d = p + v * tau - own
    w = v - own_v
    r2 = max(float(d @ d), 1e-6)
    theta = float(np.arctan2(d[0], d[1]))
    rate = float(d[1] * w[0] - d[0] * w[1]) / r2
    g_th = np.array([d[1], -d[0]]) / r2  # d theta / d d
    g_rd = np.array([-w[1] - 2.0 * d[0] * rate, w[0] - 2.0 * d[1] * rate]) / r2  # d theta' / d d
    g_rw = np.array([d[1], -d[0]]) / r2  # d theta' / d w
    J = np.array([np.r_[g_th, tau * g_th], np.r_[g_rd, tau * g_rd + g_rw]])
    return np.array([theta, rate]), J


def unscented(p: np.ndarray, v: np.ndarray, P: np.ndarray, t_h: float, t: float, own: np.ndarray,
              own_v: np.ndarray, kappa: float = 1.0) -> tuple[np.ndarray, np.ndarray] | None:
    """[theta, theta'] at t and its covariance by the unscented transform of (p, v; P) (the
    2n + 1 points of sqrt((n + kappa) P)); None when P is not positive definite."""
    n = 4
    try:
        L = np.linalg.cholesky((n + kappa) * P)
    except np.linalg.LinAlgError:
        return None
    s0 = np.r_[p, v]
    pts = [s0] + [s0 + L[:, i] for i in range(n)] + [s0 - L[:, i] for i in range(n)]
    m = np.array([bearing_and_rate(q[:2], q[2:], t_h, t, own, own_v)[0] for q in pts])
    m[:, 0] = m[0, 0] + wrap_pi(m[:, 0] - m[0, 0])
    w = np.full(2 * n + 1, 0.5 / (n + kappa))
    w[0] = kappa / (n + kappa)
    mean = w @ m
    e = m - mean
    return mean, (w[:, None] * e).T @ e


def curvature(m0: np.ndarray, m1: np.ndarray, T: float) -> float:
    """The bearing change over T that a constant rate misses, theta_1 - theta_0 - T theta'_0."""
    return float(wrap_pi(np.asarray(m1[0] - m0[0] - T * m0[1])))


def predict(h: TmaHint, t0: float, o0: np.ndarray, t: float, o1: np.ndarray, x0: np.ndarray,
            P0: np.ndarray, x1: np.ndarray, P1: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """[theta, theta'] at t and its covariance (without Q) from the hint h, for a track whose
    [theta, theta'] was x0 (P0) at t0 and is predicted x1 (P1) at t by 000's model; own ship
    at o0, o1 (straight between them); None where the module's switch or a guard says no."""
    if not h.converged or h.P is None:
        return None
    p, v, P = np.array([h.x, h.y]), np.array([h.vx, h.vy]), np.asarray(h.P, float).reshape(4, 4)
    u = (o1 - o0) / (t - t0)
    m0, J0 = bearing_and_rate(p, v, h.t, t0, o0, u)
    m1, J1 = bearing_and_rate(p, v, h.t, t, o1, u)
    if abs(curvature(m0, m1, t - t0)) <= np.sqrt(P0[0, 0]):
        return None  # the model's constant rate is within its sigma: it predicts
    c0, c1 = J0 @ P @ J0.T, J1 @ P @ J1.T
    ut = unscented(p, v, P, h.t, t, o1, u) if h.usable else None
    if ut is not None:
        m1, c1 = ut
    if not (usable_covariance(c0) and usable_covariance(c1)):
        return None
    if not consistent(m0, c0, x0, P0) or not consistent(m1[:1], c1[:1, :1], x1[:1], P1[:1, :1]):
        return None
    return m1, c1


def usable_covariance(C: np.ndarray) -> bool:
    """C (2, 2) finite, positive definite, and its bearing sigma at most MAX_SIGMA: a
    published P that is near singular (an unobservable range) can lose J P J' to rounding."""
    if not np.all(np.isfinite(C)) or C[0, 0] > MAX_SIGMA**2:
        return False
    return bool(np.all(np.linalg.eigvalsh(0.5 * (C + C.T)) > 0.0))


def consistent(m: np.ndarray, C: np.ndarray, x: np.ndarray, P: np.ndarray) -> bool:
    """The solution's [theta(, theta')] m (cov C) agrees with the track's x (cov P):
    d^2 = y' (C + P)^-1 y <= the 99.7 % chi-square quantile of its dimension."""
    y = np.array(m - x, dtype=float)
    y[0] = wrap_pi(y[0])
    return bool(quadratic_form(y, C + P) <= GATES[y.size - 1])


def with_bearing(x: np.ndarray, P: np.ndarray, k: np.ndarray, m2: np.ndarray, C2: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """x (N, n), P with rows k's bearing block [theta, theta'] set to m2 (K, 2), C2 (K, 2, 2),
    uncorrelated with the rest of the state."""
    if k.size == 0:
        return x, P
    x, P = x.copy(), P.copy()
    x[k, :2] = m2
    x[k, 0] = wrap_2pi(m2[:, 0])
    P[k, :2, 2:] = 0.0
    P[k, 2:, :2] = 0.0
    P[k, :2, :2] = C2
    return x, P
