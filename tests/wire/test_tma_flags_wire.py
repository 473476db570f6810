"""The TMA flags of issue 31 section 3 on the wire (sonar/tma/<array>, docs/protocol.md):
built from the core's CycleOutput by common.wire.sonar_messages, decoded as bools, absent
in messages of older publishers, anything but a bool refused."""

from __future__ import annotations

import msgpack
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.sonar.tma.bounds import MINIMAL_BOUNDS
from common.sonar.tma.manager import TmaReport
from common.wire.protocol import DecodeError, decode, encode
from common.wire.sonar_messages import tma_hints_from, tma_message
from tests.sonar.test_tma import OWN
from tests.sonar.test_tma_flags import STRAIGHT, run

FLAGS = ("converged", "ctma_exhausted", "range_observable")


def _message(own=OWN) -> dict:
    out = run(own, MINIMAL_BOUNDS)[-1]
    msg = tma_message(TmaReport(out.t, "a1", [(4, out)]))
    return msgpack.unpackb(encode(msg), raw=False)


MSG = _message()


def test_flags_published_and_decoded_as_bools():
    (s,) = decode("tma", encode(MSG))["solutions"]
    assert all(type(s[f]) is bool for f in FLAGS)
    assert s["converged"] and s["range_observable"] and not s["ctma_exhausted"]
    (one_leg,) = decode("tma", encode(_message(STRAIGHT)))["solutions"]
    assert not one_leg["range_observable"]


def test_flags_absent_from_older_publishers_still_decode():
    old = {**MSG, "solutions": [{k: v for k, v in MSG["solutions"][0].items() if k not in FLAGS}]}
    (s,) = decode("tma", encode(old))["solutions"]
    assert not any(f in s for f in FLAGS)


not_bool = st.one_of(
    st.none(), st.integers(-(2**63), 2**64 - 1), st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5), st.binary(max_size=5), st.lists(st.booleans(), max_size=3),
    st.dictionaries(st.text(max_size=3), st.booleans(), max_size=2),
)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(FLAGS), not_bool)
def test_decoder_refuses_non_bool_flags(flag: str, value: object):
    bad = {**MSG, "solutions": [{**MSG["solutions"][0], flag: value}]}
    with pytest.raises(DecodeError) as e:
        decode("tma", msgpack.packb(bad, use_bin_type=True))
    assert e.value.field == f"solutions[0].{flag}"


def test_tma_hints_for_the_bearing_tracker():
    """What the bearing-tracker service takes from sonar/tma/<a> (issue 31 section 1): the
    solution with its P and flags; an older publisher's solution, without flags, is neither
    converged nor usable, so it never predicts a bearing (common.sonar.bearing.tma_prediction)."""
    ((tid, h),) = tma_hints_from(decode("tma", encode(MSG)))
    s = MSG["solutions"][0]
    assert tid == 4 and (h.t, h.x, h.y, h.vx, h.vy) == (s["t"], s["x"], s["y"], s["vx"], s["vy"])
    assert h.converged and h.usable and h.P is not None and h.P.shape == (4, 4)
    old = {**MSG, "solutions": [{k: v for k, v in s.items() if k not in FLAGS}]}
    ((_, h_old),) = tma_hints_from(decode("tma", encode(old)))
    assert not h_old.converged and not h_old.usable
