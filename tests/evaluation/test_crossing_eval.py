"""Unit tests of common.evaluation.crossing_eval on hand-made crossing sequences (1-D bearings in
degree units, so sigma = 1 and thresholds read in degrees, and a 2-D radar case)."""

from __future__ import annotations

import math

import numpy as np

from common.evaluation.crossing_eval import (
    EvalParams,
    Frame,
    RunScore,
    associate,
    score_run,
    separation,
    summarise,
)

P = EvalParams(sigma=(1.0,), gate=3.0, resolved=4.0, near=1.0, far=6.0, lost_cycles=2)


def frame(t: float, truth: list[float], tracks: dict[int, float], conf: set[int] | None = None,
          amb: set[int] = frozenset()) -> Frame:
    """Truth ids 1, 2, ... at the given positions; tracks {number: position}."""
    ids = list(tracks)
    conf = set(ids) if conf is None else conf
    return Frame.of(t, range(1, len(truth) + 1), truth, ids, [tracks[i] for i in ids],
                    [i in conf for i in ids], [i in amb for i in ids], 1)


def crossing(after: dict[int, int], steps: int = 21) -> list[Frame]:
    """Truth 1 goes -10 -> +10, truth 2 +10 -> -10 (crossing at step 10); track 7
    follows truth 1 and track 8 truth 2 until the crossing, then `after` maps
    track -> truth followed."""
    out = []
    for k in range(steps):
        x1, x2 = -10.0 + k, 10.0 - k
        follow = {7: 1, 8: 2} if k <= 10 else after
        tracks = {trk: (x1 if tr == 1 else x2) + 0.3 for trk, tr in follow.items()}
        out.append(frame(float(k), [x1, x2], tracks))
    return out


def test_kept_identities_no_swap() -> None:
    s = score_run(crossing({7: 1, 8: 2}), P)
    assert (s.swaps, s.lost) == (0, 0)


def test_exchanged_identities_are_two_swaps() -> None:
    s = score_run(crossing({7: 2, 8: 1}), P)
    assert (s.swaps, s.lost) == (2, 0)


def test_changes_while_unresolved_are_ignored() -> None:
    frames = crossing({7: 1, 8: 2})
    # at steps 8-12 the truths are within 4 of each other: the nearest track flips
    frames[9] = frame(9.0, [-1.0, 1.0], {7: 1.0, 8: -1.0})
    frames[11] = frame(11.0, [1.0, -1.0], {7: -1.0, 8: 1.0})
    assert score_run(frames, P).swaps == 0
    frames[15] = frame(15.0, [5.0, -5.0], {7: -5.0, 8: 5.0})  # resolved: out and back
    assert score_run(frames, P).swaps == 4


def test_renumbering_after_deletion_is_a_break_not_a_swap() -> None:
    frames = [frame(0.0, [0.0], {3: 0.0}), frame(1.0, [0.0], {}), frame(2.0, [0.0], {4: 0.0})]
    s = score_run(frames, P)
    assert (s.swaps, s.lost) == (0, 0)  # one uncovered cycle <= lost_cycles


def test_a_deleted_tracks_number_reused_at_once_is_another_track() -> None:
    """The single-hypothesis tracker gives a deleted track's number to a new tentative track
    in the same cycle: the truth's new number is then a break, not a swap (the number
    stayed live, the track did not)."""
    frames = [frame(0.0, [0.0], {3: 0.0}), frame(1.0, [0.0], {3: 9.0, 4: 0.0}, conf={4}),
              frame(2.0, [0.0], {3: 9.0, 4: 0.0})]
    assert score_run(frames, P).swaps == 0
    kept = [frames[0], frame(1.0, [0.0], {3: 9.0, 4: 0.0}), frames[2]]  # 3 stays confirmed
    assert score_run(kept, P).swaps == 1


def test_lost_after_more_than_lost_cycles_uncovered() -> None:
    frames = [frame(0.0, [0.0], {3: 0.0})]
    frames += [frame(float(k), [0.0], {3: 9.0}) for k in range(1, 4)]  # outside the gate
    frames.append(frame(4.0, [0.0], {3: 0.0}))
    assert score_run(frames, P).lost == 1
    assert score_run(frames[:3] + frames[4:], P).lost == 0


def test_uncovered_before_first_association_is_not_lost() -> None:
    frames = [frame(float(k), [0.0], {}) for k in range(5)] + [frame(5.0, [0.0], {3: 0.0})]
    assert score_run(frames, P).lost == 0


def test_tentative_tracks_are_not_associated() -> None:
    f = frame(0.0, [0.0, 20.0], {3: 0.1, 4: 0.5, 5: 20.0}, conf={4, 5})
    assert associate(f, P).tolist() == [4, 5]
    assert associate(frame(0.0, [0.0], {3: 0.0}, conf=set()), P).tolist() == [-1]


def test_a_track_between_two_resolved_truths_is_one_truths_and_no_swap_follows() -> None:
    """Truths 5 apart (resolved), track 7 confirmed on truth 1 and 2.8 from truth 2 whose
    own track 8 is tentative: truth 2 has no track until 8 confirms; then nothing changed
    target, so no swap (with shared association truth 2 was scored on 7, then on 8)."""
    frames = [frame(float(k), [0.0, 5.0], {7: 2.2, 8: 5.0}, conf={7} if k < 5 else {7, 8})
              for k in range(10)]
    assert associate(frames[0], P).tolist() == [7, -1]
    assert score_run(frames, P).swaps == 0


def test_bearing_wrap() -> None:
    p = EvalParams(sigma=(math.radians(1.0),), gate=3.0, angle_idx=(0,))
    f = Frame.of(0.0, [1, 2], [math.radians(359.5), math.radians(0.5)], [9], [math.radians(0.2)],
                 [True], [False], 1)
    assert associate(f, p).tolist() == [-1, 9]  # one to one: the nearer truth (0.3 deg)
    assert np.allclose(separation(f, p), 1.0)


def test_radar_scaled_two_components() -> None:
    p = EvalParams(sigma=(150.0, math.radians(1.0)), gate=3.0, angle_idx=(1,))
    truth = [[90000.0, math.radians(10.0)], [90000.0, math.radians(14.0)]]
    tracks = [[90300.0, math.radians(10.5)], [90000.0, math.radians(13.0)]]
    f = Frame.of(0.0, [1, 2], truth, [5, 6], tracks, [True, True], [False, False], 2)
    assert associate(f, p).tolist() == [5, 6]  # 2.06 and 1.0 sigma
    assert np.allclose(separation(f, p), 4.0)


def test_flag_counts_during_and_outside() -> None:
    frames = crossing({7: 1, 8: 2})
    frames = [Frame(f.t, f.truth_ids, f.truth, f.track_ids, f.tracks, f.confirmed,
                    np.full(f.track_ids.size, 8 <= f.t <= 12)) for f in frames]
    s = score_run(frames, P)
    # during: separation < 1 only at step 10 (0); outside: separation > 6 at k <= 6, k >= 14
    assert s.flag_during == (2, 2)
    assert s.flag_outside == (0, 2 * 14)


def test_summarise() -> None:
    scores = [RunScore(0, 0, (3, 4), (0, 10)), RunScore(2, 1, (1, 4), (1, 10)),
              RunScore(0, 0, (0, 0), (0, 0))]
    s = summarise(scores)
    assert (s.runs, s.swap_runs, s.swaps, s.lost_runs) == (3, 1, 2, 1)
    assert math.isclose(s.swap_rate, 1 / 3)
    assert math.isclose(s.flag_during, 0.5) and math.isclose(s.flag_outside, 0.05)
    assert math.isnan(summarise([]).swap_rate)


def _flagged(frames: list[Frame], until: float) -> list[Frame]:
    """The same frames with every track flagged ambiguous up to time `until`."""
    return [Frame(f.t, f.truth_ids, f.truth, f.track_ids, f.tracks, f.confirmed,
                  np.full(f.track_ids.size, f.t <= until)) for f in frames]


def test_an_exchange_that_outlives_the_flag_is_an_unflagged_swap() -> None:
    """The exchanged crossing: each truth's new track keeps it unflagged from step 14 on
    (the first resolved cycle), so both swaps are unflagged; flagged to step 19, one
    clear cycle (step 20) is not enough; flagged to 18, two clear cycles are."""
    swapped = crossing({7: 2, 8: 1})
    s = score_run(swapped, P)
    assert (s.swaps, s.unflagged_swaps) == (2, 2)
    assert score_run(_flagged(swapped, 19.0), P).unflagged_swaps == 0
    assert score_run(_flagged(swapped, 18.0), P).unflagged_swaps == 2
    kept = score_run(_flagged(crossing({7: 1, 8: 2}), 12.0), P)
    assert (kept.swaps, kept.unflagged_swaps) == (0, 0)


def test_a_swap_undone_before_two_clear_cycles_is_not_unflagged() -> None:
    """Out at step 15 and back at step 16 (both resolved, unflagged): four swaps, the
    first two lasting one cycle, the last two undoing them: none unflagged."""
    frames = crossing({7: 1, 8: 2})
    frames[15] = frame(15.0, [5.0, -5.0], {7: -5.0, 8: 5.0})
    s = score_run(frames, P)
    assert (s.swaps, s.unflagged_swaps) == (4, 0)
    frames[16] = frame(16.0, [6.0, -6.0], {7: -6.0, 8: 6.0})  # two cycles out: unflagged
    assert score_run(frames, P).unflagged_swaps == 2


def test_summary_counts_unflagged_swap_runs() -> None:
    scores = [RunScore(2, 0, (0, 0), (0, 0), 1), RunScore(2, 0, (0, 0), (0, 0), 0)]
    assert summarise(scores).unflagged_swap_runs == 1
