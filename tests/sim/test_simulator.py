"""Tests of the scenario simulator (common.sim.scenario / mover / sim_radar / sim_sonar / simulator)."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from common.deploy.config import RadarBase, SonarArray, load
from common.radar.geometry.bistatic import azimuth, bistatic_range, bistatic_range_rate
from common.sim.mover import Mover
from common.sim.scenario import SonarArraySim
from common.sim.simulator import load_scenario
from common.sim.sonar import bearing_sigma
from common.wire import protocol
from common.wire.sim_messages import run_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
BASES = [
    RadarBase("b1", np.array([-35e3, 20e3, 300.0]), np.array([0.0, 0.0, 30.0]), ["c1", "c2"], 1),
    RadarBase("b2", np.array([45e3, 10e3, 500.0]), np.array([0.0, 0.0, 30.0]), ["c1"], 0),
]
CYL = SonarArray("a1", "cylindrical", 0.02)
LIN = SonarArray("a2", "linear", 0.02)
TINY = 1e-9
COLS = ("rb", "vb", "az", "srb", "svb", "saz", "snr")


def radar_doc(**radar) -> dict:
    r = {
        "pd": 0.9, "clutter": 2.0, "srb": 150.0, "svb": 1.5, "saz_deg": 1.0,
        "target": [
            {"id": 1, "pos": [-30e3, 50e3, 9e3], "vel": [200.0, -50.0, 0.0]},
            {"id": 7, "pos": [50e3, -20e3, 7e3], "vel": [-120.0, 160.0, 0.0], "t_on": 3.0,
             "leg": [{"t": 5.0, "course_deg": 0.0, "turn_rate_deg": 2.0}]},
        ],
    }
    r.update(radar)
    return {"sim": {"scan_period": 1.0, "n_scans": 10, "radar": r}}


def sonar_doc(**sonar) -> dict:
    s = {
        "scan_period": 20.0, "pd": 1.0, "clutter": 0.0, "sigma_amp_db": 0.0,
        "own": {"pos": [0.0, 0.0], "course_deg": 0.0, "speed": 3.0,
                "leg": [{"t": 100.0, "course_deg": 90.0, "turn_rate_deg": 0.5}]},
        "target": [
            {"id": 1, "pos": [5657.0, 5657.0], "course_deg": 270.0, "speed": 4.0,
             "sl_db": 150.0, "lines_hz": [50.0, 120.0]},
            {"id": 2, "pos": [-8000.0, 3000.0], "course_deg": 120.0, "speed": 5.0, "sl_db": 150.0},
        ],
    }
    s.update(sonar)
    return {"sim": {"scan_period": 20.0, "n_scans": 12, "sonar": s}}


def run(doc, bases=BASES, arrays=(), seed=0, n=None):
    return list(run_scenario(load_scenario(doc), list(bases), list(arrays), seed, n))


def test_deterministic_for_a_seed_and_seed_matters() -> None:
    a, b, c = run(radar_doc(), seed=5), run(radar_doc(), seed=5), run(radar_doc(), seed=6)
    assert a == b
    assert a != c


def test_plot_messages_fields_lengths_seq_and_protocol() -> None:
    steps = run(radar_doc())
    assert [t for t, _ in steps] == [float(k) for k in range(10)]
    for k, (t, msgs) in enumerate(steps):
        keys = [key for key, _ in msgs]
        plots = ["radar/plots/b1/c1", "radar/plots/b1/c2", "radar/plots/b2/c1"]
        assert keys == ["sim/truth/radar", *plots]
        for key, m in msgs[1:]:
            assert set(m) == {"v", "t", "seq", "base", "channel", *COLS}
            assert m["v"] == 1 and m["t"] == t and m["seq"] == k
            assert key == f"radar/plots/{m['base']}/{m['channel']}"
            assert len({len(m[c]) for c in COLS}) == 1
            assert all(type(x) is float for x in m["rb"])
            protocol.decode("plots", protocol.encode(m))
        truth = msgs[0][1]
        assert truth["id"] == ([1, 7] if t >= 3.0 else [1])
        protocol.decode("truth_radar", protocol.encode(truth))


def test_empty_channel_messages_are_published() -> None:
    steps = run(radar_doc(pd=0.0, clutter=0.0))
    plots = [m for _, msgs in steps for key, m in msgs if key.startswith("radar/plots/")]
    assert len(plots) == 10 * 3
    assert all(m["rb"] == [] and m["saz"] == [] and m["snr"] == [] for m in plots)


def test_noiseless_plots_reproduce_truth_geometry() -> None:
    doc = radar_doc(pd=1.0, clutter=0.0, srb=TINY, svb=TINY, saz_deg=TINY)
    for t, msgs in run(doc):
        truth = msgs[0][1]
        pos = np.column_stack([truth["x"], truth["y"], truth["z"]])
        vel = np.column_stack([truth["vx"], truth["vy"], truth["vz"]])
        for _, m in msgs[1:]:
            b = BASES[0] if m["base"] == "b1" else BASES[1]
            rb = bistatic_range(pos, b.tx, b.rx)
            order = np.argsort(rb)
            np.testing.assert_allclose(np.sort(m["rb"]), rb[order], atol=1e-5)
            got = np.argsort(m["rb"])
            vb = bistatic_range_rate(pos, vel, b.tx, b.rx)
            np.testing.assert_allclose(np.asarray(m["vb"])[got], vb[order], atol=1e-5)
            az = azimuth(pos, b.rx)
            np.testing.assert_allclose(np.asarray(m["az"])[got], az[order], atol=1e-6)


def test_truth_motion_straight_then_turn_to_course() -> None:
    steps = run(radar_doc(), n=10)
    t9 = steps[9][1][0][1]
    # target 1: straight, x = -30000 + 200 * 9
    assert t9["x"][0] == pytest.approx(-30e3 + 200.0 * 9)
    assert t9["y"][0] == pytest.approx(50e3 - 450.0)
    m = Mover(7, np.array([0.0, 0.0, 0.0]), math.radians(270.0), 100.0, 0.0,
              (load_scenario(radar_doc()).radar.targets[1].legs[0],), 0.0)
    # turn from 270 to 0 clockwise at 2 deg/s starting at t=5: 45 s quarter circle, r = v/omega
    pos, vel, _ = m.states(np.array([5.0, 50.0, 60.0]))
    r = 100.0 / math.radians(2.0)
    np.testing.assert_allclose(pos[1, :2], [-500.0 - r, r], atol=1e-6)
    np.testing.assert_allclose(vel[1:, :2], [[0.0, 100.0], [0.0, 100.0]], atol=1e-9)
    np.testing.assert_allclose(pos[2, :2], [-500.0 - r, r + 1000.0], atol=1e-6)


def test_scan_count_and_mixed_timeline() -> None:
    assert len(run(radar_doc(), n=4)) == 4
    doc = radar_doc()
    doc["sim"]["sonar"] = sonar_doc()["sim"]["sonar"]
    steps = run(doc, arrays=[CYL])
    assert len(steps) == 10  # radar at 0..9 s, sonar at 0 s only (20 s period)
    assert sum(key.startswith("sonar/") for key, _ in steps[0][1]) == 1
    doc["sim"]["n_scans"] = 45  # 45 s: radar 0..44, sonar 0, 20, 40
    steps = run(doc, arrays=[CYL])
    sonar_t = [t for t, msgs in steps for key, _ in msgs if key == "sonar/detections/a1"]
    assert len(steps) == 45 and sonar_t == [0.0, 20.0, 40.0]


def test_clutter_count_and_window() -> None:
    doc = radar_doc(pd=0.0, clutter=4.0, rb_max=100e3, vb_max=300.0)
    doc["sim"]["n_scans"] = 200
    plots = [m for _, msgs in run(doc) for key, m in msgs if key.startswith("radar/plots/")]
    counts = np.array([len(m["rb"]) for m in plots])
    assert abs(counts.mean() - 4.0) < 0.3 and counts.var() > 2.0
    rb = np.concatenate([m["rb"] for m in plots])
    vb = np.concatenate([m["vb"] for m in plots])
    assert rb.min() >= 0 and rb.max() <= 100e3 and np.abs(vb).max() <= 300.0
    assert abs(rb.mean() - 50e3) < 2e3


def test_channel_overrides_sigmas() -> None:
    doc = radar_doc(pd=1.0, clutter=0.0, channel={"c2": {"srb": 400.0, "saz_deg": 2.0}})
    m = {key: m for key, m in run(doc)[0][1]}
    assert set(m["radar/plots/b1/c2"]["srb"]) == {400.0}
    assert m["radar/plots/b1/c2"]["saz"][0] == pytest.approx(math.radians(2.0))
    assert set(m["radar/plots/b1/c1"]["srb"]) == {150.0}


@pytest.mark.parametrize(
    "path, value, key",
    [
        (("radar", "pd"), 1.5, "sim.radar.pd"),
        (("radar", "srb"), 0.0, "sim.radar.srb"),
        (("radar", "bogus"), 1, "sim.radar.bogus"),
        (("n_scans",), 0, "sim.n_scans"),
        (("radar", "channel"), {"c1": {"pd": "x"}}, "sim.radar.channel.c1.pd"),
    ],
)
def test_bad_input_names_the_key(path, value, key) -> None:
    doc = copy.deepcopy(radar_doc())
    t = doc["sim"]
    for p in path[:-1]:
        t = t[p]
    t[path[-1]] = value
    with pytest.raises(ValueError, match=key.replace(".", r"\.")):
        load_scenario(doc)


def test_bad_target_and_leg_and_unknown_channel_name_the_key() -> None:
    doc = radar_doc()
    doc["sim"]["radar"]["target"][1]["leg"][0]["t"] = 1.0  # before t_on
    with pytest.raises(ValueError, match=r"sim\.radar\.target\[1\]\.leg\[0\]\.t"):
        load_scenario(doc)
    with pytest.raises(ValueError, match=r"sim\.radar\.channel\.c9"):
        run(radar_doc(channel={"c9": {"pd": 0.5}}))


def test_sonar_noiseless_bearings_and_messages() -> None:
    doc = sonar_doc()
    doc["sim"]["n_scans"] = 18  # 0 .. 340 s
    arr = SonarArray("a1", "cylindrical", TINY)
    steps = run(doc, arrays=[arr])
    assert len(steps) == 18
    for k, (t, msgs) in enumerate(steps):
        (tk, truth), (dk, det) = msgs
        assert (tk, dk) == ("sim/truth/sonar", "sonar/detections/a1") and det["seq"] == k
        protocol.decode("truth_sonar", protocol.encode(truth))
        protocol.decode("detections", protocol.encode(det))
        np.testing.assert_allclose(np.sort(det["brg"]), np.sort(truth["brg"]), atol=1e-6)
        assert "freq" not in det and truth["own"] == det["own"]
    own_last = steps[-1][1][0][1]["own"]
    assert own_last["heading"] == pytest.approx(math.pi / 2)
    assert own_last["speed"] == pytest.approx(3.0)
    # own ship: north 100 s at 3 m/s, then a 180 s quarter turn of radius 3/omega, then east
    r = 3.0 / math.radians(0.5)
    assert own_last["x"] == pytest.approx(r + 3.0 * (340.0 - 280.0))
    assert own_last["y"] == pytest.approx(300.0 + r)


def test_linear_array_sigma_law_hand_values() -> None:
    a = SonarArraySim(endfire_deg=10.0)
    brg = np.array([math.radians(30.0), 0.0])
    got = bearing_sigma(brg, np.array([16.0, 16.0]), 0.0, LIN, a)
    # 000 claim 6: 0.02 / (|sin 30 deg| * sqrt 16) = 0.01; endfire capped at sin(10 deg)
    np.testing.assert_allclose(got, [0.01, 0.02 / (math.sin(math.radians(10.0)) * 4.0)])
    np.testing.assert_allclose(bearing_sigma(brg, np.array([1.0, 4.0]), 0.0, CYL, a), [0.02, 0.02])


def test_narrowband_one_detection_per_line_with_doppler() -> None:
    doc = sonar_doc(mode="narrowband", sfreq_hz=TINY)
    doc["sim"]["sonar"]["own"] = {"pos": [0.0, 0.0], "course_deg": 0.0, "speed": 0.0}
    # target 1 due North at 10 km closing at 5 m/s: f = f0 (1 + 5 / 1500)
    doc["sim"]["sonar"]["target"] = [
        {"id": 1, "pos": [0.0, 10e3], "course_deg": 180.0, "speed": 5.0, "sl_db": 160.0,
         "lines_hz": [50.0, 120.0]},
        {"id": 2, "pos": [-8e3, 3e3], "course_deg": 120.0, "speed": 5.0, "sl_db": 160.0},
    ]
    det = run(doc, arrays=[LIN], n=1)[0][1][1][1]
    assert len(det["brg"]) == len(det["freq"]) == len(det["sbrg"]) == 2
    want = np.array([50.0, 120.0]) * (1 + 5 / 1500)
    np.testing.assert_allclose(np.sort(det["freq"]), want, rtol=1e-9)


def test_shipped_scenarios_are_deployments_and_run() -> None:
    files = sorted(SCENARIOS.glob("*.toml"))
    assert {"two_targets", "crossing", "dense", "sonar_tma"} <= {f.stem for f in files}
    for f in files:
        cfg = load(f)
        assert cfg.zenoh.root == "pf/v1"
        scn = load_scenario(cfg.doc)
        steps = list(run_scenario(scn, cfg.bases, cfg.arrays, 1, 3))
        assert len(steps) == 3 and all(msgs for _, msgs in steps)
    dense = load(SCENARIOS / "dense.toml")
    assert len(dense.bases) == 4 and len({c for b in dense.bases for c in b.channels}) == 6
    assert len(load_scenario(dense.doc).radar.targets) >= 100


def test_crossing_scenario_crosses_in_base_b1_only() -> None:
    cfg = load(SCENARIOS / "crossing.toml")
    scn = load_scenario(cfg.doc)
    t = np.array([60.0])
    (p1, v1, _), (p2, v2, _) = (m.states(t) for m in scn.radar.targets)
    b1, b2 = cfg.base("b1"), cfg.base("b2")
    assert abs(bistatic_range(p1, b1.tx, b1.rx) - bistatic_range(p2, b1.tx, b1.rx))[0] < 50.0
    assert abs(azimuth(p1, b1.rx) - azimuth(p2, b1.rx))[0] < 1e-3
    vb1, vb2 = (bistatic_range_rate(p, v, b1.tx, b1.rx) for p, v in ((p1, v1), (p2, v2)))
    assert abs(vb1 - vb2)[0] < 5.0
    assert abs(bistatic_range(p1, b2.tx, b2.rx) - bistatic_range(p2, b2.tx, b2.rx))[0] > 100.0
