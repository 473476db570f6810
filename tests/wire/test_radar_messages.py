"""common.wire.radar_messages: the typed etracks parser accepts exactly what
protocol.decode accepts, rejects with the same field, and round-trips the builders."""

from __future__ import annotations

import copy

import msgpack
import numpy as np
import pytest

from common.core.track_table import Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.report import GlobalTracks
from common.radar.geometry.geodesy import LocalFrame
from common.wire import protocol
from common.wire.radar_messages import etracks_from, etracks_message, etracks_of, gtracks_message


def _tracks(n: int, rng: np.random.Generator) -> ElementaryTracks:
    P = rng.standard_normal((n, 5, 5))
    return ElementaryTracks(
        t=12.0, id=np.arange(1, n + 1), status=rng.integers(0, 3, n), x=rng.standard_normal((n, 5)),
        P=P @ np.swapaxes(P, 1, 2), score=rng.standard_normal(n), n_ch=rng.integers(0, 4, n),
        updated=rng.uniform(size=n) < 0.5, ambiguous=rng.uniform(size=n) < 0.5)


def _same(a: ElementaryTracks, b: ElementaryTracks) -> None:
    assert a.t == b.t
    for f in ("id", "status", "x", "P", "score", "n_ch", "updated", "ambiguous"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
        assert getattr(a, f).dtype == getattr(b, f).dtype


def test_round_trip_equals_protocol_decode() -> None:
    tr = _tracks(7, np.random.default_rng(1))
    payload = protocol.encode(etracks_message("b2", tr))
    base, fast = etracks_of(payload)
    ref_base, ref = etracks_from(protocol.decode("etracks", payload))
    assert base == ref_base == "b2"
    _same(fast, ref)
    _same(fast, tr)
    assert len(etracks_of(protocol.encode(etracks_message("b1", _tracks(0, np.random.default_rng(2)))))[1]) == 0


BAD = [
    ("v", True), ("v", 2), ("t", -1.0), ("t", float("nan")), ("t", "3"), ("base", ""), ("base", 3),
    ("tracks", {}), ("tracks", [1]), ("tracks.0.id", -1), ("tracks.0.id", 1.5), ("tracks.0.id", True),
    ("tracks.0.id", 2**63), ("tracks.0.status", "deleted"), ("tracks.0.status", ["confirmed"]),
    ("tracks.0.x", [1.0] * 4), ("tracks.0.x", [1.0, 2.0, True, 4.0, 5.0]),
    ("tracks.0.x", [1.0, 2.0, float("inf"), 4.0, 5.0]), ("tracks.0.P", [0.0] * 24),
    ("tracks.0.P", ["a"] * 25), ("tracks.0.score", None), ("tracks.0.n_ch", -2),
    ("tracks.0.updated", 1), ("tracks.0.ambiguous", "yes"),
]


@pytest.mark.parametrize("path,value", BAD)
def test_rejects_what_protocol_rejects_with_the_same_field(path: str, value: object) -> None:
    msg = protocol.unpack(protocol.encode(etracks_message("b1", _tracks(3, np.random.default_rng(3)))))
    bad = copy.deepcopy(msg)
    *head, last = path.split(".")
    node = bad
    for k in head:
        node = node[int(k)] if k.isdigit() else node[k]
    node[last] = value
    payload = msgpack.packb(bad, use_bin_type=True)
    with pytest.raises(protocol.DecodeError) as ref:
        protocol.decode("etracks", payload)
    with pytest.raises(protocol.DecodeError) as got:
        etracks_of(payload)
    assert got.value.field == ref.value.field


@pytest.mark.parametrize("missing", ["t", "base", "tracks", "tracks.1.P", "tracks.2.updated"])
def test_missing_field(missing: str) -> None:
    msg = protocol.unpack(protocol.encode(etracks_message("b1", _tracks(3, np.random.default_rng(4)))))
    *head, last = missing.split(".")
    node = msg
    for k in head:
        node = node[int(k)] if k.isdigit() else node[k]
    del node[last]
    with pytest.raises(protocol.DecodeError, match=last):
        etracks_of(msgpack.packb(msg, use_bin_type=True))


def test_gtracks_message_is_valid_and_names_the_contributing_bases() -> None:
    g = GlobalTracks(t=5.0, bases=("b1", "b2", "b3"), id=np.array([4, 9]),
                     status=np.array([Status.CONFIRMED, Status.COASTING]),
                     x=np.arange(12.0).reshape(2, 6), P=np.tile(np.eye(6), (2, 1, 1)),
                     score=np.array([3.5, 0.0]), member=np.array([[7, 0, 2], [0, 0, 0]]),
                     has=np.array([[True, False, True], [False, False, False]]),
                     ambiguous=np.array([False, True]))
    msg = protocol.decode("gtracks", protocol.encode(gtracks_message(g)))
    assert [tr["status"] for tr in msg["tracks"]] == ["confirmed", "coasting"]
    assert msg["tracks"][0]["etracks"] == [("b1", 7), ("b3", 2)] and msg["tracks"][1]["etracks"] == []
    np.testing.assert_array_equal(msg["tracks"][1]["x"], np.arange(6.0, 12.0))


def _gtracks(x: np.ndarray) -> GlobalTracks:
    n = len(x)
    return GlobalTracks(t=1.0, bases=("b1",), id=np.arange(n), status=np.full(n, Status.CONFIRMED),
                        x=x, P=np.tile(np.eye(6), (n, 1, 1)), score=np.zeros(n),
                        member=np.zeros((n, 1), dtype=np.int64), has=np.ones((n, 1), dtype=bool),
                        ambiguous=np.zeros(n, dtype=bool))


def test_gtracks_carry_lat_lon_alt_in_a_geodetic_deployment_only() -> None:
    frame = LocalFrame(47.0, 8.0, 450.0)
    x = np.array([[0.0, 0, 0, 0, 0, 0], [-50e3, 200.0, 90e3, -60.0, 9200.0, 0.0]])
    flat = protocol.decode("gtracks", protocol.encode(gtracks_message(_gtracks(x))))
    assert not {"lat", "lon", "alt"} & set(flat["tracks"][1])
    geo = protocol.decode("gtracks", protocol.encode(gtracks_message(_gtracks(x), frame)))
    t0, t1 = geo["tracks"]
    assert (t0["lat"], t0["lon"]) == pytest.approx((47.0, 8.0)) and t0["alt"] == pytest.approx(450.0)
    assert frame.to_enu(t1["lat"], t1["lon"], t1["alt"]) == pytest.approx([-50e3, 90e3, 9200.0], abs=1e-6)
    assert t1["alt"] > 450.0 + 9200.0 + 700.0  # 103 km out, the tangent plane is ~830 m up
    assert gtracks_message(_gtracks(np.zeros((0, 6))), frame)["tracks"] == []


@pytest.mark.parametrize("change,field", [
    ({"lat": 90.5}, "tracks[0].lat"),
    ({"lon": -180.5}, "tracks[0].lon"),
    ({"alt": float("nan")}, "tracks[0].alt"),
    ({"lat": "47"}, "tracks[0].lat"),
])
def test_gtracks_decoder_checks_lat_lon_alt(change: dict[str, object], field: str) -> None:
    msg = gtracks_message(_gtracks(np.zeros((1, 6))), LocalFrame(47.0, 8.0, 450.0))
    msg["tracks"][0].update(change)
    with pytest.raises(protocol.DecodeError) as e:
        protocol.decode("gtracks", protocol.encode(msg))
    assert e.value.field == field


@pytest.mark.parametrize("drop", ["lat", "lon", "alt"])
def test_gtracks_lat_lon_alt_come_together(drop: str) -> None:
    msg = gtracks_message(_gtracks(np.zeros((1, 6))), LocalFrame(47.0, 8.0, 450.0))
    del msg["tracks"][0][drop]
    with pytest.raises(protocol.DecodeError, match="missing") as e:
        protocol.decode("gtracks", protocol.encode(msg))
    assert e.value.field == f"tracks[0].{drop}"
