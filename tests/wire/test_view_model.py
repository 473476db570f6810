"""The view's model: ellipses, bistatic arcs, bounded trails and waterfalls, services
rows, and the coalesced per-topic delta every page gets."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.deploy.config import ConfigError, load
from common.wire import protocol
from common.wire.view_model import MAX_ARRAYS, ROWS, TRAIL, ViewModel, bistatic_arc, ellipses

REPO = Path(__file__).resolve().parents[2]
CFG = load(REPO / "scenarios" / "two_targets.toml")


def wire(kind: str, msg: dict[str, Any]) -> dict[str, Any]:
    """``msg`` as a service would receive it: encoded and decoded by the protocol."""
    return protocol.decode(kind, protocol.encode({"v": protocol.VERSION, **msg}))


def gtracks(t: float, tracks: list[tuple[int, float, float]], status: str = "confirmed") -> dict[str, Any]:
    P = np.diag([400.0, 1.0, 100.0, 1.0, 1e4, 1.0])
    P[0, 2] = P[2, 0] = 50.0
    return wire("gtracks", {"t": t, "tracks": [
        {"id": i, "status": status, "x": [x, 100.0, y, 0.0, 9000.0, 0.0], "P": P.ravel().tolist(),
         "score": 3.5, "etracks": [["b1", 4], ["b2", 7]], "ambiguous": i == 2}
        for i, x, y in tracks]})


@settings(max_examples=200, deadline=None)
@given(st.floats(0.1, 1e6), st.floats(0.1, 1e6), st.floats(-0.99, 0.99))
def test_ellipse_axes_are_two_sigma_of_the_eigenvalues(s1: float, s2: float, rho: float) -> None:
    c = np.array([[s1 * s1, rho * s1 * s2], [rho * s1 * s2, s2 * s2]])
    a, b, angle = ellipses(c[None])[0]
    lam = np.linalg.eigvalsh(c)
    assert a == pytest.approx(2 * math.sqrt(lam[1]), rel=1e-6)
    assert b == pytest.approx(2 * math.sqrt(max(lam[0], 0.0)), rel=1e-6, abs=1e-6 * a)
    major = np.array([math.cos(angle), math.sin(angle)])  # an eigenvector of the larger one
    assert c @ major == pytest.approx(lam[1] * major, abs=1e-6 * lam[1])


def test_ellipse_of_an_east_west_and_a_north_south_covariance() -> None:
    e = ellipses(np.array([np.diag([100.0, 4.0]), np.diag([4.0, 100.0])]))
    assert e[0] == pytest.approx([20.0, 4.0, 0.0])
    assert e[1][:2] == pytest.approx([20.0, 4.0]) and abs(e[1][2]) == pytest.approx(math.pi / 2)


def test_bistatic_arc_lies_on_the_ellipse_of_the_bistatic_range() -> None:
    tx, rx = np.array([-35000.0, 20000.0, 0.0]), np.array([1000.0, -500.0, 0.0])
    rb, theta, sig = 120000.0, math.radians(30.0), math.radians(1.0)
    pts = np.array(bistatic_arc(rb, theta, sig, tx, rx))
    assert len(pts) == 17
    path = np.hypot(*(pts - tx[:2]).T) + np.hypot(*(pts - rx[:2]).T)
    assert path == pytest.approx(rb, abs=0.2)  # 001 [1], points rounded to 0.1 m
    az = np.arctan2(pts[:, 0] - rx[0], pts[:, 1] - rx[1])
    assert az.min() == pytest.approx(theta - 2 * sig, abs=1e-5)
    assert az.max() == pytest.approx(theta + 2 * sig, abs=1e-5)
    assert bistatic_arc(float(np.hypot(*(tx - rx)[:2])), theta, sig, tx, rx) == []


def test_trail_is_bounded_one_point_per_second_and_dropped_with_its_track() -> None:
    m = ViewModel(CFG)
    for k in range(2 * TRAIL):
        for half in (0.0, 0.5):  # two messages a second: one trail point
            t = k + half
            m.ingest("gtracks", gtracks(t, [(1, 1000.0 * t, 0.0), (2, 0.0, 50.0 * t)]))
    state = json.loads(m.topics["gtracks"].json())
    one = next(k for k in state["tracks"] if k["id"] == 1)
    assert len(one["trail"]) == TRAIL
    assert [p[0] for p in one["trail"]] == [1000.0 * k for k in range(TRAIL, 2 * TRAIL)]
    assert one["n"] == 4 * TRAIL and one["et"] == [["b1", 4], ["b2", 7]]
    assert one["sig"][0] == 20.0 and one["sig"][2] == 10.0
    assert one["ell"][0] == pytest.approx(2 * math.sqrt(250 + math.sqrt(150**2 + 50**2)), abs=1e-3)
    assert [k["amb"] for k in state["tracks"]] == [False, True]
    m.ingest("gtracks", gtracks(200.0, [(2, 0.0, 0.0)]))
    m.ingest("gtracks", gtracks(201.0, [(1, 5.0, 5.0), (2, 0.0, 0.0)]))
    again = json.loads(m.topics["gtracks"].json())["tracks"][0]
    assert again["id"] == 1 and again["n"] == 1 and again["trail"] == [[5.0, 5.0]]


def test_delta_coalesces_to_the_latest_state_and_skips_unchanged_topics() -> None:
    m = ViewModel(CFG)
    first, sent = m.delta({})
    assert first is not None and set(json.loads(first)["topics"]) == {"geometry"}
    assert json.loads(first)["topics"]["geometry"]["bases"][0] == {
        "id": "b1", "tx": [-35000.0, 20000.0], "rx": [0.0, 0.0]}
    assert m.delta(sent) == (None, sent)
    for t in range(100):  # a slow page: 100 messages between two of its sends
        m.ingest("gtracks", gtracks(float(t), [(1, float(t), 0.0)]))
    slow, slow_sent = m.delta(sent)
    assert slow is not None
    topics = json.loads(slow)["topics"]
    assert set(topics) == {"gtracks"} and topics["gtracks"]["t"] == 99.0
    fast, _ = m.delta(sent)
    assert fast == slow and m.topics["gtracks"].encoded is not None  # encoded once, shared
    assert m.delta(slow_sent)[0] is None


def test_elementary_tracks_become_arcs_and_an_unknown_base_is_refused() -> None:
    m = ViewModel(CFG)
    b1 = CFG.base("b1")
    rb = float(np.linalg.norm(b1.tx[:2] - b1.rx[:2])) + 60000.0
    P = np.diag([100.0, 1.0, 1.0, 1e-4, 1e-6]).ravel().tolist()
    track = {"id": 3, "status": "confirmed", "x": [rb, 10.0, 0.0, 1.0, 0.0], "P": P, "score": 2.0,
             "n_ch": 3, "updated": True, "ambiguous": False}
    m.ingest("etracks", wire("etracks", {"t": 5.0, "base": "b1", "tracks": [track]}))
    arcs = json.loads(m.topics["etracks/b1"].json())["arcs"]
    assert [a["id"] for a in arcs] == [3] and len(arcs[0]["pts"]) == 17
    with pytest.raises(ConfigError):
        m.ingest("etracks", wire("etracks", {"t": 5.0, "base": "b9", "tracks": [track]}))


def test_range_doppler_tracks_become_whole_ellipses() -> None:
    m = ViewModel(CFG)
    b1 = CFG.base("b1")
    rb = float(np.linalg.norm(b1.tx[:2] - b1.rx[:2])) + 60000.0
    track = {"id": 5, "status": "tentative", "x": [rb, 10.0, 0.0], "P": np.eye(3).ravel().tolist(),
             "score": 1.0, "n_ch": 2, "updated": True, "ambiguous": False}
    m.ingest("etracks", wire("etracks", {"t": 5.0, "base": "b1", "azimuth": False, "tracks": [track]}))
    pts = np.array(json.loads(m.topics["etracks/b1"].json())["arcs"][0]["pts"])
    np.testing.assert_allclose(pts[0], pts[-1], atol=0.2)  # no theta: the closed ellipse


def test_waterfall_and_bearing_series_are_bounded_to_the_window() -> None:
    m = ViewModel(CFG)
    own = {"x": 0.0, "y": 0.0, "heading": 0.0, "speed": 3.0}
    for k in range(ROWS + 50):
        t = 20.0 * k
        m.ingest("detections", wire("detections", {"t": t, "seq": k, "array": "a1", "own": own,
                                                   "brg": [0.5, 1.0], "amp": [70.0, 66.0]}))
        tracks = [{"id": 1 if k < 40 else 2, "status": "confirmed", "x": [0.5, 0.0, 70.0, 0.0],
                   "P": [1e-4, 0, 0, 0] * 4, "quality": 1.0, "ambiguous": False}]
        m.ingest("btracks", wire("btracks", {"t": t, "array": "a1", "tracks": tracks}))
    w = json.loads(m.topics["waterfall/a1"].json())
    assert len(w["rows"]) == ROWS and w["rows"][-1] == [20.0 * (ROWS + 49), [28.6, 57.3]]
    assert set(w["tracks"]) == {"2"}  # track 1 ended before the window
    assert len(w["tracks"]["2"]) == ROWS and w["tracks"]["2"][0][1:] == [28.65, 1]
    for k in range(MAX_ARRAYS - 1):  # a1 and 15 more; the 17th is refused
        m.ingest("btracks", wire("btracks", {"t": 0.0, "array": f"x{k}", "tracks": []}))
    with pytest.raises(ValueError, match="16 arrays"):
        m.ingest("btracks", wire("btracks", {"t": 0.0, "array": "one-too-many", "tracks": []}))


def test_tma_solution_has_its_ellipse_and_course() -> None:
    m = ViewModel(CFG)
    P = np.diag([4e4, 1e4, 1.0, 1.0]).ravel().tolist()
    sol = {"track": 4, "t": 60.0, "x": 3000.0, "y": 8000.0, "vx": 3.0, "vy": 0.0, "P": P,
           "range": 8544.0, "course": math.pi / 2, "speed": 3.0, "constrained": False,
           "bounds": [100.0, 1e5, 0.0, 0.0, 0.0, 20.0], "bounds_modified": False, "phase": "post",
           "residual_factor": 1.0, "legs": [0.0]}
    m.ingest("tma", wire("tma", {"t": 60.0, "array": "a1", "solutions": [sol]}))
    s = json.loads(m.topics["tma/a1"].json())["sols"][0]
    assert s["ell"] == [400.0, 200.0, 0.0] and s["course"] == 90.0 and s["track"] == 4
    assert s["range_obs"] is True  # range_observable is optional: observable unless said
    m.ingest("tma", {"t": 61.0, "array": "a1", "solutions": [sol | {"range_observable": False}]})
    assert json.loads(m.topics["tma/a1"].json())["sols"][0]["range_obs"] is False


def test_services_rows_turn_dead_when_their_token_goes() -> None:
    m = ViewModel(CFG)
    metrics = {"in": 10, "out": 4, "rejected": {"decode:rb": 2, "late": 1},
               "missed": {"k1": 3}, "p50_ms": 0.5, "p99_ms": 2.0, "queue": 0, "t": 12.0}
    m.set_alive({("global_fusion", "main"), ("test", "collector")}, 0.0)
    m.set_metrics({("global_fusion", "main"): metrics}, 0.0)
    rows = json.loads(m.topics["services"].json())["rows"]
    assert [(r["service"], r["alive"]) for r in rows] == [("global_fusion", True), ("test", True)]
    assert (rows[0]["rejected"], rows[0]["missed"], rows[0]["in"]) == (3, 3, 10)
    version = m.topics["services"].version
    m.set_alive({("global_fusion", "main"), ("test", "collector")}, 0.0)
    assert m.topics["services"].version == version  # nothing changed: nothing resent
    m.set_alive({("test", "collector")}, 1.0)
    rows = json.loads(m.topics["services"].json())["rows"]
    assert [(r["service"], r["alive"]) for r in rows] == [("global_fusion", False), ("test", True)]


def test_services_show_uptime_restarts_and_a_normal_end() -> None:
    m = ViewModel(CFG)
    gf, sim = ("global_fusion", "main"), ("simulate", "two_targets")
    base = {"in": 1, "out": 1, "p50_ms": 0.1, "p99_ms": 0.2, "queue": 0, "t": 1.0}

    def rows() -> dict[str, dict[str, Any]]:
        return {r["service"]: r for r in json.loads(m.topics["services"].json())["rows"]}

    m.set_alive({gf, sim}, 100.0)
    m.set_metrics({gf: base | {"up_s": 50.0}}, 100.0)
    m.set_alive({gf, sim}, 110.0)
    m.set_metrics({gf: base | {"up_s": 60.0}}, 110.0)
    r = rows()
    assert (r["global_fusion"]["up"], r["global_fusion"]["restarts"]) == (60.0, 0)
    assert r["simulate"]["up"] == 10.0  # no metrics: since the view saw its token
    m.set_metrics({gf: base | {"up_s": 0.4}}, 112.0)  # restarted between two polls
    assert rows()["global_fusion"]["restarts"] == 1
    m.sim_status({"state": "done"}, 113.0)
    m.set_alive({gf}, 114.0)
    assert rows()["simulate"]["state"] == "finished"
    m.set_alive(set(), 115.0)  # killed: gone
    assert rows()["global_fusion"]["state"] == "gone" and rows()["global_fusion"]["up"] is None
    m.set_alive({gf}, 116.0)  # back: one more restart
    m.set_metrics({gf: base | {"up_s": 0.5, "state": "finished"}}, 117.0)
    m.set_alive(set(), 118.0)
    assert (rows()["global_fusion"]["state"], rows()["global_fusion"]["restarts"]) == ("finished", 2)


def test_non_finite_values_reach_the_page_as_null_and_keep_no_trail() -> None:
    m = ViewModel(CFG)
    P = np.diag([np.nan, 1.0, 1e12, 1.0, 1.0, 1.0]).ravel()
    m.ingest("gtracks", {"t": 1.0, "tracks": [
        {"id": 1, "status": "confirmed", "x": [np.nan, 0.0, 1e7, 0.0, 0.0, 0.0], "P": P,
         "score": 1.0, "etracks": [], "ambiguous": False}]})
    k = json.loads(m.topics["gtracks"].json())["tracks"][0]  # strict JSON: no NaN
    assert k["x"][0] is None and k["x"][2] == 1e7 and k["trail"] == []
    m.set_link(False)
    assert json.loads(m.topics["link"].json()) == {"router": False}
    text, _ = m.delta({}, {"ages": {"gtracks": 0.5}})
    assert json.loads(text)["ages"] == {"gtracks": 0.5}
