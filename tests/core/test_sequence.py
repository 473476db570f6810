"""Publisher stamps and the count of samples that never arrived (common.core.sequence,
common.bus.transport.stamp / read_stamp)."""

from __future__ import annotations

import msgpack
import pytest
from hypothesis import given
from hypothesis import strategies as st

from common.bus.transport import read_stamp, stamp
from common.core.sequence import SequenceCheck, StampJump


@given(st.text(max_size=40), st.integers(min_value=0, max_value=2**63 - 1))
def test_stamp_round_trip(source: str, n: int) -> None:
    assert read_stamp(stamp(source, n)) == (source, n)


@given(st.binary(max_size=64))
def test_any_bytes_are_a_stamp_or_a_value_error(b: bytes) -> None:
    try:
        source, n = read_stamp(b)
    except ValueError:
        return
    assert isinstance(source, str) and isinstance(n, int) and n >= 0


@pytest.mark.parametrize("value", [["s", -1], ["s", True], ["s", 1.0], [1, 2], ["s", 1, 2], {"s": 1}])
def test_wrong_stamps_are_refused(value: object) -> None:
    with pytest.raises(ValueError):
        read_stamp(msgpack.packb(value))


@given(st.lists(st.tuples(st.sampled_from("abc"), st.booleans()), max_size=200))
def test_missed_is_the_number_of_dropped_samples_between_received_ones(sent: list[tuple[str, bool]]) -> None:
    """Sources a, b, c each number their samples 0, 1, 2...; the receiver gets those
    flagged True. Missed = the dropped samples after each source's first received one
    and before its last received one."""
    check = SequenceCheck()
    counter = {s: 0 for s in "abc"}
    stamps: dict[str, list[tuple[int, bool]]] = {s: [] for s in "abc"}
    missed = 0
    for source, arrives in sent:
        n = counter[source]
        counter[source] += 1
        stamps[source].append((n, arrives))
        if arrives:
            missed += check.observe("k", source, n)
    expected = 0
    for seq in stamps.values():
        got = [n for n, ok in seq if ok]
        if got:
            expected += sum(1 for n, ok in seq if not ok and got[0] < n < got[-1])
    assert missed == expected


def test_restart_repeat_and_keys() -> None:
    check = SequenceCheck()
    assert check.observe("k", "s1", 5) == 0  # first stamp heard: nothing missed yet
    assert check.observe("k", "s1", 8) == 2
    assert check.observe("k", "s1", 8) == 0  # repeated
    assert check.observe("k", "s1", 7) == 0  # older
    assert check.observe("k", "s1", 9) == 0
    assert check.observe("k", "s2", 0) == 0  # a restarted publisher is a new source
    assert check.observe("other", "s1", 3) == 0  # sequences are per key


def test_a_stamp_jump_is_no_loss_and_does_not_hide_later_losses() -> None:
    seq = SequenceCheck(max_jump=10_000)
    assert seq.observe("k", "s", 0) == 0
    with pytest.raises(StampJump):
        seq.observe("k", "s", 10**12)
    assert seq.observe("k", "s", 1) == 0
    assert seq.observe("k", "s", 10_002) == 10_000  # a gap of exactly max_jump is a loss
    assert seq.observe("k", "s", 10_004) == 1
