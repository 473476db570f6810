"""3-D position and velocity from the bistatic ranges and range rates of K bases,
without azimuth and without an altitude assumption.

Position (weighted least squares on 001 [1], r_b,k = ||p - T_k|| + ||p - R_k||), by
Gauss-Newton, the iterative method of M. Malanowski, K. Kulpa, "Two methods for target
localization in multistatic passive radar", IEEE TAES 48(1), 2012; the textbook step
(S. Kay, Fundamentals of Statistical Signal Processing I, 1993, sec. 8.9):

    J_k = (u_T,k + u_R,k)'                 (unit vectors transmitter/receiver -> p)
    p  <- p + (J' W J)^-1 J' W (r - h(p)),  W = diag(1 / R_rr,k)        [GN]

started from S seeds (points of the surveillance volume); per candidate the converged
solution of least cost with z in the bounds is kept (the ellipsoids of coplanar sites
are symmetric about their plane: the mirror below it is refused by the bounds).
Velocity, 001 [2] at fixed p: v_b,k = (u_T,k + u_R,k) . v, linear WLS          [LS]
Then two Gauss-Newton steps on [p, v] jointly with the full 2x2 R_k of each base (the
[r_b, v_b] rows of 001 [47]'s Jacobian, `project_jacobian`), whose information

    I = sum_k J6_k' R_k^-1 J6_k,  P = I^-1                                    [FIM]

is the covariance (Cramer-Rao bound, Kay sec. 3.8). A candidate whose information is
singular or whose worst position sigma exceeds `max_sigma` is reported degenerate.
Residual chi-squares: chi2_r = sum (r - h)^2 / R_rr and chi2_v likewise on v_b (K - 3
degrees of freedom each), chi2 = sum e' R^-1 e (2K - 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.gating import quadratic_form
from common.radar.geometry.bistatic import POS, VEL, norm3, project_jacobian

STEP_TOL = 1.0  # m: a Gauss-Newton run has converged when its last step is shorter
MAX_STEP = 30e3  # m: longest Gauss-Newton step (keeps far seeds from jumping away)


@dataclass(frozen=True)
class Fix:
    """Per candidate: x (N, 6) [x vx y vy z vz], P (N, 6, 6) [FIM], chi2, chi2_r,
    chi2_v (N,), n (N,) bases used, ok (N,) converged in bounds and not degenerate,
    degenerate (N,)."""

    x: np.ndarray
    P: np.ndarray
    chi2: np.ndarray
    chi2_r: np.ndarray
    chi2_v: np.ndarray
    n: np.ndarray
    ok: np.ndarray
    degenerate: np.ndarray


def _unit_sum(p: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """h = r_b (001 [1]) and u_T + u_R for positions p (M, 3), sites (M, K, 3)."""
    d_t, d_r = p[:, None, :] - tx, p[:, None, :] - rx
    n_t, n_r = norm3(d_t), norm3(d_r)
    return n_t + n_r, d_t / n_t[..., None] + d_r / n_r[..., None]


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A^-1 b for (M, n, n), (M, n) with a relative Levenberg floor (singular A)."""
    tr = np.trace(A, axis1=1, axis2=2)[:, None, None] / A.shape[1]
    return np.linalg.solve(A + 1e-12 * tr * np.eye(A.shape[1]) + 1e-30 * np.eye(A.shape[1]),
                           b[..., None])[..., 0]


def gauss_newton(p: np.ndarray, r: np.ndarray, w: np.ndarray, tx: np.ndarray, rx: np.ndarray,
                 iters: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[GN] for M problems: start p (M, 3), ranges r (M, K), weights w (M, K) (0 for an
    unused slot), sites (M, K, 3). Returns p, the cost sum w (r - h)^2, converged."""
    p = p.copy()
    step = np.full(p.shape[0], np.inf)
    for _ in range(iters):
        h, J = _unit_sum(p, tx, rx)
        wJ = J * w[..., None]
        dp = _solve(np.einsum("mki,mkj->mij", wJ, J), np.einsum("mki,mk->mi", wJ, r - h))
        step = norm3(dp)
        dp *= np.minimum(1.0, MAX_STEP / np.maximum(step, 1e-300))[:, None]
        p += dp
    h, _ = _unit_sum(p, tx, rx)
    return p, np.sum(w * (r - h) ** 2, axis=1), step < STEP_TOL


def _jacobian(x: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """[r_b, v_b] rows of 001 [47]'s Jacobian at states x (N, 6) for sites (N, K, 3)."""
    n, k = tx.shape[:2]
    rows = project_jacobian(np.repeat(x, k, axis=0), tx.reshape(-1, 3), rx.reshape(-1, 3))
    return rows[:, :2].reshape(n, k, 2, 6)


def _residual(x: np.ndarray, z: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """z - [r_b, v_b](x) (001 [1], [2]) for states (N, 6), z (N, K, 2)."""
    h, u = _unit_sum(x[:, POS], tx, rx)
    return z - np.stack([h, np.einsum("nki,ni->nk", u, x[:, VEL])], axis=-1)


def localise(z: np.ndarray, R: np.ndarray, tx: np.ndarray, rx: np.ndarray, valid: np.ndarray,
             seeds: np.ndarray, z_bounds: tuple[float, float], max_sigma: float,
             iters: int = 25) -> Fix:
    """[GN], [LS], [FIM] for N candidates of K slots: z (N, K, 2) [r_b, v_b], R (N, K,
    2, 2), sites (N, K, 3), valid (N, K), seeds (S, 3) shared by all candidates or
    (N, S, 3) per candidate."""
    n, k = valid.shape
    s = seeds.shape[-2]
    Ri = np.linalg.inv(np.where(valid[..., None, None], R, np.eye(2)))
    Ri *= valid[..., None, None]
    w = np.where(valid, 1.0 / np.where(valid, R[..., 0, 0], 1.0), 0.0)
    rep = (np.repeat(z[..., 0], s, axis=0), np.repeat(w, s, axis=0),
           np.repeat(tx, s, axis=0), np.repeat(rx, s, axis=0))
    start = seeds.reshape(-1, 3) if seeds.ndim == 3 else np.tile(seeds, (n, 1))
    p, cost, conv = gauss_newton(start, *rep, iters=iters)
    inside = conv & (p[:, 2] >= z_bounds[0]) & (p[:, 2] <= z_bounds[1])
    best = np.argmin(np.where(inside, cost, np.inf).reshape(n, s), axis=1)
    pick = np.arange(n) * s + best
    found = inside[pick]
    x = np.zeros((n, 6))
    x[:, POS] = p[pick]
    _, u = _unit_sum(x[:, POS], tx, rx)
    wv = np.where(valid, 1.0 / np.where(valid, R[..., 1, 1], 1.0), 0.0)[..., None] * u
    x[:, VEL] = _solve(np.einsum("nki,nkj->nij", wv, u), np.einsum("nki,nk->ni", wv, z[..., 1]))
    for _ in range(2):
        J = _jacobian(x, tx, rx)
        RiJ = Ri @ J
        info = np.einsum("nkai,nkaj->nij", J, RiJ)
        x += _solve(info, np.einsum("nkai,nka->ni", RiJ, _residual(x, z, tx, rx)))
    J = _jacobian(x, tx, rx)
    info = np.einsum("nkai,nkaj->nij", J, Ri @ J)
    eig = np.linalg.eigvalsh(info)
    singular = eig[:, 0] <= 1e-12 * np.maximum(eig[:, -1], 1e-300)
    P = np.linalg.inv(info + singular[:, None, None] * np.eye(6))
    P = 0.5 * (P + np.swapaxes(P, 1, 2))
    worst = np.sqrt(np.linalg.eigvalsh(P[:, POS][:, :, POS])[:, -1])
    e = _residual(x, z, tx, rx) * valid[..., None]
    chi2 = np.sum(quadratic_form(e, np.where(valid[..., None, None], R, np.eye(2))) * valid, axis=1)
    chi2_r = np.sum(e[..., 0] ** 2 * w, axis=1)
    chi2_v = np.sum(e[..., 1] ** 2 * np.where(valid, 1.0 / np.where(valid, R[..., 1, 1], 1.0), 0.0),
                    axis=1)
    count = valid.sum(axis=1)
    degenerate = singular | (worst > max_sigma) | (count < 3)
    ok = found & ~degenerate & np.all(np.isfinite(x), axis=1) & (x[:, 4] >= z_bounds[0])
    return Fix(x, P, chi2, chi2_r, chi2_v, count, ok, degenerate)
