"""The state of a global track as a Gaussian sum: altitude bands x motion models.

Every track carries K = A x M components, component k = a M + m: altitude band a
(common.radar.fusion.initiation.altitude_bands says why a low target needs several) and motion
model m of the IMM (common.core.imm; module doc of common.radar.fusion.cycle). Arrays over
tracks: mu (N, K) weights (0 = dead component), xm (N, K, 6), Pm (N, K, 6, 6).
The IMM mixes the models within each band only, so that a band keeps its mass in
the prediction and changes it by the likelihood of the scans alone; a band whose
mass falls below `prune` is dropped, and two bands whose altitudes agree within
`merge_sigma` of their spread are merged (moment matching, per model), so that a
track whose altitude is resolved costs one band.
"""

from __future__ import annotations

import numpy as np

from common.core import imm
from common.radar.fusion import ekf as global_ekf


def bands(a: np.ndarray, A: int) -> np.ndarray:
    """View of a per-component array (N, K, ...) as (N, A, M, ...)."""
    return a.reshape(a.shape[0], A, a.shape[1] // A, *a.shape[2:])


def predict(mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray, dt: np.ndarray, A: int,
            sojourn: np.ndarray, q: np.ndarray, q_z: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IMM mixing within each band and [55]-[56] per live component with the noise q (M,)
    of its model: (c (N, K) predicted weights, xm, Pm predicted)."""
    N, K = mu.shape
    M = K // A
    p = np.repeat(imm.transition(dt, sojourn), A, axis=0)  # (N * A, M, M)
    w = mu.reshape(N * A, M)
    c, x0, P0 = np.zeros((N * A, M)), np.zeros((N * A, M, 6)), np.zeros((N * A, M, 6, 6))
    band = np.flatnonzero(w.sum(axis=1) > 0)  # a dead band mixes to zeros: left out
    c[band], x0[band], P0[band] = imm.mix(w[band], xm.reshape(N * A, M, 6)[band],
                                          Pm.reshape(N * A, M, 6, 6)[band], p[band])
    c, x0, P0 = c.reshape(N, K), x0.reshape(N, K, 6), P0.reshape(N, K, 6, 6)
    ti, ki = np.nonzero(c > 0)
    x0[ti, ki], P0[ti, ki] = global_ekf.predict(x0[ti, ki], P0[ti, ki], dt[ti], q[ki % M], q_z)
    return c, x0, P0


def band_moments(mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray, A: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass (N, A) and moment-matched mean (N, A, 6) and covariance (N, A, 6, 6) of
    every band (zeros for a dead band)."""
    N, K = mu.shape
    M = K // A
    w = mu.reshape(N * A, M)
    mass = w.sum(axis=1)
    x, P = np.zeros((N * A, 6)), np.zeros((N * A, 6, 6))
    k = np.flatnonzero(mass > 0)
    x[k], P[k] = imm.combine(w[k] / np.maximum(mass[k], 1e-300)[:, None],
                             xm.reshape(N * A, M, 6)[k], Pm.reshape(N * A, M, 6, 6)[k])
    return mass.reshape(N, A), x.reshape(N, A, 6), P.reshape(N, A, 6, 6)


def reweight(c: np.ndarray, band_loglik: np.ndarray, comp_loglik: np.ndarray, A: int
             ) -> np.ndarray:
    """Weights after a scan: band masses by the band log-likelihoods (N, A) of the
    scan's raw measurements, models within a band by the components' log-likelihoods
    (N, K) of the band's measurement (0 where a component was not updated):
    mu_am = P(a) P(m | a), P(a) ~ mass_a L_a, P(m | a) ~ c_am L_am."""
    N, K = c.shape
    M = K // A
    cb = c.reshape(N, A, M)
    mass = cb.sum(axis=2)
    with np.errstate(divide="ignore"):
        la = np.where(mass > 0, np.log(mass) + band_loglik, -np.inf)
    pa = np.exp(la - la.max(axis=1, keepdims=True))
    pa /= pa.sum(axis=1, keepdims=True)
    within = imm.probabilities(cb.reshape(N * A, M), comp_loglik.reshape(N * A, M))
    within = np.where(mass.reshape(N * A, 1) > 0, within, 0.0)
    return (pa[:, :, None] * within.reshape(N, A, M)).reshape(N, K)


def prune_merge(mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray, A: int, prune: float,
                merge_sigma: float, linear: float, z_ref: float) -> np.ndarray:
    """Drop bands of mass < prune, then merge each band into the nearest live band below
    it when their mean altitudes differ by less than merge_sigma * sqrt(var_a + var_b)
    and both are linear: sigma_z < linear * (z - z_ref), z_ref the receiver's altitude
    (before that a merged band would be one Gaussian in a flat-bottomed likelihood
    again). Moment matching per model; in place for xm, Pm; returns mu."""
    N, K = mu.shape
    M = K // A
    mu = mu.reshape(N, A, M).copy()
    mu[mu.sum(axis=2) < prune] = 0.0
    xb, Pb = bands(xm, A), bands(Pm, A)
    rows = np.flatnonzero((mu.sum(axis=2) > 0).sum(axis=1) >= 2)
    prev = np.full(rows.size, -1)
    _, zm, Pz = band_moments(mu[rows].reshape(rows.size, K), xm[rows], Pm[rows], A)
    zm, vz = zm[..., 4], Pz[..., 4, 4]  # altitude moments of the bands of `rows`, (n, A)
    for b in range(A):
        live = mu[rows, b].sum(axis=1) > 0
        k = np.flatnonzero(live & (prev >= 0))
        if k.size:
            r, a = rows[k], prev[k]
            z = np.stack([zm[k, a], zm[k, b]], axis=1)
            sz = np.sqrt(np.stack([vz[k, a], vz[k, b]], axis=1))
            ok = (np.all(sz < linear * (z - z_ref), axis=1)
                  & (np.abs(z[:, 0] - z[:, 1]) < merge_sigma * np.sqrt((sz**2).sum(axis=1))))
            r, a = r[ok], a[ok]
            w = np.stack([mu[r, a], mu[r, b]], axis=2)  # (n, M, 2): per model
            tot = w.sum(axis=2)
            wn = (w / np.maximum(tot, 1e-300)[..., None]).reshape(-1, 2)
            x, P = imm.combine(wn, np.stack([xb[r, a], xb[r, b]], axis=2).reshape(-1, 2, 6),
                               np.stack([Pb[r, a], Pb[r, b]], axis=2).reshape(-1, 2, 6, 6))
            xb[r, a], Pb[r, a] = x.reshape(-1, M, 6), P.reshape(-1, M, 6, 6)
            mu[r, a], mu[r, b] = tot, 0.0
            if r.size:
                _, xa, Pa = band_moments(mu[r, a], xb[r, a], Pb[r, a], 1)
                zm[k[ok], a], vz[k[ok], a] = xa[:, 0, 4], Pa[:, 0, 4, 4]
            live[k[ok]] = False  # merged: the band below stays the reference
        prev = np.where(live, b, prev)
    mu = mu.reshape(N, K)
    return mu / mu.sum(axis=1, keepdims=True)
