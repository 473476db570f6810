"""Block estimator of seed 004 (eq. 6-10): the straight line of a track near a crossing,
fitted to all the points of its neighbourhood with the points that fit a neighbour's
line down-weighted.

004 writes a track as X_n = A t_n + B + W_n (eq. 1) and a point as coming from the track
of interest (probability q), a close track (q') or far tracks and false points (uniform
density 1 / c) (eq. 2-5). The maximum-likelihood line, to first order in q, is

    (A, B) = Arg Max sum_n g(X_n - A t_n - B) / h(X_n)                         (eq. 6)

with h(X_n) = q'' / c + q' g(X_n - A' t_n - B'). When no two lines come close over the
span of the points (eq. 7: min_t ||(A^k - A^j) t + (B^k - B^j)||^2 > threshold) h is
constant and (eq. 8) the lines decouple: (A, B) = Arg Max sum_n g(X_n - A t_n - B). Near a
crossing the points are cut into blocks of N (n = mN + p), and with the estimates of
block l - 1 (r^k = q''^k / c, the neighbours' proportions q^j and lines A^j, B^j) the
line of track k at block l is (eq. 9, eq. 10)

    (A_l^k, B_l^k) = Arg Max sum_{m<=l} sum_p g(X_mN+p - A t_mN+p - B) / den_mN+p,
    den_mN+p = r^k + sum_{j != k} q^j g(X_mN+p - A^j_(m-1)N+p t_mN+p - B^j_(m-1)N+p).

`weights` gives 1 / den (eq. 10; eq. 8 is den = 1); `maximise` finds the local maximum
of eq. 10 from the previous block's line (004: "a grid or a gradient method from
(A_l-1, B_l-1)"): for a Gaussian g the stationarity condition is a weighted least-squares
problem with weights u_n = g(res_n) / den_n, iterated to a fixed point (the regression
form of the mean shift, an EM step of the mixture of eq. 3: every iteration raises the
objective, so it climbs to the local maximum its start lies under). `line_covariance`
is the inverse Fisher information of the line with each point counted by its posterior
probability of belonging to track k under eq. 3, and `share` that probability, the
"proportion of points assigned to track k" that updates q^k (eq. 10 text).

Conventions: the line is C(t) = B + A (t - t_ref) (t_ref a time near the points, for the
conditioning of the fit; 004 writes t_ref = 0); X (P, m) points at times t (P,), each with
the covariance cov (P, m, m) of g; angle components (angle_idx) wrapped in residuals.
Deviation: the sum of eq. 7 is taken in the metric of g (Mahalanobis), not Euclidean,
so the threshold is in sigmas whatever the units of the components.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_pi
from common.core.gating import quadratic_form


@dataclass(frozen=True)
class Line:
    """A track's line of 004 eq. 1: C(t) = B + A (t - t_ref); A, B (m,)."""

    A: np.ndarray
    B: np.ndarray
    t_ref: float

    def at(self, t: np.ndarray) -> np.ndarray:
        """C(t) for the times t (P,), shape (P, m)."""
        return self.B[None, :] + np.outer(np.asarray(t, dtype=float) - self.t_ref, self.A)


def residuals(X: np.ndarray, t: np.ndarray, line: Line, angle_idx: Sequence[int] = ()) -> np.ndarray:
    """X_n - A t_n - B, shape (P, m), angle components wrapped to [-pi, pi)."""
    d = np.asarray(X, dtype=float) - line.at(t)
    for i in angle_idx:
        d[:, i] = wrap_pi(d[:, i])
    return d


def density(d: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """g(d) (P,): the zero-mean Gaussian density of covariance cov (P, m, m) at d (P, m)."""
    m = d.shape[-1]
    return np.exp(-0.5 * quadratic_form(d, cov)) / np.sqrt((2.0 * np.pi) ** m * np.linalg.det(cov))


def lines_separated(a: Line, b: Line, t0: float, t1: float, cov: np.ndarray, threshold: float,
                    angle_idx: Sequence[int] = ()) -> bool:
    """004 eq. 7 for two lines over [t0, t1]: min_t ||C_a(t) - C_b(t)||^2 > threshold, the
    norm in the metric of g (cov (m, m)); `separated` for one line b."""
    return bool(separated(a, b.A[None, :], b.at(np.array([t0])), t0, t1, cov, threshold, angle_idx)[0])


def separated(a: Line, A: np.ndarray, C0: np.ndarray, t0: float, t1: float, cov: np.ndarray,
              threshold: float, angle_idx: Sequence[int] = ()) -> np.ndarray:
    """004 eq. 7 of line a against J lines of slopes A (J, m) and values C0 (J, m) at t0:
    (J,) True where min over [t0, t1] of the squared distance in the metric of g exceeds
    threshold; the minimum of each quadratic in t, clipped to the interval (the
    differences' angle components wrapped at t0)."""
    d0 = a.at(np.array([t0])) - C0
    for i in angle_idx:
        d0[:, i] = wrap_pi(d0[:, i])
    dA = a.A[None, :] - A
    den = quadratic_form(dA, cov)
    cross = np.einsum("ji,ji->j", dA, np.linalg.solve(cov, d0.T).T)
    s = np.clip(np.where(den > 0.0, -cross / np.where(den > 0.0, den, 1.0), 0.0), 0.0, t1 - t0)
    return quadratic_form(d0 + s[:, None] * dA, cov) > threshold  # 004 eq. 7


def weights(X: np.ndarray, t: np.ndarray, cov: np.ndarray, r: float, q: np.ndarray,
            neighbours: Sequence[Line], angle_idx: Sequence[int] = ()) -> np.ndarray:
    """1 / den_n (P,) of 004 eq. 10: den = r^k + sum_j q^j g(X_n - A^j t_n - B^j) over the
    neighbour lines (their estimates of the previous block) and proportions q (J,);
    without neighbours den = r^k, a constant factor: eq. 8."""
    den = np.full(np.asarray(t).size, float(r))
    for qj, line in zip(np.asarray(q, dtype=float), neighbours):
        den += qj * density(residuals(X, t, line, angle_idx), cov)  # 004 eq. 10
    return 1.0 / den


def objective(X: np.ndarray, t: np.ndarray, cov: np.ndarray, w: np.ndarray, line: Line,
              angle_idx: Sequence[int] = ()) -> float:
    """sum_n w_n g(X_n - A t_n - B): eq. 8 with w = 1, eq. 9-10 with w = `weights`."""
    return float(np.sum(w * density(residuals(X, t, line, angle_idx), cov)))


def _design(t: np.ndarray, t_ref: float, m: int) -> np.ndarray:
    """Phi_n (P, m, 2m) with C = Phi_n [A; B]: [dt I, I]."""
    dt = np.asarray(t, dtype=float) - t_ref
    eye = np.eye(m)
    return np.concatenate([dt[:, None, None] * eye, np.broadcast_to(eye, (dt.size, m, m))], axis=2)


def _normal_equations(t: np.ndarray, t_ref: float, cov: np.ndarray, u: np.ndarray,
                      d: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """sum u_n Phi' cov^-1 Phi (2m, 2m) and sum u_n Phi' cov^-1 d_n (2m,)."""
    m = cov.shape[-1]
    phi = _design(t, t_ref, m)
    W = np.linalg.inv(cov)
    info = np.einsum("n,nia,nij,njb->ab", u, phi, W, phi)
    rhs = np.zeros(2 * m) if d is None else np.einsum("n,nia,nij,nj->a", u, phi, W, d)
    return info, rhs


def maximise(X: np.ndarray, t: np.ndarray, cov: np.ndarray, w: np.ndarray, start: Line,
             angle_idx: Sequence[int] = (), max_iter: int = 50, tol: float = 1e-6) -> tuple[Line, bool]:
    """The local maximum of eq. 10 (eq. 8 with w = 1) reached from `start` (the previous
    block's line): fixed point of the weighted least squares with u_n = w_n g(res_n),
    each step an ascent step; returns (line, converged). Fewer points than 2m, or a
    singular system, leave the start line (converged False)."""
    m = cov.shape[-1]
    line = start
    if np.asarray(t).size < 2 * m:
        return line, False
    for _ in range(max_iter):
        d = residuals(X, t, line, angle_idx)
        u = w * density(d, cov)
        if not np.any(u > 0.0):
            return line, False
        info, rhs = _normal_equations(t, line.t_ref, cov, u / u.max(), d)
        try:
            step = np.linalg.solve(info, rhs)
        except np.linalg.LinAlgError:
            return line, False
        new = Line(line.A + step[:m], line.B + step[m:], line.t_ref)
        if len(angle_idx):
            B = new.B.copy()
            B[list(angle_idx)] = wrap_pi(B[list(angle_idx)])
            new = Line(new.A, B, new.t_ref)
        line = new
        if float(step @ rhs) / float(np.sum(u / u.max())) < tol:  # step' info step
            return line, True
    return line, False


def share(X: np.ndarray, t: np.ndarray, cov: np.ndarray, w: np.ndarray, q: float, line: Line,
          angle_idx: Sequence[int] = ()) -> np.ndarray:
    """Posterior probability (P,) that point n belongs to track k under eq. 3:
    q g_k / (q g_k + den_n), den_n = 1 / w_n the rest of the mixture (eq. 10)."""
    gk = q * density(residuals(X, t, line, angle_idx), cov)
    return gk / (gk + 1.0 / w)


def line_covariance(t: np.ndarray, cov: np.ndarray, p: np.ndarray, t_ref: float) -> np.ndarray:
    """Covariance (2m, 2m) of [A; B]: the inverse of sum_n p_n Phi_n' cov_n^-1 Phi_n, each
    point counted by its probability p_n of belonging to the track (`share`)."""
    info, _ = _normal_equations(t, t_ref, cov, p)
    return np.linalg.inv(info)
