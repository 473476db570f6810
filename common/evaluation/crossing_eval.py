"""Per-run scoring of a two-target crossing (seed 004 evaluation): track number swaps,
lost truths and the published ambiguity flag.

Pure: frames in, counts out. A frame is one tracker cycle with the truths and the live
tracks expressed in the same measurement space (sonar: [bearing]; radar: [r_b, theta]).
Distances are Euclidean on components divided by `EvalParams.sigma`, angle components
wrapped to [-pi, pi).

Association (per cycle): truths and confirmed tracks one to one, the assignment of least
total distance over the pairs within `gate` (`one_to_one`), never one track for two
truths (why, and the nearest-track rule it replaced: docs/decisions/001-crossing-scoring.md).
Swap: at a cycle where the truth is resolved (every other truth farther than
`resolved`), its associated track number differs from the one of its previous resolved
cycle while that previous track is still live. Cycles where the truths are closer
than `resolved` are skipped: there the nearest track is decided by noise, not by the
tracker. A number change after the previous track was deleted is not a swap (a break).
Unflagged swap (issue 31): a swap whose new track keeps the truth for `unflagged_cycles`
(2) resolved cycles in a row with its ambiguity flag down (a flagged cycle restarts the
count; the truth leaving that track ends it), i.e. an exchange that outlives 004's flag,
which consumers cannot tell from a good track; counted once per swap; a swap back onto
the track the truth was swapped from undoes it.
"Still live" is the track, not its number (`Numbers`): the single-hypothesis tracker
reuses the number of a deleted track at once, often in the same cycle, for a new
tentative track; a number reused so is not the live track, and a lost track replaced
by a new number is a break, not a swap (docs/decisions/001-crossing-scoring.md).
Lost: after its first association, the truth has no confirmed track within `gate` for
more than `lost_cycles` consecutive cycles.
Flag: over the cycles where a truth is associated, the fraction whose track is flagged
ambiguous while the nearest other truth is closer than `near` ("during") and while it
is farther than `far` ("outside": before and after the crossing).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from common.core.angles import wrap_pi


@dataclass(frozen=True)
class Frame:
    """One tracker cycle: truths (n, d) and live tracks (m, d) in the same space."""

    t: float
    truth_ids: np.ndarray
    truth: np.ndarray
    track_ids: np.ndarray
    tracks: np.ndarray
    confirmed: np.ndarray
    ambiguous: np.ndarray

    @classmethod
    def of(cls, t: float, truth_ids: ArrayLike, truth: ArrayLike, track_ids: ArrayLike,
           tracks: ArrayLike, confirmed: ArrayLike, ambiguous: ArrayLike, dim: int) -> "Frame":
        """Frame from array-likes; positions reshaped to (count, dim)."""
        ti = np.asarray(truth_ids, dtype=np.int64).reshape(-1)
        ki = np.asarray(track_ids, dtype=np.int64).reshape(-1)
        return cls(float(t), ti, np.asarray(truth, dtype=float).reshape(ti.size, dim), ki,
                   np.asarray(tracks, dtype=float).reshape(ki.size, dim),
                   np.asarray(confirmed, dtype=bool).reshape(-1),
                   np.asarray(ambiguous, dtype=bool).reshape(-1))


Wrong = tuple[tuple[int, int], int, tuple[int, int]]  # (track now, clear cycles, track before)


@dataclass(frozen=True)
class EvalParams:
    """Scales (per component), thresholds in scaled units, and the lost rule."""

    sigma: tuple[float, ...]
    gate: float = 5.0
    resolved: float = 6.0
    near: float = 1.0
    far: float = 8.0
    lost_cycles: int = 3
    angle_idx: tuple[int, ...] = ()
    unflagged_cycles: int = 2


@dataclass(frozen=True)
class RunScore:
    """Swaps and lost truths of one run, the flag counts (flagged, cycles), and the
    swaps that outlived the flag."""

    swaps: int
    lost: int
    flag_during: tuple[int, int]
    flag_outside: tuple[int, int]
    unflagged_swaps: int = 0


def scaled_distance(a: np.ndarray, b: np.ndarray, p: EvalParams) -> np.ndarray:
    """(n, m) Euclidean distance between rows of a and b in sigma units."""
    d = a[:, None, :] - b[None, :, :]
    if p.angle_idx:
        idx = list(p.angle_idx)
        d[..., idx] = wrap_pi(d[..., idx])
    return np.sqrt(np.sum(np.square(d / np.asarray(p.sigma)), axis=-1))


def one_to_one(d: np.ndarray, gate: float) -> np.ndarray:
    """(n,) column assigned to each row of the distances d (n, m), -1 if none: rows and
    columns one to one, least total distance over the pairs within gate (a pair beyond
    it costs more than any set of pairs within, so it is never preferred to them)."""
    out = np.full(d.shape[0], -1, dtype=np.int64)
    if d.size == 0:
        return out
    far = gate * (min(d.shape) + 1)
    r, c = linear_sum_assignment(np.where(d <= gate, d, far))
    ok = d[r, c] <= gate
    out[r[ok]] = c[ok]
    return out


def associate(f: Frame, p: EvalParams) -> np.ndarray:
    """(n,) track number of each truth's confirmed track (`one_to_one` within the gate),
    -1 if none."""
    conf = np.flatnonzero(f.confirmed)
    out = np.full(f.truth_ids.size, -1, dtype=np.int64)
    if conf.size == 0 or f.truth_ids.size == 0:
        return out
    k = one_to_one(scaled_distance(f.truth, f.tracks[conf], p), p.gate)
    out[k >= 0] = f.track_ids[conf[k[k >= 0]]]
    return out


def separation(f: Frame, p: EvalParams) -> np.ndarray:
    """(n,) scaled distance from each truth to the nearest other truth (inf if alone)."""
    d = scaled_distance(f.truth, f.truth, p)
    np.fill_diagonal(d, np.inf)
    return d.min(axis=1) if d.size else np.zeros(0)


class Numbers:
    """Which holder of each track number is live: a number seen confirmed and then absent
    or not confirmed has lost its holder (deleted, or demoted); a later confirmed track
    under it is another holder."""

    def __init__(self) -> None:
        self.holder: dict[int, int] = {}  # number -> holder count
        self.confirmed: set[int] = set()

    def step(self, f: Frame) -> set[int]:
        """The numbers of the confirmed tracks of frame f, holders updated."""
        now = set(f.track_ids[f.confirmed].tolist())
        for k in self.confirmed - now:
            self.holder[k] = self.holder.get(k, 0) + 1
        self.confirmed = now
        return now

    def tag(self, k: int) -> tuple[int, int]:
        """The track under number k now: (number, holder)."""
        return k, self.holder.get(k, 0)

    def live(self, tagged: tuple[int, int]) -> bool:
        """True when that track (number, holder) is still a confirmed track."""
        return tagged[0] in self.confirmed and self.tag(tagged[0]) == tagged


def score_run(frames: Iterable[Frame], p: EvalParams) -> RunScore:
    """Swaps, lost truths and flag counts over the frames of one run (time order)."""
    last: dict[int, tuple[int, int]] = {}
    numbers = Numbers()
    seen: set[int] = set()
    gap: dict[int, int] = {}
    lost: set[int] = set()
    swaps = unflagged = 0
    wrong: dict[int, Wrong] = {}  # truth -> its swap not yet undone
    flags = np.zeros((2, 2), dtype=np.int64)  # rows during / outside: flagged, cycles
    for f in frames:
        tracks = associate(f, p)
        sep = separation(f, p)
        numbers.step(f)
        flagged = dict(zip(f.track_ids.tolist(), f.ambiguous.tolist()))
        for truth, trk, s in zip(f.truth_ids.tolist(), tracks.tolist(), sep.tolist()):
            if trk < 0:
                if truth in seen:
                    gap[truth] = gap.get(truth, 0) + 1
                    if gap[truth] > p.lost_cycles:
                        lost.add(truth)
                continue
            seen.add(truth)
            gap[truth] = 0
            for row, inside in ((0, s < p.near), (1, s > p.far)):
                if inside:
                    flags[row] += (int(flagged[trk]), 1)
            if s > p.resolved:
                prev = last.get(truth)
                if prev is not None and prev[0] != trk and numbers.live(prev):
                    swaps += 1
                    cur = wrong.get(truth)
                    if cur is not None and cur[2] == numbers.tag(trk):
                        del wrong[truth]  # back on the track it was swapped from
                    else:
                        wrong[truth] = (numbers.tag(trk), 0, prev)
                unflagged += _outlives_flag(wrong, truth, numbers.tag(trk), flagged[trk], p)
                last[truth] = numbers.tag(trk)
    return RunScore(swaps, len(lost), (int(flags[0, 0]), int(flags[0, 1])),
                    (int(flags[1, 0]), int(flags[1, 1])), unflagged)


def _outlives_flag(wrong: dict[int, Wrong], truth: int,
                   track: tuple[int, int], flagged: bool, p: EvalParams) -> int:
    """1 when the swap of `truth` reaches `unflagged_cycles` resolved cycles with the flag
    of its new track down at this cycle, else 0; `wrong` updated in place."""
    cur = wrong.get(truth)
    if cur is None:
        return 0
    if cur[0] != track:
        del wrong[truth]
        return 0
    n = 0 if flagged else cur[1] + 1
    wrong[truth] = (track, n, cur[2])
    return int(n == p.unflagged_cycles)


@dataclass(frozen=True)
class Summary:
    """Totals over runs: runs, runs with a swap, total swaps, runs with a lost truth,
    and the flagged fractions during and outside the crossing (NaN without cycles)."""

    runs: int
    swap_runs: int
    swaps: int
    lost_runs: int
    flag_during: float
    flag_outside: float
    unflagged_swap_runs: int = 0

    @property
    def swap_rate(self) -> float:
        """Fraction of runs with at least one swap."""
        return self.swap_runs / self.runs if self.runs else float("nan")


def summarise(scores: Sequence[RunScore]) -> Summary:
    """Aggregate per-run scores."""
    fd = np.sum([s.flag_during for s in scores], axis=0) if scores else np.zeros(2)
    fo = np.sum([s.flag_outside for s in scores], axis=0) if scores else np.zeros(2)
    return Summary(
        runs=len(scores),
        swap_runs=sum(s.swaps > 0 for s in scores),
        swaps=sum(s.swaps for s in scores),
        lost_runs=sum(s.lost > 0 for s in scores),
        flag_during=float(fd[0] / fd[1]) if fd[1] else float("nan"),
        flag_outside=float(fo[0] / fo[1]) if fo[1] else float("nan"),
        unflagged_swap_runs=sum(s.unflagged_swaps > 0 for s in scores),
    )
