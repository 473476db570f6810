"""Equivalent measurements of elementary tracks (decorrelation before global fusion).

Complement of 001 step 24 (stated deviation). The seed feeds the elementary tracks'
estimates [r_b, v_b, theta] to modules 63-65 every scan as if they were fresh
measurements. They are Kalman-filtered estimates: their errors are correlated in time,
so treating them as white measurements makes the global covariance far too small (the
global EKF counts every old plot again at every scan). Here each elementary track's
report is turned back into the measurement of this scan alone, by information
differencing of two successive reports (the "equivalent measurement" of track-to-track
fusion):

    x~, P~ = the previous report (t0, x0, P0) predicted to t with F [19] and Q [20]
             of the elementary tracker (same sigma_gamma, sigma_omega);
    G      = P^-1 - P~^-1                       (information gained this scan)
    R_eq   = (G restricted to [r_b, v_b, theta])^-1
    z_eq   = H x~ + R_eq [P^-1 (x - x~)]_[r_b, v_b, theta]   (theta wrapped)

For the linear Kalman filter [25]-[31] with H [22] and full gain, P^-1 = P~^-1 + H' R^-1 H
and P^-1 (x - x~) = H' R^-1 (z - H x~), so (z_eq, R_eq) is exactly the fused plot (z, R)
the tracker used. The innovation form above is the same identity written around x~ (no
cancellation of large r_b values).

No measurement is produced when the report carries no new, exactly recoverable
information: the track was not updated (prediction only), it is ambiguous (004: gain
scaled by alpha < 1, so P^-1 - P~^-1 is no longer H' R^-1 H), G is not of the H' R^-1 H
form (G not positive definite on the measured components, or not zero outside them:
e.g. a missed report in between or a recycled track number), or z_eq is inconsistent
with x~ beyond `gate` (chi-square(3)). A track seen for the first time contributes its
own estimate (x, P) restricted to the measured components, once.

The same differencing serves the range-Doppler tracks of multistatic networks
(common.radar.network): a 3-state track [r_b, v_b, gamma_b] (F, Q the [r_b, v_b,
gamma_b] blocks of [19], [20]) gives z_eq = [r_b, v_b], R_eq 2x2 (`measured`). The
5-state path computes exactly what it computed before (same arrays, same operations).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import quadratic_form
from common.core.motion import bistatic_F, bistatic_Q

IDX = np.array([0, 1, 3])  # [r_b, v_b, theta] in [r_b, v_b, gamma_b, theta, omega]
THETA = 3
RANGE_DOPPLER = IDX[:2]  # [r_b, v_b] in [r_b, v_b, gamma_b]
OFF_TOL = 1e-5  # relative size of G outside the measured block still taken as zero


def measured(n_state: int) -> np.ndarray:
    """Measured components of an elementary state of n_state columns: [r_b, v_b, theta]
    of the 5-state tracks of 001 [18], [r_b, v_b] of the 3-state range-Doppler ones."""
    if n_state == 5:
        return IDX
    if n_state == 3:
        return RANGE_DOPPLER
    raise ValueError(f"elementary states have 3 or 5 columns, not {n_state}")


@dataclass(frozen=True)
class Equivalent:
    """Per elementary track: z (E, m) [r_b, v_b(, theta)], R (E, m, m), ok (E,) a
    measurement of this scan exists (m = 3 for 5-state tracks, 2 for 3-state ones)."""

    z: np.ndarray
    R: np.ndarray
    ok: np.ndarray


def _scaled_inv(P: np.ndarray, d: np.ndarray) -> np.ndarray:
    """inv(P) computed as D inv(D P D) D with D = diag(d) (conditioning)."""
    A = d[:, :, None] * P * d[:, None, :]
    return d[:, :, None] * np.linalg.inv(A) * d[:, None, :]


def equivalent(
    x0: np.ndarray, P0: np.ndarray, dt: np.ndarray, x: np.ndarray, P: np.ndarray,
    sigma_gamma: float, sigma_omega: float, gate: float,
) -> Equivalent:
    """Equivalent measurements (module doc) of N tracks from their previous (x0, P0)
    and current (x, P) elementary states (N, s), (N, s, s), dt (N,) apart, s = 5 or 3
    (the leading blocks of F [19] and Q [20] for s = 3)."""
    n, s = x.shape
    idx = measured(s)
    m = idx.size
    z = np.full((n, m), np.nan)
    R = np.full((n, m, m), np.nan)
    if n == 0:
        return Equivalent(z, R, np.zeros(0, dtype=bool))
    F = bistatic_F(dt)[:, :s, :s]
    xp = (F @ x0[..., None])[..., 0]  # 001 [19], [25]
    Q = bistatic_Q(dt, sigma_gamma, sigma_omega)[:, :s, :s]
    Pp = F @ P0 @ np.swapaxes(F, 1, 2) + Q  # [20], [26]
    d = 1.0 / np.sqrt(np.diagonal(Pp, axis1=1, axis2=2))
    Ii, Ip = _scaled_inv(P, d), _scaled_inv(Pp, d)
    G = Ii - Ip
    Gs = G * (1.0 / d)[:, :, None] * (1.0 / d)[:, None, :]  # in units of P~'s sigmas
    other = np.setdiff1d(np.arange(s), idx)
    g_meas = Gs[:, idx][:, :, idx]
    scale = np.abs(g_meas).max(axis=(1, 2))
    off = np.abs(Gs[:, other]).max(axis=(1, 2))
    Gm = G[:, idx][:, :, idx]
    Gm = 0.5 * (Gm + np.swapaxes(Gm, 1, 2))
    ok = (np.linalg.eigvalsh(g_meas)[:, 0] > 1e-9 * np.maximum(scale, 1e-300)) & (off <= OFF_TOL * scale)
    if not ok.any():
        return Equivalent(z, R, ok)
    k = np.flatnonzero(ok)
    Rk = np.linalg.inv(Gm[k])
    dx = x[k] - xp[k]
    if m == 3:
        dx[:, THETA] = wrap_pi(dx[:, THETA])
    v = (Rk @ (Ii[k] @ dx[..., None])[:, idx])[..., 0]  # z_eq - H x~
    S = Pp[k][:, idx][:, :, idx] + Rk
    nis = quadratic_form(v, S)
    z[k] = xp[k][:, idx] + v
    if m == 3:
        z[k, 2] = wrap_2pi(z[k, 2])
    R[k] = Rk
    ok[k] = nis <= gate
    z[~ok], R[~ok] = np.nan, np.nan
    return Equivalent(z, R, ok)


class Decorrelator:
    """Last report (t, x, P) of every elementary track per base; `step` turns the
    report of one base at time t into equivalent measurements (module doc)."""

    def __init__(self, sigma_gamma: float, sigma_omega: float, gate: float) -> None:
        self.sigma_gamma = sigma_gamma
        self.sigma_omega = sigma_omega
        self.gate = gate
        self.last: dict[int, tuple[float, np.ndarray, np.ndarray, np.ndarray]] = {}

    def step(self, base: int, t: float, ids: np.ndarray, x: np.ndarray, P: np.ndarray,
             updated: np.ndarray, ambiguous: np.ndarray) -> Equivalent:
        """The report of base `base` at t: track numbers (E,), states (E, s), (E, s, s)
        (s = 5 or 3), flags (E,). Tracks absent from the report are forgotten."""
        return self.step_bases(t, [base], np.full(ids.size, base), ids, x, P, updated, ambiguous)

    def step_bases(self, t: float, reported: list[int], base: np.ndarray, ids: np.ndarray,
                   x: np.ndarray, P: np.ndarray, updated: np.ndarray, ambiguous: np.ndarray
                   ) -> Equivalent:
        """`step` for the reports at t of the bases `reported`, row k of base base[k]
        (E,): one `equivalent` over all of them (per-row arithmetic: the same values)."""
        n = ids.size
        idx = measured(x.shape[1])
        z = np.full((n, idx.size), np.nan)
        R = np.full((n, idx.size, idx.size), np.nan)
        ok = np.zeros(n, dtype=bool)
        seen = np.zeros(n, dtype=bool)
        rows, x0, P0, dt = [], [], [], []
        for b in reported:
            k = np.flatnonzero(base == b)
            prev = self.last.get(b)
            if prev is not None and prev[1].size:
                t_b, ids0, x_b, P_b = prev
                order = np.argsort(ids0)
                j = order[np.clip(np.searchsorted(ids0[order], ids[k]), 0, ids0.size - 1)]
                seen[k] = (ids0[j] == ids[k]) & (t > t_b)
                use = np.flatnonzero(seen[k] & updated[k] & ~ambiguous[k])
                rows.append(k[use])
                x0.append(x_b[j[use]])
                P0.append(P_b[j[use]])
                dt.append(np.full(use.size, t - t_b))
            self.last[b] = (t, ids[k].copy(), x[k].copy(), P[k].copy())
        if rows:
            use = np.concatenate(rows)
            eq = equivalent(np.concatenate(x0), np.concatenate(P0), np.concatenate(dt), x[use],
                            P[use], self.sigma_gamma, self.sigma_omega, self.gate)
            z[use], R[use], ok[use] = eq.z, eq.R, eq.ok
        first = ~seen & updated & ~ambiguous
        z[first] = x[first][:, idx]
        R[first] = P[first][:, idx][:, :, idx]
        ok[first] = True
        return Equivalent(z, R, ok)
