"""Module 62 of 001: initialisation of global tracks from two elementary tracks of two
different bases, in five steps each gating the next (001 step 24):

1. azimuth coherence: |theta_i - theta_j| <= a fixed value (`azimuth_pairs`, a sorted
   search, so candidate pairs are found without forming all pairs);
2. range coherence: coarse analytic ellipse intersection [32]-[35]
   (`coarse_intersection`), then fine localisation by blocks [36]-[41]
   (common.radar.geometry.localisation);
3. velocity coherence: (vx, vy) from the 2x2 system [42]-[43] (`pair_velocity`),
   rejected above a maximum speed;
4. initial state and covariance [44]-[46] (`initial_state`);
5. extension with the other bases: done by the caller through module 63
   (common.radar.fusion.assoc); `select` picks a conflict-free set of candidates.

Frame: [32]-[35] are written in the receiver-centred frame with transmitters coplanar
with the receiver; the project's azimuth is clockwise from North, so [34] becomes
x = rho sin(theta) cos(phi), y = rho cos(theta) cos(phi) (the seed's cos/sin are for an
angle counter-clockwise from East; cos(theta - theta_i) is the same in both).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from common.core.angles import TWO_PI, wrap_2pi, wrap_pi
from common.core.params import INF, Params, Range, Rule, count, non_negative, order, positive, unbounded
from common.radar.geometry.localisation import Constraints, block_localise, gauss_newton, residuals

_ALTITUDE = "height in the deployment's frame (its origin is the file's choice)"


@dataclass(frozen=True)
class InitParams(Params):
    """Thresholds of module 62.

    az_gate_deg: test 1, maximum azimuth difference of the two elementary tracks.
    cos_tol: test 2 (coarse), accepted excess of cos(phi) [33] over 1 (noise).
    max_elevation_deg: test 2 (coarse), cos(phi) must be >= cos(max elevation).
    k_sigma, z_min, z_max: test 2 (fine), blocks within k sigma and altitude bounds (m).
    init_block_levels, init_box_sigma: test 2 (fine), number of 2x2x2 subdivisions of
        the search box and its half-width in sigmas of the Gauss-Newton covariance
        (two ellipsoids: a curved, elongated zone, hence finer and wider than in
        tracking).
    v_max: test 3, maximum speed (m/s).
    sigma_vz: the constant sigma of v_z in [45] (m/s).
    z_prior_mean, z_prior_sigma: altitude prior (m) of the fine localisation, a
        pseudo-measurement z ~ N(mean, sigma^2) (not in 001; common.radar.geometry.localisation says
        why); z_prior_sigma <= 0 switches it off. Not used by filter = "seed".
    alt_bands, alt_band_low, alt_band_ratio: the initial state is a Gaussian sum over
        this many altitude bands, centred at z_min + low * ratio^a (m) with sigma
        (ratio - 1) / 2 times the centre (`altitude_bands`); one band still imposes
        its altitude prior. Not used by filter = "seed".
    """

    az_gate_deg: float = 3.0
    cos_tol: float = 0.05
    max_elevation_deg: float = 60.0
    k_sigma: float = 3.0
    init_block_levels: int = 4
    init_box_sigma: float = 6.0
    z_min: float = 0.0
    z_max: float = 20000.0
    v_max: float = 400.0
    sigma_vz: float = 10.0
    z_prior_mean: float = 6000.0
    z_prior_sigma: float = 4000.0
    alt_bands: int = 9
    alt_band_low: float = 300.0
    alt_band_ratio: float = 1.6

    RANGES: ClassVar[dict[str, Range]] = {
        "az_gate_deg": Range("deg", 0.0, 180.0, "(]"), "cos_tol": non_negative(),
        "max_elevation_deg": Range("deg", 0.0, 90.0, "(]"), "k_sigma": positive("sigma"),
        "init_block_levels": count(0), "init_box_sigma": positive("sigma"),
        "z_min": unbounded("m", _ALTITUDE), "z_max": unbounded("m", _ALTITUDE),
        "v_max": positive("m/s"), "sigma_vz": positive("m/s"),
        "z_prior_mean": unbounded("m", _ALTITUDE), "z_prior_sigma": positive("m"),
        "alt_bands": count(1), "alt_band_low": positive("m"),
        "alt_band_ratio": Range("", 1.0, INF, "()"),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (order("z_min", "z_max"),)

    @property
    def z_prior(self) -> tuple[float, float] | None:
        """(mean, sigma) of the altitude prior, or None when switched off."""
        return (self.z_prior_mean, self.z_prior_sigma) if self.z_prior_sigma > 0 else None


def azimuth_pairs(az_a: np.ndarray, az_b: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """Test 1 for all pairs at once: indices (ia, ib) with |wrap(az_a - az_b)| <= gate.

    az_b is sorted once (with copies shifted by +-2 pi for the wrap) and each az_a finds
    its window by binary search: O((A + B) log B + pairs), no A x B matrix.
    """
    order = np.argsort(az_b)
    s = az_b[order]
    ext = np.concatenate([s - TWO_PI, s, s + TWO_PI])
    idx = np.concatenate([order, order, order])
    lo = np.searchsorted(ext, az_a - gate, "left")
    hi = np.searchsorted(ext, az_a + gate, "right")
    count = np.maximum(hi - lo, 0)
    ia = np.repeat(np.arange(az_a.size), count)
    offs = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    ib = idx[np.repeat(lo, count) + offs]
    keep = np.abs(wrap_pi(az_a[ia] - az_b[ib])) <= gate
    return ia[keep], ib[keep]


def coarse_intersection(
    rb_i: np.ndarray, rb_j: np.ndarray, az: np.ndarray,
    L_i: np.ndarray, L_j: np.ndarray, az_tx_i: np.ndarray, az_tx_j: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """001 [32]-[35]: (position relative to the receiver (P, 3), cos(phi) (P,)).

    rb: bistatic ranges, az: mean azimuth theta~, L: transmitter-receiver distances,
    az_tx: azimuths of the transmitters from the receiver. cos(phi) is returned
    unclipped (> 1: the ellipsoids do not meet in this azimuth); the position uses
    cos(phi) clipped to [0, 1].
    """
    ci = L_i * np.cos(az - az_tx_i)
    cj = L_j * np.cos(az - az_tx_j)
    ai = rb_i**2 - L_i**2
    aj = rb_j**2 - L_j**2
    with np.errstate(divide="ignore", invalid="ignore"):
        cos_phi = (2 * ai * rb_j - 2 * aj * rb_i) / (2 * ai * cj - 2 * aj * ci)  # 001 [33]
        rho = (ai * cj - aj * ci) / (2 * rb_i * cj - 2 * rb_j * ci)  # 001 [35]
    c = np.clip(cos_phi, 0.0, 1.0)
    s = np.sqrt(1.0 - c**2)
    pos = np.stack([rho * np.sin(az) * c, rho * np.cos(az) * c, rho * s], axis=-1)  # [34]
    return pos, cos_phi


def pair_velocity(
    pos: np.ndarray, vb: np.ndarray, svb: np.ndarray, tx: np.ndarray, rx: np.ndarray,
    valid: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """001 [42]-[43] and [46]: (vx, vy) (P, 2) and its covariance (P, 2, 2).

    pos (P, 3); vb, svb (P, 2) bistatic velocities and sigmas of the two tracks;
    tx (P, 2, 3), rx (P, 2, 3). Row k of A [43] is the (x, y) part of u_T + u_R of base
    k (v_z neglected, as in the seed). The seed prints the y entries of [43] over
    ||y - y_T||; the gradient of r_b (and [2]) has the 3-D norms, used here.
    valid (P, K): K >= 2 bases of which these rows count (common.radar.fusion.reopen);
    then the weighted least squares solution of the K rows of [42], its covariance the
    inverse information (for two valid rows the same as [42] and [46]).
    """
    d_t = pos[:, None, :] - tx
    d_r = pos[:, None, :] - rx
    g = d_t / np.linalg.norm(d_t, axis=-1, keepdims=True) + d_r / np.linalg.norm(
        d_r, axis=-1, keepdims=True
    )
    A = g[..., :2]  # 001 [43]
    if valid is not None:
        w = np.where(valid, 1.0 / svb**2, 0.0)
        cov = np.linalg.inv(np.einsum("pki,pk,pkj->pij", A, w, A))
        return np.einsum("pij,pkj,pk->pi", cov, A, w * np.where(valid, vb, 0.0)), cov
    v = np.linalg.solve(A, vb[..., None])[..., 0]  # 001 [42]
    A_inv = np.linalg.inv(A)
    cov = A_inv @ (svb[..., None] ** 2 * np.eye(2)) @ np.swapaxes(A_inv, 1, 2)  # 001 [46]
    return v, cov


def initial_state(
    pos: np.ndarray, pos_cov: np.ndarray, v: np.ndarray, v_cov: np.ndarray, sigma_vz: float,
    decouple_z: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """001 [44]-[45]: x = [x vx y vy z 0], P with the block covariance [41] on
    (x, y, z), [46] on (vx, vy), sigma_vz^2 on vz and no position-velocity terms.

    Deviation (stated): the z-(x, y) covariances of [41] are set to zero. The block zone
    of two bases is a curved arc; its linear x-z / y-z regression is far from the local
    slope at the target, so once (x, y) are pinned by the next scans the EKF dragged z
    along the wrong slope with a small variance (crossing.toml, 1.5 km target: z 1.5 km
    off with sigma 0.3 km). Without them z is corrected by the scans' own local
    information only. decouple_z=False keeps them: an altitude band of
    `altitude_bands` is narrow enough for its local slope to be right, and the seed's
    path (`pair_candidates` with seed=True) keeps [45] as written."""
    n = pos.shape[0]
    x = np.zeros((n, 6))
    x[:, [0, 2, 4]] = pos
    x[:, [1, 3]] = v  # 001 [44]
    P = np.zeros((n, 6, 6))
    P[:, [0, 2, 4], [[0], [2], [4]]] = np.swapaxes(pos_cov, 1, 2)
    P[:, [1, 3], [[1], [3]]] = np.swapaxes(v_cov, 1, 2)
    P[:, 5, 5] = sigma_vz**2  # 001 [45]
    if decouple_z:
        P[:, 4, [0, 2]] = P[:, [0, 2], 4] = 0.0  # z decoupled from (x, y) (docstring)
    return x, P


@dataclass(frozen=True)
class Candidates:
    """Pairs that passed tests 1-3, with their initial state (step 4).

    rows (C, 2): the two elementary tracks (rows of the cycle's ETrackSet);
    x (C, 6), P (C, 6, 6); cost (C,): normalised squared residual of the ranges and
    azimuths at the located position (smaller is more likely).
    """

    rows: np.ndarray
    x: np.ndarray
    P: np.ndarray
    cost: np.ndarray


def pair_candidates(
    y: np.ndarray, R: np.ndarray, base: np.ndarray, ia: np.ndarray, ib: np.ndarray,
    tx: np.ndarray, rx: np.ndarray, p: InitParams, seed: bool = False,
) -> Candidates:
    """Tests 2 and 3 and step 4 for candidate pairs (ia, ib) of elementary tracks.

    y (E, 3) [r_b, v_b, theta] and R (E, 3, 3) of the elementary tracks, base (E,) their
    base index into tx, rx (B, 3). The bases share the receiver (001: one receiver).
    seed: 001 as written ([radar.fusion] filter = "seed"): blocks [36]-[41] without the
    altitude prior, and [45] with the z-(x, y) covariances of [41] (`initial_state`).
    """
    rows = np.stack([ia, ib], axis=1)
    bi, bj = base[ia], base[ib]
    base_vec = tx - rx
    L = np.linalg.norm(base_vec, axis=1)
    az_tx = np.arctan2(base_vec[:, 0], base_vec[:, 1])
    az = wrap_2pi(y[ia, 2] + 0.5 * wrap_pi(y[ib, 2] - y[ia, 2]))
    rel, cos_phi = coarse_intersection(y[ia, 0], y[ib, 0], az, L[bi], L[bj], az_tx[bi], az_tx[bj])
    ok = (cos_phi <= 1.0 + p.cos_tol) & (cos_phi >= np.cos(np.radians(p.max_elevation_deg)))
    ok &= np.isfinite(rel).all(axis=1)  # test 2, coarse
    rows, rel, bi, bj = rows[ok], rel[ok], bi[ok], bj[ok]
    pb = np.stack([bi, bj], axis=1)
    sig = np.sqrt(np.diagonal(R, axis1=1, axis2=2))
    c = Constraints(y[rows, 0], sig[rows, 0], y[rows, 2], sig[rows, 2],
                    np.ones(rows.shape, bool), tx[pb], rx[pb])
    x0 = rx[bi] + rel
    x0[:, 2] = np.clip(x0[:, 2], p.z_min, p.z_max)
    z_prior = None if seed else p.z_prior
    xg, Cg = gauss_newton(x0, c, z_min=p.z_min, z_prior=z_prior)
    pos, cov, nb = block_localise(xg, Cg, c, p.k_sigma, p.init_block_levels, p.z_min, p.z_max,
                                  p.init_box_sigma, z_prior=z_prior)  # 001 [36]-[41]
    ok = nb > 0  # test 2, fine: the two ellipsoids meet within k sigma
    rows, pos, cov, pb = rows[ok], pos[ok], cov[ok], pb[ok]
    c = c.take(np.flatnonzero(ok))
    v, v_cov = pair_velocity(pos, y[rows, 1], sig[rows, 1], tx[pb], rx[pb])
    ok = np.hypot(v[:, 0], v[:, 1]) <= p.v_max  # test 3
    x, P = initial_state(pos[ok], cov[ok], v[ok], v_cov[ok], p.sigma_vz,
                         decouple_z=not seed)  # 001 [44]-[46]
    c = c.take(np.flatnonzero(ok))
    res_rb, res_az, _ = residuals(pos[ok], c)
    cost = np.sum((res_rb / c.srb) ** 2 + (res_az / c.saz) ** 2, axis=1)
    return Candidates(rows[ok], x, P, cost)


def altitude_bands(
    pos: np.ndarray, y: np.ndarray, R: np.ndarray, base: np.ndarray, rows: np.ndarray,
    tx: np.ndarray, rx: np.ndarray, p: InitParams, evidence: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Initial state of new tracks as a Gaussian sum over altitude bands (complement of
    001 [44]-[46], stated): (x (W, A, 6), P (W, A, 6, 6), weights (W, A)).

    Why: for a low target the two ellipsoids meet along a curved arc and the likelihood
    of the scans is Gaussian in (z - z_rx)^2, flat-bottomed in z; a single Gaussian in z
    settles against the steep side of that likelihood and claims an altitude it does
    not have, whatever the linearisation (docs/decisions/011-global-track-filter.md).
    Band a has the altitude prior
    N(z_a, s_a^2), z_a = z_min + low ratio^a, s_a = (ratio - 1) z_a / 2: a constant
    ratio of spread to altitude, as the range-parametrised filters of bearings-only
    tracking (Peach 1995), since the likelihood is curved in z^2 and a band is
    linear only if its spread is small against its altitude; its position is the
    Gauss-Newton solution (common.radar.geometry.localisation) of the two elementary tracks' ranges
    and azimuths with that prior, started at the located position `pos` (W, 3) moved
    to z_a; its covariance is that of Gauss-Newton with its z-(x, y) terms (the band
    is narrow enough to be linear); velocity [42]-[43] and [46] at the band's position.
    Weights: equal (a prior uniform in log-altitude from z_a of the first to the last
    band); the scans' equivalent measurements weigh the bands from the next cycle on
    (common.radar.fusion.mixture). The evidence of the two elementary estimates is not used:
    just after confirmation their covariance is not reliable enough to weigh altitudes
    (one elementary track's azimuth error can take the true band out at the first
    cycle: docs/decisions/011-global-track-filter.md). evidence=True (a
    track rebuilt from mature elementary tracks, common.radar.fusion.reopen): weights
    by the Laplace evidence of each band, log w_a = -J_a / 2 + log det(C_a) / 2 - log s_a
    (J_a: the least-squares cost of the ranges, azimuths and altitude prior at the band's
    solution, C_a its covariance), normalised.
    rows (W, 2): the two elementary tracks (rows of y, R, base); or (W, K) with -1 for
    none, at least two valid per row (common.radar.fusion.reopen: velocity by least
    squares over the valid rows, `pair_velocity`)."""
    W, A = rows.shape[0], p.alt_bands
    z_a = p.z_min + p.alt_band_low * p.alt_band_ratio ** np.arange(A)
    s_a = 0.5 * (p.alt_band_ratio - 1.0) * z_a
    sig = np.sqrt(np.diagonal(R, axis1=1, axis2=2))
    valid = rows >= 0
    pb = base[rows]
    c = Constraints(y[rows, 0], sig[rows, 0], y[rows, 2], sig[rows, 2],
                    valid, tx[pb], rx[pb]).take(np.repeat(np.arange(W), A))
    x0 = np.repeat(pos, A, axis=0)
    zc, sc = np.tile(z_a, W), np.tile(s_a, W)
    x0[:, 2] = zc
    xs, Cs = gauss_newton(x0, c, z_min=p.z_min, z_prior=(zc, sc))
    v, v_cov = pair_velocity(xs, np.repeat(y[rows, 1], A, axis=0), np.repeat(sig[rows, 1], A, axis=0),
                             tx[np.repeat(pb, A, axis=0)], rx[np.repeat(pb, A, axis=0)],
                             None if valid.shape[1] == 2 and valid.all() else np.repeat(valid, A, axis=0))
    x, P = initial_state(xs, Cs, v, v_cov, p.sigma_vz, decouple_z=False)
    w = np.full((W, A), 1.0 / A)
    if evidence:
        res_rb, res_az, _ = residuals(xs, c)
        cost = np.sum(np.where(c.valid, (res_rb / c.srb) ** 2 + (res_az / c.saz) ** 2, 0.0), axis=1)
        cost += ((xs[:, 2] - zc) / sc) ** 2
        logw = (-0.5 * cost + 0.5 * np.linalg.slogdet(Cs)[1] - np.log(sc)).reshape(W, A)
        w = np.exp(logw - logw.max(axis=1, keepdims=True))
        w /= w.sum(axis=1, keepdims=True)
    return x.reshape(W, A, 6), P.reshape(W, A, 6, 6), w


def select(members: np.ndarray, priority: np.ndarray) -> np.ndarray:
    """Conflict-free subset of candidates, best priority first (greedy, vectorised).

    members (C, K) elementary-track rows of each candidate (-1 = none), priority (C,)
    smaller is better. A candidate is accepted when it is the best remaining candidate
    of every elementary track it uses (rounds of such "locally best" candidates give
    the sequential greedy result). Returns the accepted candidate indices.
    """
    C = members.shape[0]
    order = np.argsort(priority, kind="stable")
    rank = np.empty(C, dtype=np.intp)
    rank[order] = np.arange(C)
    cand = np.repeat(np.arange(C), members.shape[1])
    et = members.ravel()
    has = et >= 0
    cand, et = cand[has], et[has]
    live = np.ones(C, dtype=bool)
    accepted = np.zeros(C, dtype=bool)
    n_et = int(et.max()) + 1 if et.size else 0
    while live.any():
        lv = live[cand]
        best = np.full(n_et, C, dtype=np.intp)
        np.minimum.at(best, et[lv], rank[cand[lv]])
        is_best = best[et] == rank[cand]
        bad = np.zeros(C, dtype=bool)
        bad[cand[~is_best]] = True
        win = live & ~bad
        accepted |= win
        taken = np.zeros(n_et, dtype=bool)
        taken[et[win[cand]]] = True
        lose = np.zeros(C, dtype=bool)
        lose[cand[taken[et]]] = True
        live &= ~lose & ~win
    return np.flatnonzero(accepted)
