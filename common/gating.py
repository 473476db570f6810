"""Track-to-plot gating: pairwise innovations, Mahalanobis distances, chi-square gate.

Seed 001 [8]-[10] (d = i' S^-1 i with a chi-square(3) threshold), seed 000 d^2 and gate G.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import chi2

from common.angles import wrap_pi


def pairwise_innovations(
    z_pred: np.ndarray, z: np.ndarray, angle_idx: Sequence[int] = ()
) -> np.ndarray:
    """All innovations y[t, j] = z[j] - z_pred[t] (001 [9]), shape (N, M, m); components
    in angle_idx wrapped to [-pi, pi)."""
    y = np.asarray(z, dtype=float)[None, :, :] - np.asarray(z_pred, dtype=float)[:, None, :]
    if len(angle_idx):
        idx = list(angle_idx)
        y[..., idx] = wrap_pi(y[..., idx])
    return y


def mahalanobis_sq(y: np.ndarray, S: np.ndarray) -> np.ndarray:
    """d2[t, j] = y' S_t^-1 y (001 [8], 000 d^2), shape (N, M).

    One Cholesky factor L_t of S_t per track (S = L L'), then d2 = |L^-1 y|^2 for all
    M plots of that track in one batched solve.
    """
    N, M, m = y.shape
    if N == 0 or M == 0:
        return np.zeros((N, M))
    L = np.linalg.cholesky(S)
    u = np.linalg.solve(L, np.swapaxes(y, 1, 2))  # (N, m, M)
    return np.einsum("nkm,nkm->nm", u, u)


def chi2_gate(prob: float, dof: int) -> float:
    """Gate threshold gamma with P(chi2_dof <= gamma) = prob (001: chi-square, 3 dof)."""
    return float(chi2.ppf(prob, dof))


def gate(d2: np.ndarray, threshold: ArrayLike) -> np.ndarray:
    """Boolean gate mask d2 <= threshold. threshold is a scalar or a per-track (N,)
    array (e.g. seed 000's G, which depends on |S| of each track)."""
    thr = np.asarray(threshold, dtype=float)
    return d2 <= (thr[:, None] if thr.ndim == 1 else thr)
