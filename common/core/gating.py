"""Track-to-plot gating: innovations, Mahalanobis distances, chi-square gate.

Seed 001 [8]-[10] and [48] (d = i' S^-1 i with a chi-square threshold), seed 000 d^2
and gate G. Every tracker gates through ``pair_distances``: a cheap prefilter of its own
(a sweep on range, an azimuth window, a bearing-only marginal) proposes candidate pairs
(t, j), and this one batched function gives their innovations, S and d^2; the tracker
then compares d^2 with its threshold (``gate``). The dense N x M forms
(``pairwise_innovations``, ``mahalanobis_sq``) serve the MHT mode and the tests.
``quadratic_form`` is the one y' S^-1 y of the code base outside this package.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import gammaincinv

from common.core.angles import wrap_pi


def pairwise_innovations(
    z_pred: np.ndarray, z: np.ndarray, angle_idx: Sequence[int] = ()
) -> np.ndarray:
    """All innovations y[t, j] = z[j] - z_pred[t] (001 [9]), shape (N, M, m); components
    in angle_idx wrapped to [-pi, pi)."""
    y = np.asarray(z, dtype=float)[None, :, :] - np.asarray(z_pred, dtype=float)[:, None, :]
    for i in angle_idx:
        y[..., i] = wrap_pi(y[..., i])
    return y


def quadratic_form(y: np.ndarray, S: np.ndarray) -> np.ndarray:
    """d2 = y' S^-1 y (001 [8], 000 d^2) over the leading axes of y (..., m) and S
    (..., m, m), broadcast against each other, by one batched solve; a 1-D y gives a
    0-d array."""
    return np.einsum("...i,...i->...", y, np.linalg.solve(S, y[..., None])[..., 0])


def mahalanobis_sq(y: np.ndarray, S: np.ndarray) -> np.ndarray:
    """d2[t, j] = y' S_t^-1 y (001 [8], 000 d^2), shape (N, M).

    One Cholesky factor L_t of S_t per track (S = L L'), inverted once per track (a tiny
    triangular m x m matrix), then d2 = |L^-1 y|^2 for all M plots of that track with
    one batched matmul (about 7x faster than a batched solve with M right-hand sides).
    """
    N, M, _ = y.shape
    if N == 0 or M == 0:
        return np.zeros((N, M))
    L_inv = np.linalg.inv(np.linalg.cholesky(S))
    u = y @ np.swapaxes(L_inv, 1, 2)  # (N, M, m): rows L^-1 y
    return np.einsum("nmk,nmk->nm", u, u)  # 001 [8]


def pair_distances(
    z_pred: np.ndarray, A: np.ndarray, z: np.ndarray, R: np.ndarray,
    t: np.ndarray, j: np.ndarray, angle_idx: Sequence[int] = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For K candidate pairs (t_k, j_k): innovations y = z_j - z_pred_t (001 [9], 000 y;
    angle_idx components wrapped to [-pi, pi)), S = A_t + R_j (001 [10], 000 S =
    H P H' + R) and d^2 = y' S^-1 y (001 [8], [48]; 000 d^2), shapes (K, m), (K, m, m), (K,).

    A (N, m, m) is each track's projected covariance H P H'; R is (M, m, m), or (M, m)
    for diagonal measurement covariances (variances)."""
    y = np.asarray(z, dtype=float)[j] - np.asarray(z_pred, dtype=float)[t]
    for i in angle_idx:
        y[:, i] = wrap_pi(y[:, i])
    S = A[t].copy()
    if R.ndim == 2:
        d = np.arange(R.shape[1])
        S[:, d, d] += R[j]
    else:
        S += R[j]
    return y, S, quadratic_form(y, S)  # 001 [8]


def overlap_pairs(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All pairs (i, j), i < j in index order of the sort, of closed intervals
    [lo, hi] that intersect, by a sort-and-sweep (no N^2 matrix). Returns original
    indices (a, b) with lo[a] <= lo[b]."""
    order = np.argsort(lo, kind="stable")
    lo_s, hi_s = lo[order], hi[order]
    end = np.searchsorted(lo_s, hi_s, side="right")  # j < end: lo_j <= hi_i
    start = np.arange(lo_s.size) + 1
    count = np.maximum(end - start, 0)
    total = int(count.sum())
    if total == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e
    i = np.repeat(np.arange(lo_s.size), count)
    offset = np.arange(total) - np.repeat(np.cumsum(count) - count, count)
    j = start[i] + offset
    return order[i], order[j]


def window_pairs(lo: np.ndarray, hi: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All pairs (i, j) with lo[i] <= v[j] <= hi[i], by sorting v (no N x M matrix): the
    sweep that proposes candidate pairs to ``pair_distances`` (cost O((N + M) log M + K))."""
    order = np.argsort(v, kind="stable")
    v_s = v[order]
    start = np.searchsorted(v_s, lo, side="left")
    count = np.maximum(np.searchsorted(v_s, hi, side="right") - start, 0)
    total = int(count.sum())
    i = np.repeat(np.arange(lo.size), count)
    offset = np.arange(total) - np.repeat(np.cumsum(count) - count, count)
    return i, order[start[i] + offset]


def chi2_gate(prob: float, dof: int) -> float:
    """Gate threshold gamma with P(chi2_dof <= gamma) = prob (001: chi-square, 3 dof)."""
    return float(2.0 * gammaincinv(dof / 2.0, prob))  # scipy.stats.chi2.ppf, without its import cost


def gate(d2: np.ndarray, threshold: ArrayLike) -> np.ndarray:
    """Boolean gate mask d2 <= threshold. threshold is a scalar, one value per pair (the
    shape of d2), or for an (N, M) d2 one per track (N,) (seed 000's G depends on |S|)."""
    thr = np.asarray(threshold, dtype=float)
    return d2 <= (thr[:, None] if thr.ndim == 1 and d2.ndim == 2 else thr)
