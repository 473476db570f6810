"""Interacting multiple model (IMM) steps, vectorised over tracks.

Bar-Shalom, Li and Kirubarajan, "Estimation with applications to tracking and
navigation" (2001), 11.6.6: every track carries M model-conditioned estimates
xm (N, M, n), Pm (N, M, n, n) and model probabilities mu (N, M). One cycle is
    1. mixing (11.6.6-6 to -9): c_j = sum_i p_ij mu_i, mu_i|j = p_ij mu_i / c_j,
       x0_j = sum_i mu_i|j x_i, P0_j = sum_i mu_i|j (P_i + (x_i - x0_j)(x_i - x0_j)');
    2. model-matched prediction and update (the caller's filters);
    3. model probabilities (11.6.6-15): mu_j = Lambda_j c_j / sum_k Lambda_k c_k;
    4. combination (11.6.6-16, -17), also of the mixed predictions for association.
The Markov chain is given in continuous time by the models' mean sojourn times tau_i
(`transition`), so that scans of any length dt are handled.
"""

from __future__ import annotations

import numpy as np


def transition(dt: np.ndarray, sojourn: np.ndarray) -> np.ndarray:
    """Model transition probabilities p_ij (N, M, M) over steps dt (N,): expm(G dt) of the
    continuous-time chain whose generator G leaves model i at rate 1 / sojourn_i (mean
    sojourn time, s) towards the other models evenly; its stationary distribution is
    proportional to the sojourn times, whatever the step. One model (M = 1) has no other
    model to leave to: p = 1."""
    dt = np.maximum(np.asarray(dt, dtype=float), 0.0)
    M = sojourn.shape[0]
    rate = 1.0 / np.asarray(sojourn, dtype=float) if M > 1 else np.zeros(1)
    G = np.repeat((rate / max(M - 1, 1))[:, None], M, axis=1)
    G[np.arange(M), np.arange(M)] = -rate
    lam, V = np.linalg.eig(G)
    p = (V[None] * np.exp(lam[None, :] * dt[:, None])[:, None, :]) @ np.linalg.inv(V)[None]
    return np.clip(p.real, 0.0, 1.0)


def combine(mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Moment-matched Gaussian of the mixture sum_j mu_j N(xm_j, Pm_j) (11.6.6-16, -17):
    mean (N, n) and covariance (N, n, n), spread of the means included."""
    x = np.einsum("nm,nmi->ni", mu, xm)
    d = xm - x[:, None, :]
    P = np.einsum("nm,nmij->nij", mu, Pm + d[..., :, None] * d[..., None, :])
    return x, 0.5 * (P + np.swapaxes(P, 1, 2))


def mix(mu: np.ndarray, xm: np.ndarray, Pm: np.ndarray, p: np.ndarray
        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mixing step (11.6.6-6 to -9): (c (N, M), x0 (N, M, n), P0 (N, M, n, n))."""
    joint = p * mu[:, :, None]  # p_ij mu_i, (N, i, j)
    c = joint.sum(axis=1)
    w = joint / np.maximum(c, 1e-300)[:, None, :]  # mu_i|j
    x0 = np.einsum("nij,nik->njk", w, xm)
    d = xm[:, :, None, :] - x0[:, None, :, :]  # (N, i, j, n)
    P0 = np.einsum("nij,nijkl->njkl", w, Pm[:, :, None] + d[..., :, None] * d[..., None, :])
    return c, x0, 0.5 * (P0 + np.swapaxes(P0, 2, 3))


def probabilities(c: np.ndarray, loglik: np.ndarray) -> np.ndarray:
    """Model probabilities (11.6.6-15) from predicted probabilities c (N, M) and the
    models' log-likelihoods of the scan's measurement (N, M) (log-sum-exp safe)."""
    a = np.log(np.maximum(c, 1e-300)) + loglik
    a -= a.max(axis=1, keepdims=True)
    w = np.exp(a)
    return w / w.sum(axis=1, keepdims=True)


def gaussian_loglik(nis: np.ndarray, S: np.ndarray) -> np.ndarray:
    """log N(nu; 0, S) = -(nis + log det(2 pi S)) / 2 from the normalised innovation
    squared nis (N,) and the innovation covariance S (N, m, m)."""
    _, logdet = np.linalg.slogdet(2.0 * np.pi * S)
    return -0.5 * (nis + logdet)
