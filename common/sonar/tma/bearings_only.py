"""Bearings-only target motion analysis (seed 002, DE 34 46 658).

Iterative Gauss-Newton estimate of the target vector
beta = (X0, Y0, Vx0, Vy0, Vx1, Vy1, ...) -- position at the reference time t0 and one
velocity per leg (002 eq. 17) -- from bearings taken at known own positions.

Frame: East-North metres, bearings in radians clockwise from North,
brg = atan2(x_t - x_o, y_t - y_o) (002 eq. 1-2). Times in seconds.

Sign convention (deviation from the seed's printed signs): the seed writes
h_i1 = -R_yi/R_i^2, h_i2 = R_xi/R_i^2 (eq. 5; claim 2 even swaps x and y) and
h_SR = -2 R_x (eq. 11.1) while it *adds* Delta p to beta (adder 94). Those signs
belong to Delta p = estimate - truth. Here H is the true Jacobian of the measurement
model (h_i1 = +R_yi/R_i^2, h_i2 = -R_xi/R_i^2, h_SR = +2 R_x, course
h_SK = (+Vy, -Vx)/V^2), so that beta <- beta + Delta p with Delta p = F delta is a
descent step; magnitudes are those of the seed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Sequence

import numpy as np
from scipy.special import chdtri

from common.core.angles import wrap_pi

SupportKind = Literal["range", "speed", "course"]


@dataclass(frozen=True)
class Support:
    """A support value (002 claims 3-10): an observed range, speed or course.

    ``t`` is the reference time T_R of the observation; ``obs_xy`` the observing
    position (X_R, Y_R), needed for a range. ``sigma`` is the value's standard
    deviation; its weight (claim 6) is 1/sigma of the filtered difference.
    """

    kind: SupportKind
    value: float
    sigma: float
    t: float
    obs_xy: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class TmaSolution:
    """Result of :func:`solve_tma` (or of a constrained solve in ``common.sonar.tma.constrained``).

    ``beta`` = (X0, Y0, Vx0, Vy0, Vx1, Vy1, ...) at ``t0``; leg j starts at
    ``manoeuvre_times[j-1]``. ``P`` is (H'WH)^-1 from the final Jacobian.
    ``residuals`` are bearing residuals B_Mi - B^_Mi (rad); ``cost`` is the weighted
    sum of squares of all residuals (bearings and support values).
    """

    beta: np.ndarray
    P: np.ndarray
    t0: float
    manoeuvre_times: tuple[float, ...]
    residuals: np.ndarray
    cost: float
    n_iter: int
    converged: bool
    t_last: float = field(default=0.0)

    def state_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Target (x, y, vx, vy) at time ``t`` and its 4x4 covariance."""
        G = state_map(np.array([t]), self.t0, self.manoeuvre_times)[0]
        return G @ self.beta, G @ self.P @ G.T


def leg_times(t: np.ndarray, t0: float, manoeuvre_times: Sequence[float]) -> np.ndarray:
    """Time signals T'_Mij (N, L) of the time comparison circuit 79 (002 claim 14).

    Leg j >= 1 gets clip(T_Mi - T_Aj, 0, T_Aj+1 - T_Aj), the three cases of claim 14.
    Deviation: eq. 15 is printed as max(0, min(T_Mi - T_Aj, T_Aj+1 - T_Mi)), which
    contradicts claim 14 for times after the leg; claim 14 is implemented. Leg 0 gets
    min(T_Mi - t0, T_A1 - t0) without the lower clip so that t0 may lie after the first
    bearing (the seed fixes T_A0 = first measurement time).
    """
    t = np.asarray(t, dtype=float)
    edges = np.concatenate(([t0], np.asarray(manoeuvre_times, dtype=float), [np.inf]))
    out = np.empty((t.size, edges.size - 1))
    out[:, 0] = np.minimum(t - t0, edges[1] - t0)
    for j in range(1, edges.size - 1):
        out[:, j] = np.clip(t - edges[j], 0.0, edges[j + 1] - edges[j])
    return out


def active_leg(t: np.ndarray, manoeuvre_times: Sequence[float]) -> np.ndarray:
    """Index of the leg whose velocity holds at each time (leg j covers (T_Aj, T_Aj+1])."""
    return np.searchsorted(np.asarray(manoeuvre_times, dtype=float), np.asarray(t, float), side="left")


def state_map(t: np.ndarray, t0: float, manoeuvre_times: Sequence[float]) -> np.ndarray:
    """Linear maps G (N, 4, 2+2L) with (x, y, vx, vy)(t_i) = G_i beta (002 eq. 16)."""
    T = leg_times(t, t0, manoeuvre_times)
    n, L = T.shape
    G = np.zeros((n, 4, 2 + 2 * L))
    G[:, 0, 0] = 1.0
    G[:, 1, 1] = 1.0
    G[:, 0, 2::2] = T
    G[:, 1, 3::2] = T
    leg = active_leg(t, manoeuvre_times)
    G[np.arange(n), 2, 2 + 2 * leg] = 1.0
    G[np.arange(n), 3, 3 + 2 * leg] = 1.0
    return G


def bearing_model(
    beta: np.ndarray, t: np.ndarray, own_xy: np.ndarray, t0: float, manoeuvre_times: Sequence[float] = ()
) -> tuple[np.ndarray, np.ndarray]:
    """Bearing estimates B^_Mi and measurement coefficients H (N, 2+2L).

    R_xi, R_yi per 002 eq. 3.1-3.2 / 16.1-16.2, B^_Mi = atan2(R_xi, R_yi) (eq. 1-2),
    h_i1, h_i2 = (R_yi, -R_xi)/R_i^2 (eq. 5, sign see module doc) and the dynamic
    coefficients h_i(2j+3), h_i(2j+4) = (h_i1, h_i2) * T'_Mij (eq. 5, claim 13).
    """
    T = leg_times(t, t0, manoeuvre_times)
    Rx = beta[0] + T @ beta[2::2] - own_xy[:, 0]
    Ry = beta[1] + T @ beta[3::2] - own_xy[:, 1]
    R2 = Rx * Rx + Ry * Ry  # eq. 3.3
    h1 = Ry / R2
    h2 = -Rx / R2
    H = np.empty((t.size, beta.size))
    H[:, 0] = h1
    H[:, 1] = h2
    H[:, 2::2] = h1[:, None] * T
    H[:, 3::2] = h2[:, None] * T
    return np.arctan2(Rx, Ry), H


def support_rows(
    beta: np.ndarray, support: Sequence[Support], t0: float, manoeuvre_times: Sequence[float] = ()
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted support differences delta_S / sigma and support coefficient rows (002 claims 3-10).

    Range: delta_SR = S_R^2 - R^2, h_SR = 2 (R_x, R_y, R_x T_R, R_y T_R) (eq. 11.1-11.2, 14.1).
    Speed: delta_SV = S_V^2 - V^2, h_SV = (0, 0, 2 Vx, 2 Vy) (eq. 12, 14.1).
    Course: delta_SK = S_K - K^ (linear, eq. 14.2), h_SK = (0, 0, Vy, -Vx)/V^2 (eq. 13).
    Squared values get sigma(S^2) = 2 S sigma_S. Velocity rows go to the leg active at T_R.
    """
    m = len(support)
    d = np.empty(m)
    H = np.zeros((m, beta.size))
    for k, s in enumerate(support):
        G = state_map(np.array([s.t]), t0, manoeuvre_times)[0]
        x, y, vx, vy = G @ beta
        if s.kind == "range":
            rx, ry = x - s.obs_xy[0], y - s.obs_xy[1]
            d[k] = s.value**2 - (rx * rx + ry * ry)
            H[k] = 2.0 * (rx * G[0] + ry * G[1])
            sig = 2.0 * s.value * s.sigma
        elif s.kind == "speed":
            d[k] = s.value**2 - (vx * vx + vy * vy)
            H[k] = 2.0 * (vx * G[2] + vy * G[3])
            sig = 2.0 * s.value * s.sigma
        else:
            v2 = vx * vx + vy * vy
            d[k] = wrap_pi(s.value - np.arctan2(vx, vy))
            H[k] = (vy * G[2] - vx * G[3]) / v2
            sig = s.sigma
        d[k] /= sig
        H[k] /= sig
    return d, H


def weighted_system(
    beta: np.ndarray,
    t: np.ndarray,
    brg: np.ndarray,
    sbrg: np.ndarray,
    own_xy: np.ndarray,
    t0: float,
    support: Sequence[Support] = (),
    manoeuvre_times: Sequence[float] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sigma-weighted differences delta (eq. 6), weighted H, and raw bearing residuals."""
    bhat, H = bearing_model(beta, t, own_xy, t0, manoeuvre_times)
    res = wrap_pi(brg - bhat)
    d = res / sbrg
    Hw = H / sbrg[:, None]
    if support:
        ds, Hs = support_rows(beta, support, t0, manoeuvre_times)
        d = np.concatenate((d, ds))
        Hw = np.vstack((Hw, Hs))
    return d, Hw, res


def covariance(Hw: np.ndarray) -> np.ndarray:
    """(H'WH)^-1 via SVD; an unobservable direction gets a huge, not a truncated, variance."""
    _, s, Vt = np.linalg.svd(Hw, full_matrices=False)
    s = np.maximum(s, s[0] * 1e-12 if s[0] > 0 else 1e-300)
    return (Vt.T / s**2) @ Vt


def initial_beta(
    t: np.ndarray, brg: np.ndarray, sbrg: np.ndarray, own_xy: np.ndarray, t0: float,
    r_grid: np.ndarray | None = None,
) -> np.ndarray:
    """Start vector (X0, Y0, Vx, Vy) from a range grid on the latest bearing.

    The seed leaves the base data store 15 arbitrary. For each candidate range r the
    target sits at r along the latest bearing; the velocity then solves the weighted
    pseudo-linear equations cos(B_i) R_xi - sin(B_i) R_yi = 0 (weights 1/(sigma_i r_i)).
    The candidate with the lowest true bearing cost is returned. Vectorised over r.
    """
    if r_grid is None:
        r_grid = np.geomspace(300.0, 100e3, 48)
    m = np.argmax(t)
    sb, cb = np.sin(brg), np.cos(brg)
    px = own_xy[m, 0] + r_grid * sb[m]
    py = own_xy[m, 1] + r_grid * cb[m]
    dt = t - t[m]
    A = np.stack((cb * dt, -sb * dt), axis=1)
    rhs = -cb[None, :] * (px[:, None] - own_xy[:, 0]) + sb[None, :] * (py[:, None] - own_xy[:, 1])
    dist = np.hypot(px[:, None] - own_xy[:, 0], py[:, None] - own_xy[:, 1])
    w = 1.0 / (sbrg[None, :] * np.maximum(dist, 1.0)) ** 2
    M = np.einsum("gn,ni,nj->gij", w, A, A) + 1e-12 * np.eye(2)
    v = np.linalg.solve(M, np.einsum("gn,ni,gn->gi", w, A, rhs)[..., None])[..., 0]
    xt = px[:, None] + v[:, :1] * dt
    yt = py[:, None] + v[:, 1:] * dt
    res = wrap_pi(brg - np.arctan2(xt - own_xy[:, 0], yt - own_xy[:, 1])) / sbrg
    g = int(np.argmin(np.sum(res * res, axis=1)))
    return np.array([px[g] + v[g, 0] * (t0 - t[m]), py[g] + v[g, 1] * (t0 - t[m]), v[g, 0], v[g, 1]])


def solve_tma(
    t: np.ndarray,
    brg: np.ndarray,
    sbrg: np.ndarray | float,
    own_xy: np.ndarray,
    t0: float,
    beta0: np.ndarray | None = None,
    support: Sequence[Support] = (),
    legs: Sequence[float] = (),
    tol: float = 1.0,
    max_iter: int = 50,
) -> TmaSolution:
    """Gauss-Newton TMA (002 claim 1, eq. 6-10, claim 17).

    Each iteration forms delta and H (eq. 5, support rows claims 3-10), solves
    Delta p = F delta with F = (H'H)^-1 H' (eq. 7-8) as a least-squares problem on the
    sigma-weighted system (QR/SVD via lstsq instead of forming the inverse), adds it to
    beta and stops when ||Delta p|| (claim 17, position correction at the latest
    measurement time, in metres) falls below ``tol``. ``legs`` are manoeuvre times T_Aj.
    Deviation: if a full step raises the weighted cost it is halved (up to 8 times); the
    seed always applies the full step, which diverges from poor starts.
    """
    t = np.asarray(t, dtype=float)
    brg = np.asarray(brg, dtype=float)
    own_xy = np.asarray(own_xy, dtype=float)
    sbrg = np.broadcast_to(np.asarray(sbrg, dtype=float), t.shape)
    legs = tuple(float(x) for x in legs)
    n_par = 4 + 2 * len(legs)
    if beta0 is None:
        b4 = initial_beta(t, brg, sbrg, own_xy, t0)
        beta = np.concatenate((b4, np.tile(b4[2:], len(legs))))
    else:
        beta = np.asarray(beta0, dtype=float).copy()
        if beta.size < n_par:
            beta = np.concatenate((beta, np.tile(beta[-2:], (n_par - beta.size) // 2)))
    T_last = leg_times(np.array([t.max()]), t0, legs)[0]
    d, Hw, res = weighted_system(beta, t, brg, sbrg, own_xy, t0, support, legs)
    cost = float(d @ d)
    converged = False
    it = 0
    for it in range(1, max_iter + 1):
        dp = np.linalg.lstsq(Hw, d, rcond=None)[0]  # eq. 7-8
        for _ in range(8):
            cand = beta + dp
            d_c, Hw_c, res_c = weighted_system(cand, t, brg, sbrg, own_xy, t0, support, legs)
            cost_c = float(d_c @ d_c)
            if np.isfinite(cost_c) and cost_c <= cost * (1.0 + 1e-9):
                break
            dp = 0.5 * dp
        else:
            break
        beta, d, Hw, res, cost = cand, d_c, Hw_c, res_c, cost_c
        norm = np.hypot(dp[0] + dp[2::2] @ T_last, dp[1] + dp[3::2] @ T_last)  # claim 17 / eq. 9
        if norm < tol:
            converged = True
            break
    return TmaSolution(beta, covariance(Hw), float(t0), legs, res, cost, it, converged, float(t.max()))


def detect_manoeuvre(
    t: np.ndarray,
    brg: np.ndarray,
    sbrg: np.ndarray | float,
    own_xy: np.ndarray,
    t0: float,
    current: TmaSolution,
    support: Sequence[Support] = (),
    min_leg_samples: int = 6,
    p_false: float = 1e-3,
) -> float | None:
    """Residual-based manoeuvre detector (002 claim 13, detector 76).

    Deviation: the seed's detector analyses the target noise spectrum; here each sample
    time after the latest leg start (leaving ``min_leg_samples`` on both sides) is tried
    as a new manoeuvre time T_Aj, the model with one more leg is fitted from
    ``current``, and the best candidate is proposed when the cost drop exceeds the
    chi-square(2) quantile at ``p_false`` / (number of candidates) (likelihood ratio).
    """
    t = np.asarray(t, dtype=float)
    order = np.sort(t)
    start = current.manoeuvre_times[-1] if current.manoeuvre_times else -np.inf
    after = order[order > start]
    cands = after[min_leg_samples:-min_leg_samples + 1] if after.size >= 2 * min_leg_samples else after[:0]
    cands = cands[cands < t.max() - 1e-9]
    if cands.size == 0:
        return None
    best_cost, best_t = current.cost, None
    for ta in cands:
        sol = solve_tma(t, brg, sbrg, own_xy, t0, current.beta, support, current.manoeuvre_times + (float(ta),))
        if sol.cost < best_cost:
            best_cost, best_t = sol.cost, float(ta)
    gate = chdtri(2, p_false / cands.size)  # chi2(2) upper quantile (scipy.stats.chi2.isf)
    return best_t if current.cost - best_cost > gate else None
