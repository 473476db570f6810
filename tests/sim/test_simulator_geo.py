"""The simulator in a geodetic deployment (issue 29): aircraft at constant ellipsoidal
height, the truth carrying the ENU positions the plots come from; a flat deployment
simulates as before."""

from __future__ import annotations

import numpy as np

from common.deploy.config import RadarBase
from common.radar.geometry.bistatic import azimuth, bistatic_range, bistatic_range_rate
from common.radar.geometry.geodesy import LocalFrame
from common.sim.simulator import load_scenario
from common.wire.sim_messages import run_scenario

ORIGIN = {"lat": 47.0, "lon": 8.0, "alt": 450.0}
BASES = [RadarBase("b1", np.array([-75e3, 60e3, -270.0]), np.zeros(3), ["c1"], 1),
         RadarBase("b2", np.array([95e3, 10e3, -460.0]), np.zeros(3), ["c1"], 0)]
TINY = 1e-9


def doc(origin: dict[str, float] | None = ORIGIN, **radar: float) -> dict:
    r = {"pd": 1.0, "clutter": 0.0, "rb_max": 400e3, "target": [
        {"id": 1, "pos": [-50e3, 90e3, 10500.0], "vel": [220.0, -60.0, 0.0]},
        {"id": 2, "pos": [80e3, -40e3, 8500.0], "vel": [-130.0, 170.0, 0.0],
         "leg": [{"t": 5.0, "course_deg": 0.0, "turn_rate_deg": 2.0}]},
    ], **radar}
    d: dict = {"sim": {"scan_period": 1.0, "n_scans": 20, "radar": r}}
    if origin is not None:
        d["radar"] = {"origin": origin}
    return d


def truths(d: dict) -> list[dict]:
    return [m for _, ms in run_scenario(load_scenario(d), BASES, [], 0) for k, m in ms if k == "sim/truth/radar"]


def test_aircraft_keep_their_ellipsoidal_height() -> None:
    frame = LocalFrame(47.0, 8.0, 450.0)
    assert load_scenario(doc()).origin == frame
    for m in truths(doc()):
        p = np.c_[m["x"], m["y"], m["z"]]
        np.testing.assert_allclose(frame.to_geodetic(p)[2], [10500.0, 8500.0], atol=1e-3)
        # ~103 / ~89 km out: the ENU z is below h - h0 by ~d^2 / (2 R)
        d2 = p[:, 0] ** 2 + p[:, 1] ** 2
        np.testing.assert_allclose(p[:, 2], [10050.0, 8050.0] - d2 / (2 * 6.37e6), atol=20.0)


def test_truth_velocity_is_the_derivative_of_the_truth_path() -> None:
    ms = truths(doc())
    for k in range(1, len(ms) - 1):
        p = [np.c_[m["x"], m["y"], m["z"]] for m in (ms[k - 1], ms[k + 1])]
        v = np.c_[ms[k]["vx"], ms[k]["vy"], ms[k]["vz"]]
        # target 1 straight: a central difference over +-1 s; target 2 turns after t = 5
        np.testing.assert_allclose(v[0], (p[1][0] - p[0][0]) / 2.0, atol=1e-3)
        assert abs(v[0, 2] - (-(220.0 * ms[k]["x"][0] - 60.0 * ms[k]["y"][0]) / 6.37e6)) < 0.05
        assert abs(np.hypot(v[1, 0], v[1, 1]) - np.hypot(130.0, 170.0)) < 1.0  # turning, same speed


def test_noiseless_plots_come_from_the_truth_positions() -> None:
    for _, msgs in run_scenario(load_scenario(doc(srb=TINY, svb=TINY, saz_deg=TINY)), BASES, [], 0):
        truth = msgs[0][1]
        pos = np.c_[truth["x"], truth["y"], truth["z"]]
        vel = np.c_[truth["vx"], truth["vy"], truth["vz"]]
        for _, m in msgs[1:]:
            b = BASES[0] if m["base"] == "b1" else BASES[1]
            got, order = np.argsort(m["rb"]), np.argsort(bistatic_range(pos, b.tx, b.rx))
            np.testing.assert_allclose(np.asarray(m["rb"])[got], bistatic_range(pos, b.tx, b.rx)[order], atol=1e-5)
            np.testing.assert_allclose(np.asarray(m["vb"])[got],
                                       bistatic_range_rate(pos, vel, b.tx, b.rx)[order], atol=1e-5)
            np.testing.assert_allclose(np.asarray(m["az"])[got], azimuth(pos, b.rx)[order], atol=1e-6)


def test_flat_deployment_flies_the_mover_as_is() -> None:
    flat = truths(doc(origin=None))
    assert load_scenario(doc(origin=None)).origin is None
    assert flat[3]["x"][0] == -50e3 + 220.0 * 3 and flat[3]["z"] == [10500.0, 8500.0]
    geo = truths(doc())
    assert abs(geo[3]["z"][0] - flat[3]["z"][0]) > 400.0  # h0 and the Earth's fall
