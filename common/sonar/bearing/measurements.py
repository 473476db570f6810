"""Seed 000's measurements for the bearing trackers of both modes (common.sonar.bearing.tracker,
common.sonar.mht.tracker): a detection list as z = [brg, level[, freq]] with the diagonal of R,
the bearing sigma of claim 6 for linear arrays.
"""

from __future__ import annotations

import math

import numpy as np

from common.core.angles import wrap_2pi
from common.core.rejection import Rejected
from common.sonar.bearing.model import linear_array_sigma
from common.sonar.bearing.params import TrackerParams


def bearing_sigmas(p: TrackerParams, array_kind: str, sigma0: float, brg: np.ndarray,
                   amp: np.ndarray, heading: float) -> np.ndarray:
    """sigma^mess of each bearing: 000 claim 6 for linear arrays, sigma0 otherwise."""
    if array_kind == "linear":
        return linear_array_sigma(brg, amp, heading, sigma0, math.radians(p.endfire_deg))
    return np.full(np.shape(brg), sigma0)


def measurement_variances(p: TrackerParams, array_kind: str, sigma0: float, brg: np.ndarray,
                          level: np.ndarray, heading: float) -> np.ndarray:
    """Diagonal of 000 R per measurement (K, m): sigma_brg^2, sigma_a^2[, sigma_f^2]."""
    cols = [bearing_sigmas(p, array_kind, sigma0, brg, 10.0 ** (level / 10.0), heading) ** 2,
            np.full(brg.shape, p.sigma_amp_db**2)]
    if p.mode == "narrowband":
        cols.append(np.full(brg.shape, p.sigma_freq_hz**2))
    return np.column_stack(cols)


def detection_measurements(
    p: TrackerParams, array_kind: str, sigma0: float, t_last: float | None, t: float,
    brg: np.ndarray, amp: np.ndarray, heading: float, freq: np.ndarray | None,
    sbrg: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A detection list of time t (after t_last) as 000's measurements, for both modes: levels
    (K,) dB, z (K, m) = [brg, level[, freq]], diagonal of R (K, m); sbrg replaces the law."""
    if t_last is not None and not t > t_last:
        raise Rejected("time_order", f"t={t} is not after the previous cycle t={t_last}")
    narrowband = p.mode == "narrowband"
    if narrowband and freq is None:
        raise ValueError("narrowband tracking needs detection frequencies")
    brg = wrap_2pi(np.asarray(brg, dtype=float).reshape(-1))
    level = 10.0 * np.log10(np.asarray(amp, dtype=float).reshape(-1))
    cols = [brg, level] + ([np.asarray(freq, dtype=float).reshape(-1)] if narrowband else [])
    Rd = measurement_variances(p, array_kind, sigma0, brg, level, heading)
    if sbrg is not None:
        Rd[:, 0] = np.square(np.asarray(sbrg, dtype=float).reshape(-1))
    return level, np.column_stack(cols), Rd
