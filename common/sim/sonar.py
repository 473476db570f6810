"""Simulated passive sonar detections of one array for one scan.

Amplitude: ``a = 10^(SNR/10)`` (linear power signal-to-noise ratio) with the passive
sonar equation SNR = SL - TL - NL + DI (dB), TL = 20 log10(r) + alpha r / 1000, plus
Gaussian noise of sigma_amp_db. A target is detected with probability pd if its SNR
reaches the threshold. False detections: uniform bearings, SNR = threshold +
Exponential(clutter_snr_db).

Bearing error: cylindrical arrays sigma0; linear arrays the law of 000 claim 6,
sigma = sigma0 / (|sin(theta - heading)| sqrt(a)), with |sin| floored at
sin(endfire_deg) (deviation: the law is infinite at endfire). The noise is drawn with
the true bearing; the reported ``sbrg`` uses the measured bearing and amplitude, as the
seed defines sigma^mess. Deviation: a linear array's port/starboard ambiguity is not
simulated; the array sits at the own-ship position.

Narrowband mode: one detection per frequency line of each target, with Doppler
f = f0 (1 + v_close / c) and Gaussian frequency noise sfreq_hz; false detections get a
frequency uniform in band_hz.
"""

from __future__ import annotations

import math

import numpy as np

from common.core.angles import TWO_PI, wrap_2pi
from common.deploy.config import SonarArray
from common.sim.scenario import SonarArraySim, SonarSim


def bearing_sigma(
    brg: np.ndarray, amp: np.ndarray, heading: float, array: SonarArray, a: SonarArraySim
) -> np.ndarray:
    """Bearing standard deviation (rad): sigma0, or 000 claim 6 for linear arrays."""
    if array.kind != "linear":
        return np.full(np.shape(brg), array.sigma0)
    s = np.maximum(np.abs(np.sin(brg - heading)), math.sin(math.radians(a.endfire_deg)))
    return array.sigma0 / (s * np.sqrt(amp))  # 000 claim 6, endfire floor


def sonar_detections(
    own_pos: np.ndarray,
    own_vel: np.ndarray,
    heading: float,
    pos: np.ndarray,
    vel: np.ndarray,
    targets_sl_db: np.ndarray,
    lines_hz: list[tuple[float, ...]],
    array: SonarArray,
    a: SonarArraySim,
    sonar: SonarSim,
    rng: np.random.Generator,
) -> dict[str, np.ndarray]:
    """Detections (brg, amp, sbrg[, freq]) of targets at pos, vel (N, 3)."""
    d = (pos - own_pos)[:, :2]
    r = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1.0)
    brg = np.arctan2(d[:, 0], d[:, 1])
    narrow = a.mode == "narrowband"
    if narrow:
        idx = np.repeat(np.arange(len(r)), [len(lines) for lines in lines_hz]).astype(int)
        f0 = np.array([f for lines in lines_hz for f in lines], dtype=float)
    else:
        idx = np.arange(len(r))
    n = len(idx)
    tl = 20.0 * np.log10(r[idx]) + sonar.alpha_db_km * r[idx] / 1000.0
    snr = targets_sl_db[idx] - tl - a.nl_db + a.di_db + a.sigma_amp_db * rng.standard_normal(n)
    det = (rng.random(n) < a.pd) & (snr >= a.snr_threshold_db)
    amp = 10.0 ** (snr / 10.0)
    sigma = bearing_sigma(brg[idx], amp, heading, array, a)
    b = wrap_2pi(brg[idx] + sigma * rng.standard_normal(n))
    k = rng.poisson(a.clutter)
    clutter_snr = a.snr_threshold_db + rng.exponential(a.clutter_snr_db, k)
    out = {
        "brg": np.concatenate([b, rng.uniform(0.0, TWO_PI, k)]),
        "amp": np.concatenate([amp, 10.0 ** (clutter_snr / 10.0)]),
    }
    if narrow:
        rel = (vel - own_vel)[:, :2]
        v_close = -np.sum(d * rel, axis=1) / r
        f = f0 * (1.0 + v_close[idx] / sonar.sound_speed) + a.sfreq_hz * rng.standard_normal(n)
        out["freq"] = np.concatenate([np.maximum(f, 1e-3), rng.uniform(*a.band_hz, k)])
    keep = np.concatenate([det, np.ones(k, dtype=bool)])
    order = rng.permutation(int(keep.sum()))
    out = {c: v[keep][order] for c, v in out.items()}
    out["sbrg"] = bearing_sigma(out["brg"], out["amp"], heading, array, a)
    return out
