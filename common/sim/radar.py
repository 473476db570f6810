"""Simulated passive radar plots of one channel of one bistatic base for one scan.

Target plots are the true bistatic measurements y = [r_b, v_b, theta] (001 [1]-[3])
plus Gaussian noise with the channel's diagonal covariance R (001 [4]); a base declared
`azimuth = false` gets no az, saz columns (the same draws, so its other columns equal
those of an azimuth base); targets outside
the surveillance window (r_b > rb_max or |v_b| > vb_max) are not detected. False plots
are uniform in the window, their number Poisson distributed.

SNR (dB) of a target plot follows the bistatic radar equation, SNR ~ 1/(R_T R_R)^2:
``snr_db - 20 log10(R_T R_R / snr_ref_range^2)`` plus Gaussian noise, floored at the
detection threshold; false plots have ``threshold + Exponential(clutter_snr_db)``.
Detection (pd_model): "fixed", Bernoulli(pd) independent of SNR; "snr", the SNR before
the floor exceeds the threshold and Bernoulli(pd) (pd a ceiling), so that
P_D = pd Phi((snr_db - 20 log10(R_T R_R / snr_ref_range^2) - threshold) / snr_sigma_db)
(`detection_probability`). Both draw the same numbers: "fixed" runs are unchanged.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ndtr

from common.core.angles import TWO_PI, wrap_2pi
from common.deploy.config import RadarBase
from common.radar.geometry.bistatic import azimuth, bistatic_range_rate
from common.sim.radar_scenario import RadarChannelSim, RadarSim

COLUMNS = ("rb", "vb", "az", "srb", "svb", "saz", "snr")


def mean_snr(r_t: np.ndarray, r_r: np.ndarray, ch: RadarChannelSim, radar: RadarSim) -> np.ndarray:
    """Mean SNR (dB) of targets at distances r_t, r_r (m) from transmitter and receiver."""
    with np.errstate(divide="ignore"):
        return ch.snr_db - 20.0 * np.log10(r_t * r_r / radar.snr_ref_range**2)


def detection_probability(r_t: np.ndarray, r_r: np.ndarray, ch: RadarChannelSim,
                          radar: RadarSim) -> np.ndarray:
    """P_D of targets inside the window under radar.pd_model (module doc)."""
    if radar.pd_model == "fixed":
        return np.full(np.shape(r_t), ch.pd)
    excess = mean_snr(r_t, r_r, ch, radar) - radar.snr_threshold_db
    return ch.pd * ndtr(excess / max(radar.snr_sigma_db, 1e-12))


def radar_plots(
    pos: np.ndarray,
    vel: np.ndarray,
    base: RadarBase,
    ch: RadarChannelSim,
    radar: RadarSim,
    rng: np.random.Generator,
) -> dict[str, np.ndarray]:
    """Plots (columns of COLUMNS, without az and saz at a range-Doppler base) of one
    channel for targets at pos, vel (N, 3)."""
    r_t = np.linalg.norm(pos - base.tx, axis=1)
    r_r = np.linalg.norm(pos - base.rx, axis=1)
    rb = r_t + r_r  # 001 [1]
    vb = bistatic_range_rate(pos, vel, base.tx, base.rx)  # 001 [2]
    az = azimuth(pos, base.rx)  # 001 [3]
    n = len(rb)
    noise = rng.standard_normal((n, 4))
    det = (rng.random(n) < ch.pd) & (rb <= radar.rb_max) & (np.abs(vb) <= radar.vb_max)
    snr = mean_snr(r_t, r_r, ch, radar) + radar.snr_sigma_db * noise[:, 3]
    if radar.pd_model == "snr":
        det &= snr > radar.snr_threshold_db
    snr = np.maximum(snr, radar.snr_threshold_db)
    k = rng.poisson(ch.clutter)
    vb_max, thr = radar.vb_max, radar.snr_threshold_db
    out = {
        "rb": np.concatenate([rb + ch.srb * noise[:, 0], rng.uniform(0.0, radar.rb_max, k)]),
        "vb": np.concatenate([vb + ch.svb * noise[:, 1], rng.uniform(-vb_max, vb_max, k)]),
        "az": np.concatenate([az + ch.saz * noise[:, 2], rng.uniform(0.0, TWO_PI, k)]),
        "snr": np.concatenate([snr, thr + rng.exponential(radar.clutter_snr_db, k)]),
    }
    keep = np.concatenate([det, np.ones(k, dtype=bool)])
    order = rng.permutation(int(keep.sum()))
    out = {c: v[keep][order] for c, v in out.items()}
    out["rb"] = np.maximum(out["rb"], 0.0)
    out["az"] = wrap_2pi(out["az"])
    m = len(order)
    out.update(srb=np.full(m, ch.srb), svb=np.full(m, ch.svb), saz=np.full(m, ch.saz))
    if not base.azimuth:
        del out["az"], out["saz"]
    return out
