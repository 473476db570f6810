"""Decoders of range-Doppler bases' messages (property tests): plots and fused plots
carry az and saz together or not at all, and a base's declaration decides which it
may send; etracks carry x of 5 floats, or of 3 with `azimuth: false`, P its square."""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core.rejection import Rejected
from common.radar.elementary.tracker import ElementaryTracks
from common.wire import protocol
from common.wire.protocol import DecodeError
from common.wire.radar_messages import etracks_from, etracks_message, etracks_of, plots_of

finite = st.floats(0.1, 1e5)


@st.composite
def plot_maps(draw: st.DrawFn) -> tuple[str, dict[str, Any], bool, bool]:
    """A valid plots or fused map of n plots, then with or without az, saz."""
    kind = draw(st.sampled_from(["plots", "fused"]))
    n = draw(st.integers(0, 4))
    col = st.lists(finite, min_size=n, max_size=n)
    msg: dict[str, Any] = {"v": 1, "t": 2.0, "base": "b1", "rb": draw(col), "vb": draw(col),
                           "srb": draw(col), "svb": draw(col)}
    if kind == "plots":
        msg.update(seq=0, channel="c1")
    else:
        msg["n_ch"] = [1] * n
    has_az, has_saz = draw(st.booleans()), draw(st.booleans())
    if has_az:
        msg["az"] = draw(st.lists(st.floats(0.0, 6.28), min_size=n, max_size=n))
    if has_saz:
        msg["saz"] = draw(col)
    return kind, msg, has_az, has_saz


@settings(max_examples=300, deadline=None)
@given(plot_maps(), st.booleans())
def test_az_and_saz_together_and_as_declared(case: tuple[str, dict[str, Any], bool, bool],
                                             declared: bool) -> None:
    kind, msg, has_az, has_saz = case
    payload = msgpack.packb(msg, use_bin_type=True)
    if has_az != has_saz:
        with pytest.raises(DecodeError) as e:
            protocol.decode(kind, payload)
        assert e.value.field in ("az", "saz")
        return
    dec = protocol.decode(kind, payload)
    if has_az != declared:
        with pytest.raises(Rejected) as r:
            plots_of(dec, declared)
        assert r.value.reason == ("missing_azimuth" if declared else "unexpected_azimuth")
        return
    p = plots_of(dec, declared)
    assert p.azimuth == declared and p.y.shape == (len(msg["rb"]), 3 if declared else 2)


@st.composite
def etracks_maps(draw: st.DrawFn) -> tuple[dict[str, Any], int | None]:
    """An etracks map whose tracks have x of 3 or 5 floats and P of 9 or 25, with or
    without `azimuth`; returns it and the state size it is valid for (None: invalid)."""
    azimuth = draw(st.sampled_from([None, True, False]))
    want = 3 if azimuth is False else 5
    tracks = []
    for i in range(draw(st.integers(0, 3))):
        nx, nP = draw(st.sampled_from([3, 5])), draw(st.sampled_from([9, 25]))
        tracks.append({"id": i, "status": "confirmed", "x": draw(st.lists(finite, min_size=nx, max_size=nx)),
                       "P": [1.0] * nP, "score": 3.0, "n_ch": 2, "updated": True, "ambiguous": False})
    msg: dict[str, Any] = {"v": 1, "t": 1.0, "base": "b2", "tracks": tracks}
    if azimuth is not None:
        msg["azimuth"] = azimuth
    ok = all(len(e["x"]) == want and len(e["P"]) == want**2 for e in tracks)
    return msg, want if ok else None


@settings(max_examples=300, deadline=None)
@given(etracks_maps())
def test_etracks_state_size(case: tuple[dict[str, Any], int | None]) -> None:
    msg, size = case
    payload = msgpack.packb(msg, use_bin_type=True)
    if size is None:
        for parse in (lambda: protocol.decode("etracks", payload), lambda: etracks_of(payload)):
            with pytest.raises(DecodeError) as e:
                parse()
            assert e.value.field.startswith("tracks[")
        return
    base, fast = etracks_of(payload)
    _, slow = etracks_from(protocol.decode("etracks", payload))
    n = len(msg["tracks"])
    assert base == "b2" and fast.x.shape == slow.x.shape == (n, size)
    assert fast.P.shape == slow.P.shape == (n, size, size)
    np.testing.assert_array_equal(fast.x, slow.x)


@given(st.integers(0, 3), st.sampled_from([3, 5]))
def test_etracks_message_round_trip(n: int, k: int) -> None:
    rng = np.random.default_rng(n)
    tr = ElementaryTracks(4.0, np.arange(n), np.full(n, 1), rng.normal(size=(n, k)),
                          np.broadcast_to(np.eye(k), (n, k, k)).copy(), np.ones(n),
                          np.full(n, 2), np.ones(n, bool), np.zeros(n, bool))
    payload = protocol.encode(etracks_message("b3", tr))
    assert ("azimuth" in protocol.unpack(payload)) == (k == 3)
    _, back = etracks_of(payload)
    np.testing.assert_array_equal(back.x, tr.x)
    np.testing.assert_array_equal(back.P, tr.P)
