"""Batched linear / extended Kalman filter steps over N tracks.

Shapes: x (N, n), P (N, n, n), z (N, m). Model matrices F, Q (n, n) are shared by all
tracks, or (N, n, n) per track; likewise H (m, n) or (N, m, n), R (m, m) or (N, m, m).
Equations: seed 001 [25]-[31] (linear KF) and [55]-[62] (EKF with a pre-evaluated h and
Jacobian H); seed 000 Joseph-form covariance update; seed 004 eq. 11 gain weight alpha.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from common.core.angles import wrap_pi


def _sym(P: np.ndarray) -> np.ndarray:
    """Symmetrise a batch of matrices (removes round-off asymmetry)."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _t(A: np.ndarray) -> np.ndarray:
    """Transpose the last two axes."""
    return np.swapaxes(A, -1, -2)


def predict(
    x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Prediction: x~ = F x^ (001 [25]); P~ = F P^ F' + Q (001 [26])."""
    x_pred = (F @ x[..., None])[..., 0]  # 001 [25]
    P_pred = _sym(F @ P @ _t(F) + Q)  # 001 [26]
    return x_pred, P_pred


def innovation(
    z: np.ndarray, z_pred: np.ndarray, angle_idx: Sequence[int] = ()
) -> np.ndarray:
    """Innovation i = z - z_pred (001 [27]); components in angle_idx wrapped to [-pi, pi)."""
    y = np.asarray(z, dtype=float) - z_pred  # 001 [27]
    if len(angle_idx):
        idx = list(angle_idx)
        y[..., idx] = wrap_pi(y[..., idx])
    return y


def innovation_cov(P: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Innovation covariance S = H P H' + R (001 [28], [10])."""
    return _sym(H @ P @ _t(H) + R)  # 001 [28]


def update(
    x: np.ndarray,
    P: np.ndarray,
    y: np.ndarray,
    H: np.ndarray,
    R: np.ndarray,
    joseph: bool = True,
    gain_scale: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Kalman update with a given innovation y (N, m); returns (x+, P+, S, K).

    K = P H' S^-1 (001 [29]; the seed prints "P H S^-1", H' is meant for the shapes to
    agree) is computed with a linear solve, never an explicit inverse,
    and K is returned unscaled. With a = gain_scale (N,) in [0, 1] (alpha of seed 004
    eq. 11; None means a = 1):
        x+ = x + a K y                                   (001 [30] at a = 1)
        joseph=True : P+ = (I - aKH) P (I - aKH)' + a^2 K R K'   (Joseph form, seed 000)
        joseph=False: P+ = P - a(2 - a) K H P                      (001 [31] at a = 1)
    Both covariance forms are equal for the optimal K (because K S K' = K H P); the
    Joseph form stays valid and positive semi-definite under round-off. a = 0 leaves x
    and P exactly as predicted ("memory" mode of seed 004).
    """
    S = innovation_cov(P, H, R)
    HP = H @ P
    K = _t(np.linalg.solve(S, HP))  # 001 [29]: K' = S^-1 H P since S, P symmetric
    Ka = K if gain_scale is None else np.asarray(gain_scale, dtype=float)[:, None, None] * K
    x_new = x + (Ka @ y[..., None])[..., 0]  # 001 [30]
    if joseph:
        A = np.eye(P.shape[-1]) - Ka @ H
        P_new = A @ P @ _t(A) + Ka @ R @ _t(Ka)
    else:
        a = 1.0 if gain_scale is None else np.asarray(gain_scale, dtype=float)[:, None, None]
        P_new = P - a * (2.0 - a) * (K @ HP)  # 001 [31]
    return x_new, _sym(P_new), S, K


def ekf_update(
    x: np.ndarray,
    P: np.ndarray,
    z: np.ndarray,
    h: np.ndarray,
    H: np.ndarray,
    R: np.ndarray,
    angle_idx: Sequence[int] = (),
    joseph: bool = True,
    gain_scale: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """EKF update (001 [55]-[62]): h = h(x~) (N, m) and Jacobian H (N, m, n) given.

    Innovation z - h with angle_idx components wrapped, then `update`.
    """
    # 001 [58]-[62]
    return update(x, P, innovation(z, h, angle_idx), H, R, joseph, gain_scale)


def diagonal_covariances(v: np.ndarray) -> np.ndarray:
    """Batch of diagonal covariance matrices (K, m, m) from their diagonals (K, m)."""
    out = np.zeros(v.shape + (v.shape[-1],))
    i = np.arange(v.shape[-1])
    out[..., i, i] = v
    return out
