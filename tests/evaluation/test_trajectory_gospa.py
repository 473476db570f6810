"""Tests of common.evaluation.trajectory_gospa: the joint (over time) assignment of the
trajectory GOSPA metric against hand-built crossings and against brute force."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from common.evaluation.metrics import MetricsAccumulator, count_switches
from common.evaluation.trajectory_gospa import joint_assignment

C, GAMMA = 10.0, 10.0


def _frame(truths: list[float], tracks: list[float], track_ids: list[int] | None = None):
    ids = track_ids if track_ids is not None else [7 + k for k in range(len(tracks))]
    return (np.arange(1, len(truths) + 1), np.array(truths, dtype=float).reshape(-1, 1),
            np.array(ids), np.array(tracks, dtype=float).reshape(-1, 1))


def test_tracks_passing_each_others_truth_briefly_keep_their_truths():
    """Truths at 0 and 4; for two steps each track is nearer the other truth (as a
    position error along the line joining them): the per-step assignment exchanges the
    tracks twice, the joint one keeps them (4 units^2 saved per step < two switches)."""
    steps = [([0.0, 4.0], [0.5, 3.5])] * 3 + [([0.0, 4.0], [2.2, 1.8])] * 2 + [([0.0, 4.0], [0.5, 3.5])] * 3
    acc = MetricsAccumulator(C, 2.0, GAMMA)
    for t, (x, y) in enumerate(steps):
        f = _frame(x, y)
        acc.add(float(t), f[0], f[1], f[2], f[3])
    assert count_switches(acc.associations).switches == 4
    joint = acc.joint_associations()
    assert count_switches(joint).switches == 0
    assert all(step == {1: 7, 2: 8} for step in joint)


def test_tracks_that_exchange_their_truths_for_good_are_switches():
    """After 20 steps each track follows the other truth for 20 more: one switch per
    truth (keeping the first pairs would cost 2 x 3.6^2 per step, more than 2 gamma^2 in
    the end)."""
    frames = [_frame([0.0, 4.0], [0.2, 3.8])] * 20 + [_frame([0.0, 4.0], [3.8, 0.2])] * 20
    joint = joint_assignment(frames, C, GAMMA)
    assert count_switches(joint).switches == 2
    assert joint[-1] == {1: 8, 2: 7}


def test_a_truth_takes_a_new_track_when_its_own_is_deleted():
    frames = [_frame([0.0], [0.1], [7])] * 3 + [_frame([0.0], [], [])] + [_frame([0.0], [0.1], [9])] * 3
    joint = joint_assignment(frames, C, GAMMA)
    assert [s[1] for s in joint] == [7, 7, 7, None, 9, 9, 9]


def _cost(series: list[dict[int, int | None]], frames) -> float:
    """Trajectory GOSPA cost (p = 2) of an assignment series, by its definition."""
    total = 0.0
    for k, (tid, tp, kid, kp) in enumerate(frames):
        pos = {int(j): float(y[0]) for j, y in zip(kid, kp)}
        used = [j for j in series[k].values() if j is not None]
        for i, x in zip(tid.tolist(), tp[:, 0]):
            j = series[k][i]
            total += C**2 / 2 if j is None else (x - pos[j]) ** 2
        total += C**2 / 2 * (len(kid) - len(used))
        if k + 1 < len(frames):
            for i in set(series[k]) & set(series[k + 1]):
                a, b = series[k][i], series[k + 1][i]
                if a != b:
                    total += GAMMA**2 / 2 * ((a is not None) + (b is not None))
    return total


def _all_assignments(frame) -> list[dict[int, int | None]]:
    """Every partial one-to-one assignment of one frame's pairs closer than C."""
    tid, tp, kid, kp = frame
    out = []
    for choice in itertools.product([None, *range(len(kid))], repeat=len(tid)):
        taken = [c for c in choice if c is not None]
        if len(taken) != len(set(taken)):
            continue
        if any(c is not None and abs(tp[i, 0] - kp[c, 0]) >= C for i, c in enumerate(choice)):
            continue
        out.append({int(tid[i]): (None if c is None else int(kid[c])) for i, c in enumerate(choice)})
    return out


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.lists(st.floats(-12.0, 12.0), min_size=0, max_size=2),
                          st.lists(st.floats(-12.0, 12.0), min_size=0, max_size=3)),
                min_size=1, max_size=4))
def test_the_joint_assignment_reaches_the_brute_force_minimum(steps):
    """Two truths, up to three tracks, up to four steps (truth 1 and track 7 are the
    ones present when a step has one): the LP's assignment costs the exhaustive minimum."""
    frames = [_frame(x, y) for x, y in steps]
    best = min(_cost(list(s), frames) for s in itertools.product(*map(_all_assignments, frames)))
    assert abs(_cost(joint_assignment(frames, C, GAMMA), frames) - best) < 1e-6
