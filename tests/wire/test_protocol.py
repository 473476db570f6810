"""Wire protocol v1: round trips, strict validation, and fuzzing of the decoders."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.wire import protocol
from common.wire.protocol import DecodeError, decode, encode


def plots_msg(n: int = 3) -> dict:
    r = np.arange(n, dtype=float)
    return {"v": 1, "t": 12.5, "seq": 4, "base": "b1", "channel": "c2",
            "rb": 1e4 + r, "vb": -3.0 + r, "az": 0.5 + 0.1 * r,
            "srb": np.full(n, 150.0), "svb": np.full(n, 2.0), "saz": np.full(n, 0.02),
            "snr": np.full(n, 14.0)}


def etracks_msg() -> dict:
    return {"v": 1, "t": 3.0, "base": "b2", "tracks": [
        {"id": 1, "status": "confirmed", "x": [1e4, 2.0, 0.0, 0.3, 0.0],
         "P": list(np.eye(5).ravel()), "score": 7.0, "n_ch": 3, "updated": True,
         "ambiguous": False}]}


def gtracks_msg() -> dict:
    return {"v": 1, "t": 3.0, "tracks": [
        {"id": 4, "status": "tentative", "x": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
         "P": list(np.eye(6).ravel()), "score": 9.5, "etracks": [["b1", 2], ["b3", 7]],
         "ambiguous": True}]}


def detections_msg() -> dict:
    return {"v": 1, "t": 60.0, "seq": 0, "array": "a1",
            "own": {"x": 0.0, "y": 10.0, "heading": 2.4, "speed": 2.5},
            "brg": [0.1, 6.2], "amp": [12.0, 3.0], "sbrg": [0.02, 0.03]}


VALID = {"plots": plots_msg, "etracks": etracks_msg, "gtracks": gtracks_msg,
         "detections": detections_msg}


@pytest.mark.parametrize("kind", sorted(VALID))
def test_round_trip(kind: str) -> None:
    msg = VALID[kind]()
    out = decode(kind, encode(msg))
    for name, value in msg.items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(out[name], value)
    assert out["t"] == msg["t"]


def test_columns_are_numpy_and_empty_lists_allowed() -> None:
    msg = plots_msg(0)
    out = decode("plots", encode(msg))
    assert out["rb"].dtype == np.float64 and out["rb"].shape == (0,)


def test_gtrack_pairs_decoded_as_tuples() -> None:
    out = decode("gtracks", encode(gtracks_msg()))
    assert out["tracks"][0]["etracks"] == [("b1", 2), ("b3", 7)]


@pytest.mark.parametrize("field,value,reason", [
    ("rb", [1.0, 2.0], "differs from"),
    ("srb", [150.0, 0.0, 150.0], "must be > 0"),
    ("srb", [150.0, -1.0, 150.0], "must be > 0"),
    ("vb", [1.0, math.nan, 2.0], "not finite"),
    ("vb", [1.0, math.inf, 2.0], "not finite"),
    ("az", [0.1, 7.0, 0.2], "angle must be in"),
    ("rb", [1.0, "x", 2.0], "expected a number"),
    ("seq", -1, "must be >= 0"),
    ("seq", 1.5, "expected an integer"),
    ("base", "", "non-empty string"),
    ("t", True, "expected a number"),
])
def test_rejections_name_the_field(field: str, value: object, reason: str) -> None:
    msg = plots_msg()
    msg[field] = value
    with pytest.raises(DecodeError) as e:
        decode("plots", encode(msg))
    assert field in str(e.value)
    assert reason in str(e.value)


def test_missing_field_and_version() -> None:
    msg = plots_msg()
    del msg["saz"]
    with pytest.raises(DecodeError, match="saz: missing"):
        decode("plots", encode(msg))
    msg = plots_msg()
    msg["v"] = 2
    with pytest.raises(DecodeError, match="version"):
        decode("plots", encode(msg))


def test_nested_track_field_named() -> None:
    msg = etracks_msg()
    msg["tracks"][0]["P"] = [0.0] * 24
    with pytest.raises(DecodeError) as e:
        decode("etracks", encode(msg))
    assert e.value.field == "tracks[0].P"


@pytest.mark.parametrize("payload", [b"", b"\xc1", b"\x93\x01\x02\x03", msgpack.packb(3),
                                     msgpack.packb({1: 2}), b"\xdc\xff\xff"])
def test_garbage_payloads(payload: bytes) -> None:
    with pytest.raises(DecodeError):
        decode("plots", payload)


@settings(max_examples=1500, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(st.binary(max_size=300), st.sampled_from(sorted(protocol.SCHEMAS)))
def test_fuzz_random_bytes_only_decode_error(payload: bytes, kind: str) -> None:
    try:
        decode(kind, payload)
    except DecodeError:
        pass


scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**63), 2**64 - 1),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5), st.binary(max_size=5),
)
values = st.recursive(scalars, lambda c: st.lists(c, max_size=4) | st.dictionaries(
    st.text(max_size=4), c, max_size=4), max_leaves=10)


@st.composite
def near_valid(draw: st.DrawFn) -> tuple[str, bytes]:
    """A valid message with one to three fields replaced, removed or re-typed."""
    kind = draw(st.sampled_from(sorted(VALID)))
    msg = VALID[kind]()
    msg = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in msg.items()}
    for _ in range(draw(st.integers(1, 3))):
        name = draw(st.sampled_from(sorted(msg)))
        action = draw(st.sampled_from(["replace", "delete", "shorten", "poison"]))
        if action == "replace":
            msg[name] = draw(values)
        elif action == "delete":
            msg.pop(name, None)
        elif isinstance(msg.get(name), list) and msg[name]:
            if action == "shorten":
                msg[name] = msg[name][:-1]
            else:
                msg[name] = [*msg[name][:-1], draw(values)]
        if not msg:
            break
    return kind, msgpack.packb(msg, use_bin_type=True)


@settings(max_examples=1500, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(near_valid())
def test_fuzz_near_valid_maps_only_decode_error(case: tuple[str, bytes]) -> None:
    kind, payload = case
    try:
        out = decode(kind, payload)
    except DecodeError:
        return
    assert out["v"] == 1 and math.isfinite(out["t"])


@pytest.mark.parametrize("key,kind", [
    ("pf/v1/radar/plots/b1/c2", "plots"), ("pf/v1/radar/fused/b1", "fused"),
    ("pf/v1/radar/etracks/b3", "etracks"), ("pf/v1/radar/gtracks", "gtracks"),
    ("pf/v1/sonar/detections/a1", "detections"), ("pf/v1/sonar/btracks/a1", "btracks"),
    ("pf/v1/sonar/history/a1/7", "history"), ("pf/v1/sonar/tma/a1", "tma"),
    ("pf/v1/sonar/tma/bounds/a1", "tma_bounds"), ("pf/v1/sim/truth/radar", "truth_radar"),
    ("pf/v1/sim/status", "sim_status"), ("pf/v1/metrics/tma/a1", None),
    ("pf/v1/alive/tma/a1", None), ("other/radar/gtracks", None), ("pf/v1/radar/plots/b1", None),
])
def test_kind_of_key(key: str, kind: str | None) -> None:
    assert protocol.kind_of(key, "pf/v1") == kind
