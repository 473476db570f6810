"""Discrete-time motion models: transition F(T) and process noise Q(T).

T is a scalar (returns (n, n)) or an array of N time steps (returns (N, n, n)), so tracks
updated at different times can be predicted in one batch. Noise parameters broadcast
against T the same way.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def _cv_block(T: np.ndarray) -> np.ndarray:
    """F of one [position, rate] pair: [[1, T], [0, 1]], shape T.shape + (2, 2)."""
    F = np.zeros(T.shape + (2, 2))
    F[..., 0, 0] = F[..., 1, 1] = 1.0
    F[..., 0, 1] = T
    return F


def _cwna_block(T: np.ndarray) -> np.ndarray:
    """Integrated white-noise rate block [[T^3/3, T^2/2], [T^2/2, T]] (unit power)."""
    Q = np.empty(T.shape + (2, 2))
    Q[..., 0, 0] = T**3 / 3.0
    Q[..., 0, 1] = Q[..., 1, 0] = T**2 / 2.0
    Q[..., 1, 1] = T
    return Q


def _block_diag(*blocks: np.ndarray) -> np.ndarray:
    """Block-diagonal stack of batched square blocks sharing leading axes."""
    lead = np.broadcast_shapes(*(b.shape[:-2] for b in blocks))
    n = sum(b.shape[-1] for b in blocks)
    out = np.zeros(lead + (n, n))
    i = 0
    for b in blocks:
        k = b.shape[-1]
        out[..., i : i + k, i : i + k] = b
        i += k
    return out


def _scale(power: ArrayLike) -> np.ndarray:
    """Noise power as an array broadcastable against (..., n, n)."""
    return np.asarray(power, dtype=float)[..., None, None]


def bistatic_F(T: ArrayLike) -> np.ndarray:
    """001 [19]: state [r_b, v_b, gamma_b, theta, omega]; constant bistatic
    acceleration on (r_b, v_b, gamma_b), constant azimuth rate on (theta, omega)."""
    T = np.asarray(T, dtype=float)
    F = np.zeros(T.shape + (5, 5))
    F[..., range(5), range(5)] = 1.0
    F[..., 0, 1] = F[..., 1, 2] = T
    F[..., 0, 2] = T**2 / 2.0
    F[..., 3, 4] = T
    return F


def bistatic_Q(T: ArrayLike, sigma_gamma: ArrayLike, sigma_omega: ArrayLike) -> np.ndarray:
    """001 [20]: sigma_gamma^2 * white-jerk block on (r_b, v_b, gamma_b)
    + sigma_omega^2 * white angular-acceleration block on (theta, omega).
    sigma_gamma, sigma_omega are the standard deviations as written in the seed."""
    T = np.asarray(T, dtype=float)
    Qg = np.empty(T.shape + (3, 3))
    Qg[..., 0, 0] = T**5 / 20.0
    Qg[..., 0, 1] = Qg[..., 1, 0] = T**4 / 8.0
    Qg[..., 0, 2] = Qg[..., 2, 0] = T**3 / 6.0
    Qg[..., 1, 1] = T**3 / 3.0
    Qg[..., 1, 2] = Qg[..., 2, 1] = T**2 / 2.0
    Qg[..., 2, 2] = T
    return _block_diag(
        _scale(np.square(sigma_gamma)) * Qg,
        _scale(np.square(sigma_omega)) * _cwna_block(T),
    )


def cv_F(T: ArrayLike) -> np.ndarray:
    """001 [51]: 6-state constant velocity, state ordering [x, vx, y, vy, z, vz]."""
    b = _cv_block(np.asarray(T, dtype=float))
    return _block_diag(b, b, b)


def cv_Q(T: ArrayLike, q: ArrayLike, q_z: ArrayLike | None = None) -> np.ndarray:
    """Q of 001 [51]: q * [[T^3/3, T^2/2], [T^2/2, T]] on (x, vx) and (y, vy), q_z * the
    same block on (z, vz).

    q = sigma_vxy^2 and q_z = sigma_vz^2 of the seed (noise powers, m^2/s^3); q_z defaults
    to q. Deviation: the seed prints the sigma_vz^2 block on rows/columns 4-5 (vy, z) with
    an empty last row, which breaks the [x vx y vy z vz] ordering it states and would put
    position noise on vy; we place it on (z, vz), rows/columns 5-6, as the model intends.
    """
    T = np.asarray(T, dtype=float)
    b = _cwna_block(T)
    q_z = q if q_z is None else q_z
    return _block_diag(_scale(q) * b, _scale(q) * b, _scale(q_z) * b)


def bearing_F(T: ArrayLike) -> np.ndarray:
    """Seed 000 straight-line-segment model: state [brg, brg_rate, amp, amp_rate]."""
    b = _cv_block(np.asarray(T, dtype=float))
    return _block_diag(b, b)


def bearing_Q(T: ArrayLike, q_theta: ArrayLike, q_a: ArrayLike) -> np.ndarray:
    """Seed 000 Q = diag(q_theta * B(T), q_a * B(T)), B = [[f1, f2], [f2, f3]].

    f1 = T^3/3 and f3 = T as in the seed. Deviation: the seed prints f2(T) = T^2/3; we use
    T^2/2, the exact cross term of integrated white noise (the model f1 and f3 come from,
    and the value in 001 [20]); with T^2/3 the matrix is not the covariance of any
    white-noise rate process.
    """
    T = np.asarray(T, dtype=float)
    b = _cwna_block(T)
    return _block_diag(_scale(q_theta) * b, _scale(q_a) * b)


def bearing_freq_F(T: ArrayLike) -> np.ndarray:
    """Narrowband (LOFAR/DEMON) model of seed 000: [brg, brg_rate, amp, amp_rate,
    freq, freq_rate]. Deviation: the seed lists [brg, brg_rate, freq, freq_rate, amp,
    amp_rate]; we append the frequency pair so the broadband state is a prefix (same
    H/indices for both variants). F is block-diagonal, so only the ordering differs."""
    b = _cv_block(np.asarray(T, dtype=float))
    return _block_diag(b, b, b)


def bearing_freq_Q(
    T: ArrayLike, q_theta: ArrayLike, q_a: ArrayLike, q_f: ArrayLike
) -> np.ndarray:
    """Seed 000 Q completed with a frequency block q_f * B(T) (same B as bearing_Q),
    ordering as in bearing_freq_F."""
    T = np.asarray(T, dtype=float)
    b = _cwna_block(T)
    return _block_diag(_scale(q_theta) * b, _scale(q_a) * b, _scale(q_f) * b)
