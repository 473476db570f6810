"""blah2 answers (common.wire.blah2) and external feeds (common.wire.plot_feed): frames,
stash, config, timestamps in ms and s, every rejection; property tests of the decoder."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from common.core.rejection import Rejected
from common.deploy.config import parse
from common.radar.plots.units import C, IngestParams
from common.wire import protocol
from common.wire.blah2 import MS_FROM, parse_config, parse_frame, parse_saved, parse_stash, unix_seconds
from common.wire.plot_feed import CsvFeed, NodeFeed, Units, csv_rows

MS = 1_700_000_000_123


def frame(**kw: object) -> bytes:
    return json.dumps({"timestamp": MS, "delay": [10.0, 20.5], "doppler": [-30.0, 12.0], "snr": [14.0, 20.0],
                       **kw}).encode()


def test_timestamps_in_ms_and_in_s() -> None:
    assert parse_frame(frame()).t == pytest.approx(1_700_000_000.123)
    assert parse_frame(frame(timestamp=1_700_000_000)).t == 1_700_000_000.0
    assert unix_seconds(MS_FROM) == MS_FROM / 1000 and unix_seconds(MS_FROM - 1) == MS_FROM - 1


@pytest.mark.parametrize("body, reason", [
    (b"{not json", "json"), (b"[1, 2]", "fields"), (frame(delay=None), "fields"),
    (frame(delay=[1.0, "x"]), "fields"), (frame(delay=[1.0]), "lengths"), (frame(snr=[1.0]), "lengths"),
    (frame(doppler=[math.nan, 1.0]), "nan"), (frame(delay=[-0.5, 1.0]), "negative_delay"),
    (frame(timestamp=-5), "timestamp"), (frame(timestamp="now"), "fields"), (b"\xff\xfe", "json"),
])
def test_bad_frames_are_rejected_whole(body: bytes, reason: str) -> None:
    with pytest.raises(Rejected) as e:
        parse_frame(body)
    assert e.value.reason == reason


def test_stash_groups_rows_into_frames_and_saved_files() -> None:
    body = json.dumps({"timestamp": [MS, MS, MS + 500], "delay": [1.0, 2.0, 3.0], "doppler": [4.0, 5.0, 6.0]})
    frames = parse_stash(body)
    assert [len(f) for f in frames] == [2, 1] and frames[1].t == pytest.approx(MS / 1000 + 0.5)
    assert frames[0].snr is None
    lines = frame().decode() + "\nnot json\n" + frame(timestamp=MS + 1).decode()
    assert len(parse_saved(lines)) == 3 and len(parse_saved("[" + frame().decode() + "]")) == 1


def test_config() -> None:
    doc = {"location": {"rx": {"latitude": 47.0, "longitude": 8.0, "altitude": 450.0},
                        "tx": {"latitude": 47.1, "longitude": 8.1, "altitude": 500.0}},
           "capture": {"fc": 204.64e6, "fs": 2e6}, "process": {"data": {"cpi": 0.5}}}
    c = parse_config(json.dumps(doc))
    assert (c.rx, c.fc, c.fs, c.cpi) == ((47.0, 8.0, 450.0), 204.64e6, 2e6, 0.5)
    del doc["capture"]["fc"]
    with pytest.raises(Rejected, match="capture.fc"):
        parse_config(json.dumps(doc))


CFG = parse({"radar": {"base": [{"id": "n1", "tx": [30e3, 0.0, 0.0], "rx": [0.0, 0.0, 0.0], "channels": ["c"],
                                 "azimuth": False}]}})


def test_node_feed_message_is_a_valid_plots_message() -> None:
    base = CFG.bases[0]
    units = Units(30e3, 600e6, 8e6, IngestParams(time_offset=-0.25))
    feed = NodeFeed(base, units, 60.0)
    key, msg = feed.message(parse_frame(frame()), now=MS / 1000)
    assert key == "radar/plots/n1/c"
    got = protocol.decode("plots", protocol.encode(msg))
    assert got["t"] == pytest.approx(MS / 1000 - 0.25) and got["seq"] == 0
    np.testing.assert_allclose(got["rb"], [40e3, 50.5e3])
    np.testing.assert_allclose(got["vb"], [30.0 * C / 600e6, -12.0 * C / 600e6])
    with pytest.raises(Rejected, match="duplicate"):
        feed.message(parse_frame(frame()))
    assert len(feed.newer(parse_stash(json.dumps({"timestamp": [MS, MS + 1000], "delay": [1.0, 2.0],
                                                  "doppler": [0.0, 0.0]})))) == 1


def test_csv_rows_checks() -> None:
    base = CFG.bases[0]
    feed = CsvFeed([base], {"n1": Units(30e3, 600e6, 8e6, IngestParams())}, 60.0)
    text = ("t,base,channel,delay_km,doppler_hz,snr_db\n1,n1,c,10,-30,20\n1,n2,c,10,-30,20\n"
            "1,n1,d,1,1,1\n2,n1,c,-1,1,1\n2,n1,c,inf,1,1\n2,n1,c,x,1,1\n")
    reasons, groups = [], []
    for row in csv_rows(text):
        assert not isinstance(row, Rejected)
        try:
            groups.append(feed.row(row))
        except Rejected as e:
            reasons.append(e.reason)
    assert reasons == ["unknown_base", "unknown_channel", "negative_delay", "nan", "csv"]
    key, cols = groups[0]
    assert key == (1.0, "n1", "c") and cols["rb"] == pytest.approx(40e3)
    _, msg = feed.message(key, [cols])
    protocol.decode("plots", protocol.encode(msg))
    with pytest.raises(Rejected, match="time_backwards"):
        feed.message((0.5, "n1", "c"), [cols])
    assert isinstance(next(csv_rows("a,b\n1,2\n")), Rejected)


numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**20, 10**20),
                    st.text(max_size=3), st.none(), st.booleans())


@given(st.dictionaries(st.sampled_from(["timestamp", "delay", "doppler", "snr", "x"]),
                       st.one_of(numbers, st.lists(numbers, max_size=4)), max_size=5))
def test_decoder_returns_a_checked_frame_or_rejects(doc: dict[str, object]) -> None:
    try:
        f = parse_frame(json.dumps(doc))
    except Rejected as e:
        assert e.reason in {"json", "fields", "lengths", "nan", "negative_delay", "timestamp"}
        return
    assert f.t > 0 and math.isfinite(f.t)
    assert len(f.delay) == len(f.doppler) and np.all(f.delay >= 0) and np.all(np.isfinite(f.doppler))
    assert f.snr is None or len(f.snr) == len(f.delay)


@given(st.binary(max_size=40))
def test_decoder_never_raises_anything_else_on_bytes(body: bytes) -> None:
    try:
        parse_frame(body)
    except Rejected:
        pass


@given(st.lists(st.tuples(st.floats(0, 300), st.floats(-500, 500)), max_size=8),
       st.integers(1_000_000_000, 4_000_000_000), st.integers(0, 999), st.booleans())
def test_valid_frames_round_trip(rows: list[tuple[float, float]], s: int, ms: int, in_ms: bool) -> None:
    """Stamps of 2001-2096 in s or in ms both read as UNIX seconds."""
    doc = {"timestamp": s * 1000 + ms if in_ms else s, "delay": [r[0] for r in rows],
           "doppler": [r[1] for r in rows]}
    f = parse_frame(json.dumps(doc))
    assert f.t == pytest.approx(s + ms / 1000 if in_ms else s, abs=1e-6)
    assert f.delay.tolist() == doc["delay"] and f.doppler.tolist() == doc["doppler"] and f.snr is None
