"""The max_ahead rule of common.radar.plots.channel_fusion.PlotFusion: one plot stamped
far in the future neither blinds its base nor stops a channel for good."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core.rejection import Rejected
from common.radar.plots.channel_fusion import PlotFusion, Plots

CHANNELS = ["c1", "c2", "c3"]


def one_plot() -> Plots:
    a = np.array
    return Plots(a([50e3]), a([100.0]), a([1.0]), a([150.0]), a([1.5]), a([0.01]))


def feed(core: PlotFusion, msgs: list[tuple[str, float]]) -> tuple[list[tuple[float, int]], list[str]]:
    """(scan time, channels fused) of every emitted scan, and the rejection reasons."""
    out, rejected = [], []
    for ch, t in msgs:
        try:
            out += [(s, int(f.n_ch.max())) for s, f in core.push(ch, t, one_plot())]
        except Rejected as e:
            rejected.append(e.reason)
    return out, rejected


def normal(n: int) -> list[tuple[str, float]]:
    return [(c, float(k)) for k in range(n) for c in CHANNELS]


def test_a_far_future_plot_after_the_start_is_rejected_and_the_base_goes_on() -> None:
    core = PlotFusion(CHANNELS, 1)
    msgs = normal(20)
    msgs.insert(14, ("c2", 1e300))
    out, rejected = feed(core, msgs)
    assert rejected == ["ahead"]
    assert out == [(float(k), 3) for k in range(20)]


def test_a_far_future_first_plot_is_evicted_by_the_next_plots() -> None:
    core = PlotFusion(CHANNELS, 1)
    out, rejected = feed(core, [("c1", 1e300), *normal(10)])
    assert rejected == [] and core.take_evicted() == [("c1", 1e300)]
    assert out == [(float(k), 3) for k in range(10)]


def test_a_single_channel_base_recovers_from_a_far_future_plot() -> None:
    core = PlotFusion(["c1"], 1)
    out, rejected = feed(core, [("c1", 0.0), ("c1", 5e9), *[("c1", float(k)) for k in range(1, 10)]])
    assert core.take_evicted() == [("c1", 5e9)] and rejected == []
    assert [s for s, _ in out] == [float(k) for k in range(10)]
    with pytest.raises(Rejected, match="ahead"):
        core.push("c1", 1e6, one_plot())


@settings(max_examples=200, deadline=None)
@given(at=st.integers(0, 45), channel=st.sampled_from(CHANNELS),
       ahead=st.one_of(st.floats(61.0, 1e6), st.just(1e300), st.floats(1e9, 1e15)))
def test_no_single_message_stops_a_channel_for_good(at: int, channel: str, ahead: float) -> None:
    """Any one far-future plot anywhere in a clean 16-scan stream: every clean scan is
    still published with all three channels fused."""
    msgs = normal(16)
    t_bad = msgs[min(at, len(msgs) - 1)][1] + ahead
    msgs.insert(at, (channel, t_bad))
    out, rejected = feed(PlotFusion(CHANNELS, 1), msgs)
    assert set(rejected) <= {"ahead"}
    assert out == [(float(k), 3) for k in range(16)]


def test_a_jump_of_the_whole_base_clock_is_taken_once_a_majority_agrees() -> None:
    """All three channels jump 1000 s: the first jumped plot is rejected, the second
    (a majority with it) takes the jump, every later scan is fused from all channels."""
    jumped = [(c, t + (1000.0 if t >= 5 else 0.0)) for c, t in normal(10)]
    out, rejected = feed(PlotFusion(CHANNELS, 1), jumped)
    assert rejected == ["ahead"]
    assert out[:5] == [(float(k), 3) for k in range(5)]
    assert out[5] == (1005.0, 2) and out[6:] == [(1000.0 + k, 3) for k in range(6, 10)]


def test_a_single_channel_base_takes_a_jump_on_its_second_plot() -> None:
    core = PlotFusion(["c1"], 1)
    out, rejected = feed(core, [("c1", float(k)) for k in range(5)] + [("c1", 1000.0 + k) for k in range(5, 8)])
    assert rejected == ["ahead"] and [s for s, _ in out] == [0.0, 1.0, 2.0, 3.0, 4.0, 1006.0, 1007.0]
