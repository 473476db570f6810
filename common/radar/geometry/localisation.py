"""Module 64 of 001 (and the fine step of module 62): target position and covariance
from the bistatic ranges of several bases, by blocks.

Every track n carries K constraint slots (one per base) with a validity mask; a slot
holds a bistatic range r_b (sigma_rb), an azimuth theta (sigma_theta) and the base's
transmitter and receiver. Two steps, both vectorised over tracks:

1. `gauss_newton`: weighted least squares refinement of a starting position (the
   coarse solution [32]-[35] of module 62, or the predicted global position). Used
   only to centre and size the box of step 2 (stated addition, welcome in issue 4).
2. `block_localise`: the parallelepiped x0 +- box_sigma sigma along the principal axes
   of the Gauss-Newton covariance C is subdivided `levels` times into 2x2x2 children; a child is kept while its range
   (and
   azimuth) interval can be within k sigma of every measurement and z in [z_min,
   z_max], and at the last level while its centre is (001 module 62, part 2). Each kept block m gets the probability
   P^m of [36]-[39] and the zone is summarised by mean and covariance [41].

Deviations, each for a stated reason:
* [39] multiplies the factors [37] of the ranges only; we also multiply a factor of
  the same form for the azimuth of each contributing elementary track. With two bases
  the intersection of two ellipsoids is a curve, so the range factors alone leave the
  extent of the block cloud along it set by the box size, not by the data.
* The normalised weight 1 - erf(|u| / sqrt 2) of [37] has variance 2/3 (in sigma^2
  units) where the Gaussian likelihood has 1: with w(u) = 2 (1 - Phi(|u|)),
  int u^2 w du / int w du = (2 phi(0) / 3) / phi(0) = 2/3. The covariance of [41] is
  multiplied by 3/2 so that it is the error covariance of the block mean (honest
  NEES); the Monte Carlo test of tests/radar/test_global_init.py checks the coverage.
* The seed writes Erf(x) = (1/sqrt(pi)) int_0^x e^-t^2 dt [38], half the classical erf
  it names; [37] is a probability only with the classical erf (scipy.special.erf).
* Each block stands for a uniform box, so its own spread (half-width h: h^2 / 3 per
  axis) is added to [41] (the covariance of the mixture of boxes); it keeps the
  covariance positive definite when few blocks survive.
* Azimuths follow the project convention (clockwise from North, atan2(dx, dy)).
* Altitude prior (not in 001): with transmitters and receiver nearly coplanar, d r_b /
  d z vanishes near the sensors' plane and the ellipsoids are symmetric about it, so 3-D
  position from two bases is ill-posed at low elevation (a banana-shaped zone, and its
  mirror below the plane). z >= z_min removes the mirror; the optional pseudo-measurement
  z ~ N(z_prior_mean, z_prior_sigma^2) (`z_prior`) regularises Gauss-Newton and weights
  the blocks with a factor of the form [37] (so the 3/2 correction below still holds).
  The caller decides where it may enter: once, in the initial state of a track (module
  62); module 64 during tracking uses it only to centre and size the box (a prior in
  every scan's measurement would be counted again at every EKF update).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import erf

from common.core.angles import wrap_pi
from common.core.gating import quadratic_form
from common.core.imm import gaussian_loglik
from common.radar.geometry.bistatic import norm3

STEP_TOL = 1e-6  # squared step (in posterior sigmas) below which a row stops iterating
COV_CORRECTION = 1.5  # inverse of the 2/3 variance ratio of the erf weight [37]
_CHILD = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)


@dataclass(frozen=True)
class Constraints:
    """Measurements of K base slots for N tracks; invalid slots are ignored.

    rb, srb, az, saz: (N, K); valid: (N, K) bool; tx, rx: (K, 3) or (N, K, 3).
    """

    rb: np.ndarray
    srb: np.ndarray
    az: np.ndarray
    saz: np.ndarray
    valid: np.ndarray
    tx: np.ndarray
    rx: np.ndarray

    def take(self, rows: np.ndarray) -> "Constraints":
        """The constraints of tracks `rows` (e.g. the owners of a flat block list)."""
        tx = self.tx if self.tx.ndim == 2 else self.tx[rows]
        rx = self.rx if self.rx.ndim == 2 else self.rx[rows]
        return Constraints(self.rb[rows], self.srb[rows], self.az[rows], self.saz[rows],
                           self.valid[rows], tx, rx)


def residuals(pos: np.ndarray, c: Constraints) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Range residuals r_b - r_b(pos) ([36]), wrapped azimuth residuals, and the
    horizontal receiver distance, each (N, K) for positions (N, 3)."""
    d_t = pos[:, None, :] - c.tx
    d_r = pos[:, None, :] - c.rx
    rb = norm3(d_t) + norm3(d_r)  # 001 [36]
    az = np.arctan2(d_r[..., 0], d_r[..., 1])
    return c.rb - rb, wrap_pi(c.az - az), np.hypot(d_r[..., 0], d_r[..., 1])


def gauss_newton(
    x0: np.ndarray, c: Constraints, iterations: int = 5, z_min: float = 0.0,
    z_prior: tuple[float, float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted least squares position from ranges and azimuths, started at x0 (N, 3).

    Returns the position (N, 3), z kept >= z_min, and the information inverse
    (J' W J)^-1 (N, 3, 3) at it (a tiny ridge keeps it finite when z is unobservable).
    z_prior = (mean, sigma), scalars or (N,): the altitude pseudo-measurement
    z ~ N(mean, sigma^2) is one more row of the least squares (module doc).
    """
    x = np.array(x0, dtype=float)
    w = c.valid.astype(float)
    prior = np.zeros((x.shape[0], 3, 3))
    if z_prior is not None:
        prior[:, 2, 2] = 1.0 / np.square(z_prior[1])
    for it in range(iterations + 1):
        d_t = x[:, None, :] - c.tx
        d_r = x[:, None, :] - c.rx
        n_t = norm3(d_t)[..., None]
        n_r = norm3(d_r)[..., None]
        rho2 = d_r[..., 0] ** 2 + d_r[..., 1] ** 2
        j_rb = (d_t / n_t + d_r / n_r) * (w / c.srb)[..., None]
        j_az = np.zeros_like(j_rb)
        j_az[..., 0] = d_r[..., 1] / rho2
        j_az[..., 1] = -d_r[..., 0] / rho2
        j_az *= (w / c.saz)[..., None]
        J = np.concatenate([j_rb, j_az], axis=1)
        info = np.swapaxes(J, 1, 2) @ J + prior + 1e-12 * np.eye(3)
        if it == iterations:
            break
        res_rb, res_az, _ = residuals(x, c)
        r = np.concatenate([res_rb * w / c.srb, res_az * w / c.saz], axis=1)
        g = (np.swapaxes(J, 1, 2) @ r[..., None])[..., 0]
        if z_prior is not None:
            g[:, 2] += (z_prior[0] - x[:, 2]) * prior[:, 2, 2]
        dx = np.linalg.solve(info, g[..., None])[..., 0]
        x = x + dx
        x[:, 2] = np.maximum(x[:, 2], z_min)
    return x, np.linalg.inv(info)


def _box(
    C: np.ndarray, k: float, min_half: float, max_half: float
) -> tuple[np.ndarray, np.ndarray]:
    """Axes (N, 3, 3) (columns: eigenvectors of C) and half-widths (N, 3) of the
    parallelepiped x0 +- k sigma along the principal axes of C (N, 3, 3)."""
    w, V = np.linalg.eigh(C)
    return V, np.clip(k * np.sqrt(np.maximum(w, 0.0)), min_half, max_half)


def _keep(
    pos: np.ndarray, c: Constraints, k: float, z_min: float, z_max: float,
    h: np.ndarray | None = None, V: np.ndarray | None = None, reach: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Blocks (centres (M, J, 3): J blocks of each of the M rows of c, half-widths h
    (M, 3) along the axes V (M, 3, 3); none: centre test) that may hold a point within
    k sigma of every valid measurement and inside [z_min, z_max] (M, J), and |r_b
    residual| [36], |azimuth residual| (M, J, K) at the centres. Spread of a block,
    half-diagonal d: 001's bounds |grad r_b| <= 2 and |grad theta| <= 1 / rho; and
    Taylor bounds sum_i |g . v_i| e_i + e^2 ||H|| / 2 over the box of half-widths
    `reach` (M, 3) <= h that holds the points that matter (e: its half-diagonal; g, H:
    gradient at the centre and bound of the Hessian over that box, ||H|| <= 1 / |x - tx|
    + 1 / |x - rx| for r_b, 1 / rho^2 for theta, distances shrunk by e): a block that
    fails them holds no such point that passes, so the blocks kept at the last level are
    the same (tests/radar/test_block_pruning.py checks against an exhaustive evaluation)."""
    tx = c.tx if c.tx.ndim == 2 else c.tx[:, None]
    rx = c.rx if c.rx.ndim == 2 else c.rx[:, None]
    srb, saz, valid = c.srb[:, None], c.saz[:, None], c.valid[:, None]
    d_t = pos[:, :, None, :] - tx
    d_r = pos[:, :, None, :] - rx
    n_t, n_r = norm3(d_t), norm3(d_r)
    res_rb = np.abs(c.rb[:, None] - (n_t + n_r))  # 001 [36], as `residuals`
    res_az = np.abs(wrap_pi(c.az[:, None] - np.arctan2(d_r[..., 0], d_r[..., 1])))
    if h is None or V is None:
        ok = np.all(((res_rb <= k * srb) & (res_az <= k * saz)) | ~valid, axis=2)
        return ok & (pos[..., 2] >= z_min) & (pos[..., 2] <= z_max), res_rb, res_az
    rho = np.hypot(d_r[..., 0], d_r[..., 1])
    reach = h if reach is None else reach
    diag = norm3(h)
    d, e = diag[:, None, None], norm3(reach)[:, None, None]
    with np.errstate(divide="ignore", invalid="ignore"):  # the Taylor bounds
        g_rb = d_t / n_t[..., None] + d_r / n_r[..., None]
        g_az = np.stack([d_r[..., 1], -d_r[..., 0], 0.0 * rho], -1) / rho[..., None] ** 2
        lin_rb = (np.abs(g_rb @ V[:, None]) @ reach[:, None, :, None])[..., 0]
        lin_az = (np.abs(g_az @ V[:, None]) @ reach[:, None, :, None])[..., 0]
        far_rb = (n_t > e) & (n_r > e)
        tight_rb = np.where(far_rb, lin_rb + 0.5 * e**2 * (1.0 / (n_t - e) + 1.0 / (n_r - e)),
                            np.inf)
        tight_az = np.where(rho > e, lin_az + 0.5 * e**2 / (rho - e) ** 2, np.inf)
    ok_rb = ((res_rb <= k * srb + 2.0 * d)  # with a margin for the rounding of the bounds
             & (res_rb <= k * srb + tight_rb + 1e-9 * (n_t + n_r)))
    ok_az = ((res_az <= k * saz + d / np.maximum(rho, 1.0))
             & (res_az <= k * saz + tight_az + 1e-12))
    s_z = np.minimum(diag[:, None], np.abs(V[:, 2, :] * reach).sum(axis=1)[:, None]
                     + 1e-9 * np.abs(pos[..., 2]))
    ok_z = (pos[..., 2] >= z_min - s_z) & (pos[..., 2] <= z_max + s_z)
    return np.all((ok_rb & ok_az) | ~valid, axis=2) & ok_z, res_rb, res_az


def block_localise(
    x0: np.ndarray, C0: np.ndarray, c: Constraints, k: float = 3.0, levels: int = 3,
    z_min: float = 0.0, z_max: float = 20000.0, box_sigma: float = 4.0,
    min_half: float = 25.0, max_half: float = 30000.0,
    z_prior: tuple[float, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Blocks around x0 (N, 3) sized by C0 (N, 3, 3) -> (mean (N, 3), cov (N, 3, 3),
    n_blocks (N,)); mean and cov are NaN where no block survives (no intersection).
    z_prior = (mean, sigma): the altitude prior multiplies the weight [39] of each
    block by a factor of the form [37] (module doc)."""
    n = x0.shape[0]
    if n == 0:
        return np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros(0, dtype=np.intp)
    V, half0 = _box(C0, box_sigma, min_half, max_half)
    pos, owner = np.array(x0, dtype=float), np.arange(n)
    res_rb, res_az = (np.abs(r) for r in residuals(pos, c)[:2])  # levels = 0: at x0
    h_end = half0 / 2.0**levels
    within = (V * (h_end**2 / 3.0)[:, None, :]) @ np.swapaxes(V, 1, 2)
    K = c.rb.shape[1]
    for level in range(1, levels + 1):
        h = half0[owner] / 2.0**level
        local = _CHILD[None, :, :] * h[:, None, :]  # (M, 8, 3) in the box axes
        Vo = V[owner]
        pos = pos[:, None, :] + local @ np.swapaxes(Vo, 1, 2)  # the 8 children of each
        spread = (h, Vo, h - h_end[owner]) if level < levels else ()  # reach: leaf centres
        keep, res_rb, res_az = _keep(pos, c.take(owner), k, z_min, z_max, *spread)
        keep = keep.ravel()
        pos, owner = pos.reshape(-1, 3)[keep], np.repeat(owner, 8)[keep]
        res_rb, res_az = res_rb.reshape(-1, K)[keep], res_az.reshape(-1, K)[keep]
    cm = c.take(owner)
    p_rb = 1.0 - erf(res_rb / (cm.srb * np.sqrt(2.0)))  # 001 [37]
    p_az = 1.0 - erf(res_az / (cm.saz * np.sqrt(2.0)))  # [37] for the azimuth
    p = np.prod(np.where(cm.valid, p_rb * p_az, 1.0), axis=1)
    if z_prior is not None:
        p = p * (1.0 - erf(np.abs(pos[:, 2] - z_prior[0]) / (z_prior[1] * np.sqrt(2.0))))
    total = np.bincount(owner, p, minlength=n).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        pm = p / total[owner]  # 001 [39]
        mean = np.stack([np.bincount(owner, pm * pos[:, i], minlength=n) for i in range(3)],
                        1).astype(float)
        mean[total <= 0] = np.nan  # 001 [41], mean
        d = pos - mean[owner]
        cov = np.stack([np.bincount(owner, pm * d[:, i] * d[:, j], minlength=n)
                        for i in range(3) for j in range(3)], 1).reshape(n, 3, 3).astype(float)  # [41]
    cov = COV_CORRECTION * cov + within
    cov[total <= 0] = np.nan
    return mean, cov, np.bincount(owner, minlength=n)


def _predict_meas(pts: np.ndarray, c: Constraints, ref_az: np.ndarray) -> np.ndarray:
    """Ranges [36] and azimuths (unwrapped around ref_az (N, K)) of the K constraint
    slots at points pts (N, M, 3) -> (N, M, 2K)."""
    tx = c.tx[None, None] if c.tx.ndim == 2 else c.tx[:, None]
    rx = c.rx[None, None] if c.rx.ndim == 2 else c.rx[:, None]
    d_t = pts[:, :, None, :] - tx
    d_r = pts[:, :, None, :] - rx
    rb = norm3(d_t) + norm3(d_r)  # 001 [36]
    az = ref_az[:, None, :] + wrap_pi(np.arctan2(d_r[..., 0], d_r[..., 1]) - ref_az[:, None, :])
    return np.concatenate([rb, az], axis=-1)


def _slr(
    x: np.ndarray, S: np.ndarray, c: Constraints, z_min: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Statistical linear regression of the ranges and azimuths over N(x, S): mean
    (N, 2K), slope A (N, 2K, 3) and a factor U (N, 2K, 3) of the linearisation error
    covariance Omega = U U', from the 6 unscented points x +- L e_i, L = sqrt(3) S^(1/2)
    (kappa = 0), of the function h(X) evaluated with z kept >= z_min (a function of X
    flat below z_min: the regression is on the points themselves, so that its slope
    stays that of the data).

    Closed forms of the regression on these points (dY+-: the + and - points' outputs
    minus their mean): Psi = L (dY+ - dY-) / 6 and S = L L' / 3, so
    A = Psi' S^-1 = (dY+ - dY-)' L^-1 / 2, and Omega = Cov(Y) - Psi' S^-1 Psi, the
    part of dY outside the span of the antisymmetric point pairs, is
    (dY+ + dY-)' (dY+ + dY-) / 12: positive semi-definite, of rank <= 3 (used by
    `linearised_position` through the Woodbury identity). Equal to the general formulas
    to rounding; they cost a third of a dense.toml fusion cycle (eigenvalue clip of
    Omega, inverse of S, 2K x 2K solves)."""
    lam, V = np.linalg.eigh(S)
    s = np.sqrt(3.0 * np.maximum(lam, 0.0))
    L = V * s[:, None, :]
    dev = np.concatenate([np.swapaxes(L, 1, 2), -np.swapaxes(L, 1, 2)], axis=1)  # (N, 6, 3)
    at = x[:, None, :] + dev
    at[..., 2] = np.maximum(at[..., 2], z_min)
    d_r = x[:, None, :] - c.rx
    ref_az = np.arctan2(d_r[..., 0], d_r[..., 1])  # azimuths at x
    Y = _predict_meas(at, c, ref_az)
    y_mean = Y.mean(axis=1)
    plus, minus = Y[:, :3] - y_mean[:, None, :], Y[:, 3:] - y_mean[:, None, :]
    inv_s = np.divide(1.0, s, out=np.zeros_like(s), where=s > 0)  # L^-1 = diag(1/s) V'
    A = 0.5 * (np.swapaxes(plus - minus, 1, 2) * inv_s[:, None, :]) @ np.swapaxes(V, 1, 2)
    U = np.swapaxes(plus + minus, 1, 2) / np.sqrt(12.0)
    return y_mean, A, U


def _inv_sym(A: np.ndarray) -> np.ndarray:
    """Inverse of symmetric matrices (N, 3, 3); the pseudo-inverse if one is singular in
    floating point (a degenerate prediction must not stop the whole cycle)."""
    try:
        return np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(A, hermitian=True)


def _information(x: np.ndarray, S: np.ndarray, c: Constraints, z_min: float
                 ) -> tuple[np.ndarray, ...]:
    """One posterior linearisation over N(x, S) (`_slr`): (d (N, 2K) residuals of the
    measurements (azimuths wrapped, 0 in invalid slots), A (N, 2K, 3), U (N, 2K, 3)
    masked, info = A' R_eff^-1 A (N, 3, 3), g = A' R_eff^-1 d (N, 3)), R_eff =
    D + U U' (D = diag(sigma^2), 1 in invalid slots) inverted by Woodbury:
    R_eff^-1 = D^-1 - D^-1 U (I + U' D^-1 U)^-1 U' D^-1 (3x3 solves)."""
    K = c.rb.shape[1]
    mask = np.concatenate([c.valid, c.valid], axis=1).astype(float)
    d_inv = 1.0 / np.where(mask > 0, np.concatenate([c.srb, c.saz], axis=1) ** 2, 1.0)
    y, A, U = _slr(x, S, c, z_min)
    d = np.concatenate([c.rb, c.az], axis=1) - y
    d[:, K:] = wrap_pi(d[:, K:])
    d *= mask
    A = A * mask[..., None]
    U = U * mask[..., None]
    DA, Dd, DU = A * d_inv[..., None], d * d_inv, U * d_inv[..., None]
    Ut = np.swapaxes(U, 1, 2)
    UDA, UDd = Ut @ DA, (Ut @ Dd[..., None])[..., 0]
    CiX = np.linalg.solve(np.eye(3) + Ut @ DU, np.concatenate([UDA, UDd[..., None]], axis=2))
    UDAt = np.swapaxes(UDA, 1, 2)
    info = np.swapaxes(A, 1, 2) @ DA - UDAt @ CiX[..., :3]
    g = (np.swapaxes(A, 1, 2) @ Dd[..., None])[..., 0] - (UDAt @ CiX[..., 3:])[..., 0]
    return d, A, U, info, g


def linearised_position(
    x_pred: np.ndarray, P_pred: np.ndarray, c: Constraints, z_min: float = 0.0,
    iterations: int = 4, floor_sigma: float = 1e5,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Module 64 during tracking: the position measurement of this scan's ranges and
    azimuths, linearised over the posterior given the predicted position.

    Iterated posterior linearisation (Garcia-Fernandez, Svensson, Morelande and
    Sarkka, "Posterior linearization filter", IEEE TSP 2015): starting from the
    prediction N(x_pred, P_pred) (N, 3), (N, 3, 3), the ranges [36] and azimuths are
    replaced by their statistical linear regression over the current posterior N(x, S)
    (`_slr`: h(X) ~ y + A (X - x) + e, cov e = Omega), and the linear-Gaussian update
    with R_eff = diag(sigma^2) + Omega gives the next posterior; `iterations` times.
    At the last linearisation the scan's own information and measurement are
        I = A' R_eff^-1 A,  R = (I + I_3 / floor_sigma^2)^-1,  z = x + R A' R_eff^-1 d,
    d = measurements - y (azimuths wrapped), so that the EKF of module 65, which adds the
    prediction, receives this scan's information only (no inflation; the floor only
    keeps R finite along an axis the scan does not observe). Returns (z (N, 3),
    R (N, 3, 3), chi2 (N,), posterior position (N, 3), loglik (N,)); chi2 = normalised
    squared residuals of the linear model (R_eff) plus the prediction term at the
    posterior, chi-square with 2 x (valid constraints) degrees of freedom; loglik = log
    N(d - A (x_pred - x); 0, A P_pred A' + R_eff), the likelihood of the scan's ranges
    and azimuths under the prediction (invalid slots add the same constant to every
    prediction of a track: used to weigh altitude hypotheses of one track).

    Deviations from 001 (stated): 001 localises each scan by blocks [36]-[41] alone.
    For a low target, z is nearly unobservable in one scan (crossing.toml, 1.5 km at
    40 km: sigma_z ~ 3 km) and the block zone is cut at z >= z_min and curved, so its
    mean [41] is biased upwards by kilometres; the EKF averaged that bias into a
    confident, wrong altitude. A Jacobian at a point estimate (EKF/IEKF) claims the
    slope d r_b / d z of that point, which grows with the height above the sensors'
    plane: with an altitude estimated too high it overstates the z information
    (figures: docs/decisions/011-global-track-filter.md). The regression over
    the posterior uses the slope the data have over the altitudes still credible and
    adds Omega for the curvature it cannot follow, so the information is honest while
    the altitude is uncertain and tends to the Jacobian's once it is known.
    """
    J0 = _inv_sym(P_pred)
    x, S = np.array(x_pred, dtype=float), np.array(P_pred, dtype=float)
    n = x.shape[0]
    act = np.arange(n)
    for _ in range(iterations):
        sub = c if act.size == n else c.take(act)
        _, _, _, info, g = _information(x[act], S[act], sub, z_min)
        info_post = info + J0[act]
        S_new = _inv_sym(info_post)
        step = (S_new @ (g + (J0[act] @ (x_pred[act] - x[act])[..., None])[..., 0])[..., None])[..., 0]
        x_new = x[act] + step
        x_new[:, 2] = np.maximum(x_new[:, 2], z_min)
        step = x_new - x[act]
        x[act], S[act] = x_new, 0.5 * (S_new + np.swapaxes(S_new, 1, 2))
        moved = np.einsum("ni,ni->n", step, (info_post @ step[..., None])[..., 0]) > STEP_TOL
        act = act[moved]
        if act.size == 0:
            break
    d, A, U, info, g = _information(x, S, c, z_min)
    K = c.rb.shape[1]
    Ut = np.swapaxes(U, 1, 2)
    sig2 = np.concatenate([c.srb, c.saz], axis=1) ** 2
    d_inv = 1.0 / np.where(np.concatenate([c.valid, c.valid], axis=1), sig2, 1.0)
    R_eff = U @ Ut + np.eye(2 * K) / d_inv[:, :, None]
    R = _inv_sym(info + np.eye(3) / floor_sigma**2)
    z = x + (R @ g[..., None])[..., 0]
    post = x + (_inv_sym(info + J0) @ (g + (J0 @ (x_pred - x)[..., None])[..., 0])[..., None])[..., 0]
    res = d - (A @ (post - x)[..., None])[..., 0]
    e = post - x_pred
    chi2 = (quadratic_form(res, R_eff)
            + np.einsum("ni,ni->n", e, (J0 @ e[..., None])[..., 0]))
    nu = d - (A @ (x_pred - x)[..., None])[..., 0]
    S = A @ P_pred @ np.swapaxes(A, 1, 2) + R_eff
    nis = quadratic_form(nu, S)
    return z, 0.5 * (R + np.swapaxes(R, 1, 2)), chi2, post, gaussian_loglik(nis, S)
