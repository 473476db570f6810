"""ADS-B truth (common.evaluation.adsb) on the committed sample tests/evaluation/data/adsb:
two readsb snapshots one second apart, origin 47.0 N, 8.0 E, 450 m (ellipsoidal).

The expected ENU values were computed by hand with pymap3d.geodetic2enu(lat, lon,
ft * 0.3048, 47.0, 8.0, 450.0, ell=wgs84):
  4b1a01 at 47.1, 8.1, 30000 ft     -> ( 7602.258,  11137.987, 8679.760)  t = now - 1.5
  4b1a01 at 47.1005, 8.101, 30000 ft -> ( 7678.208,  11193.751, 8679.572)  t = now + 1 - 0.5
  4b1a02 at 46.9, 7.9, 20000 ft (MLAT) -> (-7627.044, -11122.753, 5631.750)
  ~4b1a03 at 46.95, 8.05, 10000 ft baro + 30 m -> (3808.179, -5559.988, 2624.440)
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from common.evaluation.adsb import NON_ICAO, AdsbScoring, AdsbTruth, aircraft_id, parse_snapshot
from common.evaluation.pcrlb import Evaluation
from common.radar.geometry.geodesy import LocalFrame

DATA = Path(__file__).parent / "data" / "adsb"
ORIGIN = LocalFrame(47.0, 8.0, 450.0)
NOW = 1700000000.0
A1_0 = np.array([7602.258, 11137.987, 8679.760])
A1_1 = np.array([7678.208, 11193.751, 8679.572])
A2 = np.array([-7627.044, -11122.753, 5631.750])
A3_BARO30 = np.array([3808.179, -5559.988, 2624.440])


def _snapshots() -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted(DATA.glob("aircraft-*.json"))]


def _truth(baro_offset: float | None = None) -> tuple[AdsbTruth, Counter[str]]:
    rejects: Counter[str] = Counter()
    truth = AdsbTruth(ORIGIN)
    truth.add(f for s in _snapshots() for f in parse_snapshot(s, rejects, baro_offset))
    return truth, rejects


def test_the_sample_parses_with_every_reject_counted_by_reason() -> None:
    rejects: Counter[str] = Counter()
    fixes = parse_snapshot(_snapshots()[0], rejects)
    assert [f.hex for f in fixes] == ["4b1a01", "4b1a02"]
    assert rejects == {"baro_only": 1, "ground": 1, "no_position": 1, "stale": 1, "bad_hex": 1}
    assert fixes[0].t == NOW - 1.5 and fixes[0].h == pytest.approx(30000 * 0.3048)
    assert [f.lower for f in fixes] == ["", "mlat"]


def test_baro_altitude_only_with_a_stated_offset_and_tisb_non_icao_flagged() -> None:
    rejects: Counter[str] = Counter()
    fixes = parse_snapshot(_snapshots()[0], rejects, baro_offset=30.0)
    f3 = next(f for f in fixes if f.hex == "~4b1a03")
    assert f3.h == pytest.approx(10000 * 0.3048 + 30.0) and f3.lower == "tisb"
    assert "baro_only" not in rejects and rejects["ground"] == 1
    assert aircraft_id("~4b1a03") == 0x4B1A03 + NON_ICAO and aircraft_id("4b1a01") == 0x4B1A01


def test_positions_in_the_local_frame_match_the_hand_computed_values() -> None:
    truth, _ = _truth(baro_offset=30.0)
    path = truth.paths[0x4B1A01]
    assert path.t.tolist() == [NOW - 1.5, NOW + 0.5]
    np.testing.assert_allclose(path.p, [A1_0, A1_1], atol=1e-3)
    np.testing.assert_allclose(truth.paths[0x4B1A02].p, [A2], atol=1e-3)  # repeated: once
    np.testing.assert_allclose(truth.paths[aircraft_id("~4b1a03")].p, [A3_BARO30], atol=1e-3)
    assert truth.lower == {0x4B1A02: "mlat", aircraft_id("~4b1a03"): "tisb"}


def test_truth_is_interpolated_between_fixes_and_absent_outside() -> None:
    truth, _ = _truth()
    ids, x = truth.at(NOW - 0.5)  # halfway between 4b1a01's fixes
    assert ids.tolist() == [0x4B1A01]  # 4b1a02 has one fix (twice): nothing to interpolate
    np.testing.assert_allclose(x[0, ::2], (A1_0 + A1_1) / 2, atol=1e-3)
    np.testing.assert_allclose(x[0, 1::2], (A1_1 - A1_0) / 2.0, atol=1e-3)
    np.testing.assert_allclose(truth.at(NOW + 0.5)[1][0, ::2], A1_1, atol=1e-3)
    assert truth.at(NOW + 2.0)[0].size == 0 and truth.at(NOW - 3.0)[0].size == 0
    gap = AdsbTruth(ORIGIN, max_gap=1.0)
    gap.add(f for s in _snapshots() for f in parse_snapshot(s, Counter()))
    assert gap.at(NOW - 0.5)[0].size == 0  # fixes 2 s apart: no interpolation


@pytest.mark.parametrize("doc", [None, [], {"now": "x", "aircraft": []}, {"now": 1.0},
                                 {"now": float("nan"), "aircraft": []}])
def test_a_broken_snapshot_is_counted_not_raised(doc: object) -> None:
    rejects: Counter[str] = Counter()
    assert parse_snapshot(doc, rejects) == [] and rejects == {"bad_snapshot": 1}


def test_broken_aircraft_are_counted_not_raised() -> None:
    rejects: Counter[str] = Counter()
    doc = {"now": 10.0, "aircraft": [
        3, {"hex": 5}, {"hex": "abcdef", "lat": "47", "lon": 8.0, "seen_pos": 0, "alt_geom": 1},
        {"hex": "abcdef", "lat": 91.0, "lon": 8.0, "seen_pos": 0, "alt_geom": 1},
        {"hex": "abcdef", "lat": 47.0, "lon": 8.0, "alt_geom": 1},
        {"hex": "abcdef", "lat": 47.0, "lon": 8.0, "seen_pos": 0, "alt_geom": True},
        {"hex": "ABCDEF", "lat": 47.0, "lon": 8.0, "seen_pos": 1, "alt_geom": 100}]}
    fixes = parse_snapshot(doc, rejects)
    assert rejects == {"not_a_map": 1, "bad_hex": 1, "bad_position": 2, "no_seen_pos": 1,
                       "no_altitude": 1}
    assert [(f.hex, f.t) for f in fixes] == [("abcdef", 9.0)]


def test_a_track_away_from_every_adsb_aircraft_is_unverified_not_false() -> None:
    truth, _ = _truth()
    scoring = AdsbScoring(truth, Evaluation(c=2000.0, gamma=2000.0))
    t = NOW + 0.5
    _, tx = truth.at(t)
    far = tx[0].copy()
    far[0] += 50e3
    x = np.vstack([tx + 10.0, far])
    scoring.add(t, np.array([7, 9]), x, np.tile(np.eye(6) * 100.0, (2, 1, 1)))
    assert scoring.unverified == {9} and scoring.unverified_steps == 1
    s = scoring.ev.metrics.summary()
    assert s.false == 0 and s.missed == 0 and s.localisation > 0
