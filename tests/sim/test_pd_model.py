"""Detection probability from the bistatic radar equation ([sim.radar] pd_model = "snr",
common.sim.radar): P_D falls with R_T R_R as the equation says, against a Monte Carlo
count; the default "fixed" model is unchanged."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from common.deploy.config import ConfigError, RadarBase
from common.sim.radar import detection_probability, radar_plots
from common.sim.radar_scenario import RadarChannelSim, RadarSim
from common.sim.scenario import load_scenario

BASE = RadarBase("b", np.zeros(3), np.array([100e3, 0.0, 0.0]), ["c"], azimuth=False)
CH = RadarChannelSim(pd=0.9, clutter=0.0, snr_db=20.0)
RADAR = RadarSim(CH, {}, [], 1.0, rb_max=1e6, snr_threshold_db=12.0, snr_sigma_db=2.0,
                 snr_ref_range=60e3, pd_model="snr")


def _targets(y: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n targets at (50 km, y, 5 km), at rest."""
    return np.tile([50e3, y, 5e3], (n, 1)), np.zeros((n, 3))


def test_pd_follows_the_radar_equation() -> None:
    rng = np.random.default_rng(3)
    n, scans = 400, 25
    expected = []
    for y in (0.0, 30e3, 60e3, 90e3, 150e3):
        pos, vel = _targets(y, n)
        r_t, r_r = np.linalg.norm(pos - BASE.tx, axis=1), np.linalg.norm(pos - BASE.rx, axis=1)
        pd = float(detection_probability(r_t, r_r, CH, RADAR)[0])
        count = sum(len(radar_plots(pos, vel, BASE, CH, RADAR, rng)["rb"]) for _ in range(scans))
        m = n * scans
        assert abs(count / m - pd) <= 4 * np.sqrt(pd * (1 - pd) / m) + 1e-9, (y, count / m, pd)
        expected.append(pd)
    assert expected[0] == pytest.approx(0.9, abs=0.01)  # near: the pd ceiling
    assert np.all(np.diff(expected) < 0) and expected[-1] < 0.05  # falls with R_T R_R


def test_fixed_model_ignores_snr_and_draws_the_same() -> None:
    pos, vel = _targets(150e3, 200)
    fixed = dataclasses.replace(RADAR, pd_model="fixed")
    loud = dataclasses.replace(CH, snr_db=200.0)
    a = radar_plots(pos, vel, BASE, loud, fixed, np.random.default_rng(1))
    b = radar_plots(pos, vel, BASE, loud, RADAR, np.random.default_rng(1))
    assert all(np.array_equal(a[k], b[k]) for k in a)  # an SNR far above: no difference
    weak = radar_plots(pos, vel, BASE, CH, fixed, np.random.default_rng(1))
    assert len(weak["rb"]) == len(a["rb"])  # "fixed": the weak SNR changes nothing


def test_pd_model_is_validated() -> None:
    doc = {"sim": {"duration": 1.0, "radar": {"pd_model": "snr"}}}
    radar = load_scenario(doc).radar
    assert radar is not None and radar.pd_model == "snr"
    doc["sim"]["radar"]["pd_model"] = "swerling"
    with pytest.raises(ConfigError, match="pd_model"):
        load_scenario(doc)
