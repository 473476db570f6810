"""Bearing and bearing rate predicted with a contact's TMA solution (issue 31, contacts that
pass close; docs/equations.md "TMA-predicted bearing"; docs/decisions/026-tma-predicted-bearing.md,
028-own-state-along-the-relative-track.md).

Choice (stated; 000 predicts with its straight-line-segment model only): near a closest
approach the bearing of a straight relative track moves tens of degrees per sample while
000's model extrapolates its last rate, and its rate estimate lags a rate that grows cycle
after cycle. Along a straight relative track the bearing theta, its rate omega and the
relative range rate s = r' / r obey a closed system (the scale-invariant part of modified
polar coordinates), exact over T while the own ship holds its course:

  theta(t0 + T) = theta_0 + atan2(omega_0 T, 1 + s T),
  omega(t0 + T) = omega_0 / D,  D = (1 + s T)^2 + (omega_0 T)^2,

the relative position being r_0 [1 + s T, omega_0 T] in the line-of-sight frame of t0.

1. A solution whose range is observable (002's solve converged, issue 31's range rule):
   every cycle the track propagates its own [theta, omega] (x0, P0) by that system with
   s = (d . w) / |d|^2 of the solution at t0 (d = p + v (t0 - t_h) - o(t0), w = v - u, u
   the own velocity), mean at (x0, s), covariance F P0 F' + G G' J_s P J_s' (F, G the
   Jacobians in x0 and s) plus the bearing block of 000's Q. Far from the approach it is
   000's constant rate; near it the rate grows as the geometry says.
2. Otherwise (026): only when the solution's own bearing change over the cycle departs
   from a constant rate by more than the track's bearing sigma (near the approach), the
   solution's own [theta, omega] at t, theta = atan2(d_x, d_y), omega = (d_y w_x - d_x w_y)
   / |d|^2, covariance J P J' + Q, if its bearing at t agrees with 000's prediction (1 dof,
   both covariances). theta and omega are invariant along d -> k d, w -> k w, the direction
   bearings alone leave open, so J P J' stays finite when the range is not observable.

Guards (a stale or wrong solution cannot capture a track): a solution is used for
``max_age`` seconds after its time (RangeNoise) and only by the track it was solved for (a
reopened number drops it); it must be converged (002's stop rule); its [theta, omega] at
t0 must agree with the track's estimate there (chi-square 99.7 %, 2 dof), so a solution of
another contact fails; the predicted bearing sigma must be at most MAX_SIGMA. In case 1
the solution gives the curvature only, never the track's bearing or rate, and a detection
must still pass the 000 gate with the predicted covariance.
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


def rate_ratio(p: np.ndarray, v: np.ndarray, t_h: float, t0: float, own: np.ndarray,
               own_v: np.ndarray) -> tuple[float, np.ndarray]:
    """s = r' / r = (d . w) / |d|^2 at t0 of the solution (p, v at t_h) seen from own
    (velocity own_v), and J_s (4,) = d s / d[p, v]."""
    tau = t0 - t_h
    d = p + v * tau - own
    w = v - own_v
    r2 = max(float(d @ d), 1e-6)
    s = float(d @ w) / r2
    g_d = (w - 2.0 * s * d) / r2
    return s, np.r_[g_d, tau * g_d + d / r2]


def propagate(x0: np.ndarray, s: float, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[theta, omega] after T along a straight relative track from x0 = [theta_0, omega_0]
    and s (module docstring), its Jacobian F (2, 2) in x0 and G (2,) in s."""
    a, b = 1.0 + s * T, x0[1] * T
    D = a * a + b * b
    m = np.array([x0[0] + np.arctan2(b, a), x0[1] / D])
    F = np.array([[1.0, a * T / D], [0.0, (a * a - b * b) / D**2]])
    G = np.array([-b * T / D, -2.0 * x0[1] * a * T / D**2])
    return m, F, G


def predict(h: TmaHint, t0: float, o0: np.ndarray, t: float, o1: np.ndarray, x0: np.ndarray,
            P0: np.ndarray, x1: np.ndarray, P1: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """[theta, omega] at t, its covariance (with 000's Q) and the linearised bearing
    transition F (2, 2) for a track whose [theta, omega] was x0 (P0) at t0 and is predicted
    x1 (P1, with Q) at t by 000's model, from the hint h (module docstring: the track's own
    state along the solution's relative track when its range is observable, else near the
    approach the solution's own bearing and rate); own ship at o0, o1 (straight between
    them); None where the module's switch or a guard says no."""
    if not h.converged or h.P is None:
        return None
    p, v, P = np.array([h.x, h.y]), np.array([h.vx, h.vy]), np.asarray(h.P, float).reshape(4, 4)
    u = (o1 - o0) / (t - t0)
    T = t - t0
    A = np.array([[1.0, T], [0.0, 1.0]])
    Q = P1 - A @ P0 @ A.T  # the bearing block of 000's Q (P1 = A P0 A' + Q)
    m0, J0 = bearing_and_rate(p, v, h.t, t0, o0, u)
    c0 = J0 @ P @ J0.T
    if not usable_covariance(c0) or not consistent(m0, c0, x0, P0):
        return None  # a solution of another contact, or one that drifted
    if h.usable:  # the track's own bearing and rate along the solution's relative track
        s, Js = rate_ratio(p, v, h.t, t0, o0, u)
        m1, F, G = propagate(x0, s, T)
        C1 = F @ P0 @ F.T + np.outer(G, G) * max(float(Js @ P @ Js), 0.0) + Q
        return (m1, C1, F) if usable_covariance(C1) else None
    m1, J1 = bearing_and_rate(p, v, h.t, t, o1, u)
    if abs(float(wrap_pi(m1[0] - m0[0] - T * m0[1]))) <= np.sqrt(P0[0, 0]):
        return None  # the model's constant rate is within its sigma: it predicts
    c1 = J1 @ P @ J1.T
    if not usable_covariance(c1) or not consistent(m1[:1], c1[:1, :1], x1[:1], P1[:1, :1]):
        return None
    return m1, c1 + Q, np.zeros((2, 2))


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
