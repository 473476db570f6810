"""Formulas of seed 000 for bearing tracking: gate value G, track quality increment dL,
SPRT thresholds T1/T2, linear-array bearing sigma, measurement matrix H (first
embodiment) and the detection probability from the predicted amplitude (second
embodiment, used by both modes).

All functions are vectorised over leading axes. Units: bearings in radians, amplitude
as a level in dB (000 calls the intensity "la amplitud o el nivel"), frequency in Hz.
Deviation (units): G and dL mix the beam spacing (rad) with sqrt|S| (rad x dB [x Hz]),
exactly as printed in the seed; the amplitude reference is the false detections' level
density (`false_alarm_probability`, 1/dB) or, without it, 1 dB; the frequency one 1 Hz.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import erfc

LN_2PI = math.log(2.0 * math.pi)


def measurement_matrix(narrowband: bool) -> np.ndarray:
    """H of 000: z = [brg, amp] from x = [brg, brg_rate, amp, amp_rate]; narrowband
    z = [brg, amp, freq] from x = [..., freq, freq_rate] (ordering of common.core.motion)."""
    if not narrowband:
        return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])  # 000 H
    H = np.zeros((3, 6))
    H[0, 0] = H[1, 2] = H[2, 4] = 1.0
    return H


def gate_value(
    p_d: ArrayLike, p_fa: ArrayLike, beam_spacing: float, det_S: ArrayLike, M: int
) -> np.ndarray:
    """000 gate G = 2 ln( P_D dTheta / ((1 - P_D) (2 pi)^(M/2) P_FA sqrt|S|) ).

    G is exactly the d^2 below which an association raises L more than a missed
    detection does (dL_hit > ln(1 - P_D), see `quality_increment`)."""
    det_S = np.asarray(det_S, dtype=float)
    p_d, p_fa = np.asarray(p_d, dtype=float), np.asarray(p_fa, dtype=float)
    return 2.0 * (
        np.log(p_d * beam_spacing / ((1.0 - p_d) * (2.0 * math.pi) ** (M / 2.0) * p_fa))
        - 0.5 * np.log(det_S)
    )


def quality_increment(
    p_d: ArrayLike, p_fa: ArrayLike, beam_spacing: float, det_S: ArrayLike, d2: ArrayLike, M: int
) -> np.ndarray:
    """000 claim 4: dL = ln( P_D dTheta / (P_FA sqrt|S|) ) - (d^2 + M ln 2 pi) / 2."""
    det_S = np.asarray(det_S, dtype=float)
    return (
        np.log(np.asarray(p_d, dtype=float) * beam_spacing / np.asarray(p_fa, dtype=float))
        - 0.5 * np.log(det_S)
        - 0.5 * (np.asarray(d2, dtype=float) + M * LN_2PI)
    )


def missed_increment(p_d: ArrayLike) -> np.ndarray:
    """dL of a missed detection, ln(1 - P_D). The seed only says that L decreases when
    there is no measurement; ln(1 - P_D) is the log-likelihood ratio of a miss in the
    sequential test it cites (Blackman & Popoli ch. 6) and the value that makes G the
    break-even d^2 of the hit increment."""
    return np.log1p(-np.asarray(p_d, dtype=float))


def thresholds(alpha: float, beta: float) -> tuple[float, float]:
    """000 claim 2: T1 = ln(beta / (1 - alpha)) (delete), T2 = ln((1 - beta) / alpha)
    (confirm); alpha = P(confirm a false track), beta = P(delete a true track)."""
    return math.log(beta / (1.0 - alpha)), math.log((1.0 - beta) / alpha)


def linear_array_sigma(
    brg: ArrayLike, amp: ArrayLike, heading: ArrayLike, sigma0: float, endfire: float
) -> np.ndarray:
    """000 claim 6: sigma = sigma0 / (|sin(theta - theta_0)| sqrt(a)), a the linear
    amplitude (> 0). Deviation: |sin| is floored at sin(endfire) because the law is
    infinite at endfire."""
    s = np.maximum(np.abs(np.sin(np.asarray(brg, dtype=float) - heading)), math.sin(endfire))
    return sigma0 / (s * np.sqrt(np.asarray(amp, dtype=float)))  # 000 claim 6


def false_alarm_probability(
    level: ArrayLike, p_fa: float, d_thr: float, mean_excess: float
) -> np.ndarray:
    """P_FA of a detection at `level` (dB): the seed's false-alarm probability p_fa
    weighted by the density of false detections' levels, an exponential excess over the
    threshold D_thr with mean `mean_excess` (dB), relative to its value at the mean
    false level D_thr + mean_excess: p_fa exp(1 - (a - D_thr) / mean_excess) (levels
    below D_thr count at D_thr). A strong detection is an unlikely false alarm, a weak
    one a likely one; p_fa keeps its meaning at the typical false level (000
    "probabilidad de falsa alarma ... a partir de una densidad"; the level density is
    not in the seed: deviation, stated)."""
    excess = np.maximum(np.asarray(level, dtype=float) - d_thr, 0.0)
    return p_fa * np.exp(1.0 - excess / mean_excess)


def detection_probability(
    amp_pred: ArrayLike, sigma_amp_pred: ArrayLike, p_d_max: float, d_thr: float
) -> np.ndarray:
    """000 (MHT embodiment) P_D = P_D_max / 2 erfc((D_thr - a_pre) / (sigma_a_pre sqrt 2)):
    the probability that the predicted amplitude a_pre (dB, estimation error sigma_a_pre,
    the standard deviation of the predicted amplitude) exceeds the detection threshold
    D_thr, times P_D_max. Vectorised over a_pre and sigma_a_pre; sigma_a_pre > 0."""
    a = np.asarray(amp_pred, dtype=float)
    sig = np.asarray(sigma_amp_pred, dtype=float)
    return 0.5 * p_d_max * erfc((d_thr - a) / (sig * math.sqrt(2.0)))  # 000 P_D(erfc)
