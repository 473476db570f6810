"""Units of a blah2 node's detections (common.radar.plots.units) and the time rules of
one stream (common.radar.plots.stamps)."""

from __future__ import annotations

import numpy as np
import pymap3d
import pytest

from common.core.rejection import Rejected
from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate
from common.radar.geometry.geodesy import WGS84, LocalFrame
from common.radar.plots.stamps import StampCheck
from common.radar.plots.units import C, IngestParams, delay_to_rb, doppler_to_vb, sigmas

FRAME = LocalFrame(47.0, 8.0, 450.0)
RX, TX = (47.3555, 6.9121, 805.0), (47.7299, 7.3510, 1145.0)


def test_delay_to_rb_matches_bistatic_range_from_ecef_sites() -> None:
    rx, tx = FRAME.to_enu(*RX), FRAME.to_enu(*TX)
    ecef = [np.array(pymap3d.geodetic2ecef(*s, ell=WGS84)) for s in (RX, TX)]
    baseline = float(np.linalg.norm(ecef[0] - ecef[1]))
    assert baseline == pytest.approx(float(np.linalg.norm(tx - rx)), abs=1e-6)
    target = FRAME.to_enu(np.array([47.1, 47.5]), np.array([7.5, 8.2]), np.array([9000.0, 4000.0]))
    rb = bistatic_range(target, tx, rx)
    delay_km = (rb - baseline) / 1000.0  # what the node reports
    np.testing.assert_allclose(delay_to_rb(delay_km, baseline), rb, atol=1e-6)


def test_doppler_to_vb_is_minus_lambda_fd() -> None:
    rx, tx = np.zeros(3), np.array([50e3, 0.0, 0.0])
    pos, vel = np.array([[20e3, 30e3, 8e3]]), np.array([[-150.0, 40.0, 0.0]])
    vb = bistatic_range_rate(pos, vel, tx, rx)
    dt = 1e-3  # v_b is the rate of r_b
    assert vb[0] == pytest.approx((bistatic_range(pos + dt * vel, tx, rx) - bistatic_range(pos, tx, rx))[0] / dt,
                                  rel=1e-5)
    fc = 600e6
    f_d = -vb * fc / C  # a closing target (v_b < 0) has a positive Doppler shift
    np.testing.assert_allclose(doppler_to_vb(f_d, fc), vb, rtol=1e-12)
    assert doppler_to_vb(np.array([10.0]), 100e6)[0] == pytest.approx(-C / 100e6 * 10.0)


def test_sigmas_follow_bins_snr_and_overrides() -> None:
    p = IngestParams()
    srb, svb = sigmas(np.array([p.snr_ref, p.snr_ref + 6.0, p.snr_ref + 60.0]), 3, 600e6, 8e6, p)
    bin_r, bin_v = C / 8e6, (C / 600e6) / p.cpi
    factor = np.array([1.0, 10 ** (-6.0 / 20), p.floor])
    np.testing.assert_allclose(srb, bin_r / np.sqrt(12) * factor)
    np.testing.assert_allclose(svb, bin_v / np.sqrt(12) * factor)
    srb, svb = sigmas(None, 2, 600e6, 8e6, p)
    np.testing.assert_allclose(srb, bin_r / np.sqrt(12))
    srb, svb = sigmas(None, 2, 600e6, 8e6, IngestParams(srb=40.0, svb=0.3))
    assert srb.tolist() == [40.0, 40.0] and svb.tolist() == [0.3, 0.3]


def test_stamps_backwards_duplicate_and_ahead() -> None:
    with pytest.raises(Rejected, match="ahead"):
        StampCheck("n0", 60.0).accept(1000.0, now=900.0)  # first stamp: against the wall clock
    s = StampCheck("n1", 60.0)
    s.accept(950.0, now=900.0)
    for t, reason in ((950.0, "duplicate"), (949.0, "time_backwards"), (1011.0, "ahead")):
        with pytest.raises(Rejected) as e:
            s.accept(t)
        assert e.value.reason == reason
    s.accept(1012.0)  # a second stamp agreeing with the rejected one: the clock jumped
    assert s.last == 1012.0
