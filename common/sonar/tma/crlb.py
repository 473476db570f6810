"""Cramer-Rao lower bound for bearings-only target motion analysis.

Fisher information J = sum_i h_i h_i' / sigma_i^2 with h_i the gradient of the
bearing model at the true target vector (the measurement coefficients of 002 eq. 5);
the bound is J^-1, mapped to any time with the state map of ``common.sonar.tma.bearings_only``.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from common.sonar.tma.bearings_only import bearing_model, state_map


def fisher_information(
    beta: np.ndarray,
    t: np.ndarray,
    own_xy: np.ndarray,
    sbrg: np.ndarray | float,
    t0: float,
    legs: Sequence[float] = (),
) -> np.ndarray:
    """J = sum_i h_i h_i' / sigma_i^2 for the target vector ``beta`` (002 eq. 5 gradients)."""
    t = np.asarray(t, dtype=float)
    _, H = bearing_model(np.asarray(beta, float), t, np.asarray(own_xy, float), t0, legs)
    w = 1.0 / np.broadcast_to(np.asarray(sbrg, float), t.shape) ** 2
    return (H * w[:, None]).T @ H


def crlb(
    beta: np.ndarray,
    t: np.ndarray,
    own_xy: np.ndarray,
    sbrg: np.ndarray | float,
    t0: float,
    legs: Sequence[float] = (),
) -> np.ndarray:
    """Cramer-Rao bound J^-1 on beta."""
    return np.linalg.inv(fisher_information(beta, t, own_xy, sbrg, t0, legs))


def crlb_at(
    beta: np.ndarray,
    t: np.ndarray,
    own_xy: np.ndarray,
    sbrg: np.ndarray | float,
    t0: float,
    t_eval: float,
    legs: Sequence[float] = (),
) -> np.ndarray:
    """4x4 bound on (x, y, vx, vy) at ``t_eval``: G J^-1 G'."""
    G = state_map(np.array([t_eval]), t0, legs)[0]
    return G @ crlb(beta, t, own_xy, sbrg, t0, legs) @ G.T


def position_rms_bound(
    beta: np.ndarray,
    t: np.ndarray,
    own_xy: np.ndarray,
    sbrg: np.ndarray | float,
    t0: float,
    t_eval: float,
    legs: Sequence[float] = (),
) -> float:
    """sqrt(trace) of the position block of the bound at ``t_eval`` (metres)."""
    C = crlb_at(beta, t, own_xy, sbrg, t0, t_eval, legs)
    return float(np.sqrt(C[0, 0] + C[1, 1]))
