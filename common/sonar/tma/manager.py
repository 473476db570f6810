"""Per-array TMA bookkeeping behind ``pfusion tma``: one :class:`~common.sonar.tma.constrained.TmaTracker`
per confirmed bearing track (seeds 002 and 003), fed from the bearing tracker's cycles and
registers; pure (no Zenoh, no clock: driven by message time only).

Typed boundary: btracks cycles come in as :class:`BTracks`, history replies as
:class:`TrackHistory`, and each cycle leaves as a :class:`TmaReport`; common.wire.sonar_messages
builds and parses the messages.

Bearings: the detections the bearing tracker associated with the track, with their
sigmas and own-ship positions, from its bearing register (the history queryable,
common.sonar.bearing.history), fetched when the track is new and whenever its TMA cycle
is due. They are independent with a known sigma, so the TMA covariance P is the true
one to first order, unlike the filtered bearings x[0] of btracks (issue 13; figures:
docs/decisions/008-tma-on-detections.md). btracks gives the confirmed tracks and the cycle times; ``sample_dt``
thins the bearings.

Decimation: a track's TMA cycle (one ``TmaTracker.update`` with every bearing buffered
since its previous cycle) runs when ``cycle_dt`` seconds of message time have passed.
"""

from __future__ import annotations

from collections import OrderedDict, deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from common.core.params import ANGLE, Params, Range, Rule, count, non_negative, order, positive
from common.core.rejection import Rejected
from common.sonar.tma.bearings_only import Support
from common.sonar.tma.bounds import MINIMAL_BOUNDS, TWO_PI, Bounds
from common.sonar.tma.constrained import CtmaParams, CycleOutput, TmaTracker
from common.sonar.tma.operator_inputs import Accepted, ClearWhat, OperatorInputs


@dataclass(frozen=True)
class BTrack:
    """One track of a seed 000 btracks cycle as TMA reads it: number, confirmed or not,
    state x (bearing first) and covariance P flattened row by row."""

    id: int
    confirmed: bool
    x: np.ndarray
    P: np.ndarray


@dataclass(frozen=True)
class BTracks:
    """One seed 000 btracks cycle of an array: its time and tracks, in message order."""

    t: float
    array: str
    tracks: list[BTrack]


@dataclass(frozen=True)
class TrackHistory:
    """The seed 000 bearing register of one track as served: number, status ("confirmed"
    or "deleted") and rows (n, 5) t, brg, sbrg, own_x, own_y in served order."""

    id: int
    status: str
    rows: np.ndarray


@dataclass(frozen=True)
class TmaReport:
    """One TMA cycle of an array (seeds 002, 003): the latest solution of every live
    track, as (track number, cycle output) in track order, and the (number, birth) of
    every track of the cycle (common.sonar.tma.operator_inputs)."""

    t: float
    array: str
    solutions: list[tuple[int, CycleOutput]]
    births: list[tuple[int, float]] = field(default_factory=list)


@dataclass(frozen=True)
class TmaParams(Params):
    """``[sonar.tma]``: decimation and buffering of the TMA service.

    cycle_dt: message-time seconds between two TMA cycles of a track (0: every btracks cycle).
    sample_dt: minimum spacing (s) of the bearings kept for TMA (0: keep all).
    own_keep: own-ship positions kept for matching btracks by time.
    max_pending: btracks messages that may wait for their own-ship position.
    state_dir: folder where the service keeps the operator's TMA inputs of each array
        (tma-<array>.json), read back at its start ("": not kept, a restart forgets them).
    """

    cycle_dt: float = 60.0
    sample_dt: float = 0.0
    own_keep: int = 64
    max_pending: int = 8
    state_dir: str = ""

    RANGES: ClassVar[dict[str, Range]] = {
        "cycle_dt": non_negative("s"), "sample_dt": non_negative("s"),
        "own_keep": count(1), "max_pending": count(0),
    }


@dataclass(frozen=True)
class SupportParams(Params):
    """``[sonar.tma.support]``: course and speed support values of 002 (claims 3-10).

    Values from another source, given to every track of the array from its first cycle
    (at that time). A range is only given at run time (``sonar/tma/support/<array>``): it
    belongs to one track, one time and one observing position.

    course, course_sigma: target course (rad, clockwise from North) and its sigma (rad);
        course_sigma = 0: no course support.
    speed, speed_sigma: target speed (m/s) and its sigma (m/s); speed_sigma = 0: none.
    """

    course: float = 0.0
    course_sigma: float = 0.0
    speed: float = 0.0
    speed_sigma: float = 0.0

    RANGES: ClassVar[dict[str, Range]] = {
        "course": ANGLE, "course_sigma": non_negative("rad"),
        "speed": non_negative("m/s"), "speed_sigma": non_negative("m/s"),
    }

    def supports(self, t: float) -> list[Support]:
        """The configured support values at time t."""
        out = []
        if self.course_sigma > 0:
            out.append(Support("course", self.course, self.course_sigma, t))
        if self.speed_sigma > 0:
            out.append(Support("speed", self.speed, self.speed_sigma, t))
        return out


BOUNDS_FIELDS = ("r_min", "r_max", "course_min", "course_max", "speed_min", "speed_max")


@dataclass(frozen=True)
class BoundsParams(Params):
    """``[sonar.tma.bounds]`` and per-array ``[sonar.tma.bounds.<array>]`` (003).

    r_min, r_max: range bounds (m).
    course_min, course_max: course interval clockwise from course_min to course_max
        (rad; equal values mean no course bound).
    speed_min, speed_max: speed bounds (m/s).
    Defaults: the minimal bounds of 003 Fig. 5.
    """

    r_min: float = MINIMAL_BOUNDS.r_min
    r_max: float = MINIMAL_BOUNDS.r_max
    course_min: float = 0.0
    course_max: float = TWO_PI
    speed_min: float = MINIMAL_BOUNDS.v_min
    speed_max: float = MINIMAL_BOUNDS.v_max

    RANGES: ClassVar[dict[str, Range]] = {
        "r_min": non_negative("m"), "r_max": positive("m"),
        "course_min": ANGLE, "course_max": ANGLE,
        "speed_min": non_negative("m/s"), "speed_max": positive("m/s"),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (order("r_min", "r_max"), order("speed_min", "speed_max"))


def make_bounds(p: BoundsParams) -> Bounds:
    """Checked seed 003 :class:`Bounds` (of the configuration or of a bounds message).

    Requires 0 <= r_min < r_max, 0 <= speed_min < speed_max, courses in [0, 2 pi].
    """
    r0, r1, k0, k1, v0, v1 = (float(getattr(p, k)) for k in BOUNDS_FIELDS)
    if not all(np.isfinite((r0, r1, k0, k1, v0, v1))):
        raise Rejected("bad_bounds", "bounds must be finite")
    if not 0.0 <= r0 < r1:
        raise Rejected("bad_bounds", f"need 0 <= r_min < r_max, got {r0}, {r1}")
    if not 0.0 <= v0 < v1:
        raise Rejected("bad_bounds", f"need 0 <= speed_min < speed_max, got {v0}, {v1}")
    if not (0.0 <= k0 <= TWO_PI and 0.0 <= k1 <= TWO_PI):
        raise Rejected("bad_bounds", f"courses must be in [0, 2pi], got {k0}, {k1}")
    return Bounds(r0, r1, k0, k1, v0, v1)


def thin(t: np.ndarray, dt: float, t_prev: float) -> np.ndarray:
    """Mask of the times kept so that kept times are >= dt apart (greedy, in order),
    the first one >= dt after ``t_prev``."""
    keep = np.zeros(t.size, bool)
    last = t_prev
    for i, ti in enumerate(t):
        if ti - last >= dt:
            keep[i] = True
            last = ti
    return keep


@dataclass
class TrackTma:
    """One confirmed track: its TmaTracker, the bearings buffered for its next cycle
    (rows t, brg, sbrg, own_x, own_y), its latest cycle output and the configured
    support values it started with."""

    tracker: TmaTracker
    config_support: list[Support] = field(default_factory=list)
    t_last: float = -np.inf
    t_kept: float = -np.inf
    t_cycle: float = -np.inf
    buf: list[np.ndarray] = field(default_factory=list)
    out: CycleOutput | None = None
    failures: int = 0

    def add(self, rows: np.ndarray, sample_dt: float) -> None:
        """Buffer rows later than any bearing seen, thinned to sample_dt spacing."""
        rows = rows[rows[:, 0] > self.t_last]
        if rows.size == 0:
            return
        self.t_last = float(rows[-1, 0])
        rows = rows[thin(rows[:, 0], sample_dt, self.t_kept)]
        if rows.size:
            self.t_kept = float(rows[-1, 0])
            self.buf.append(rows)

    def cycle(self, t: float, cycle_dt: float) -> bool:
        """Run one TMA/CTMA cycle if due and bearings are buffered; True if it ran.

        A singular system (e.g. a constant bearing: target on a collision course, range
        unobservable) keeps the previous output; the bearings stay in the tracker.
        """
        if not self.buf or t - self.t_cycle < cycle_dt:
            return False
        rows = np.concatenate(self.buf)
        self.buf.clear()
        self.t_cycle = t
        try:
            out = self.tracker.update(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3:5])
        except np.linalg.LinAlgError:
            self.failures += 1
            return True
        if out is not None:
            self.out = out
        return True


class TmaManager:
    """TMA of every confirmed bearing track of one array.

    Use: :meth:`add_own` per detections message, :meth:`push` per btracks message, then
    for each cycle from :meth:`ready`: :meth:`history_wanted` (the tracks whose history
    the caller fetches), :meth:`step` (returns the TMA report).
    """

    def __init__(self, array: str, params: TmaParams = TmaParams(), bounds: Bounds = MINIMAL_BOUNDS,
                 config: CtmaParams = CtmaParams(), support: SupportParams = SupportParams()) -> None:
        self.array = array
        self.params = params
        self.support = support
        self.bounds = bounds
        self.config = config
        self.tracks: dict[int, TrackTma] = {}
        self.own: OrderedDict[float, tuple[float, float]] = OrderedDict()
        self.pending: deque[BTracks] = deque()
        self.t_pushed = -np.inf
        self.cycles = 0
        self.inputs = OperatorInputs()

    def add_own(self, t: float, x: float, y: float) -> None:
        """Own-ship position at detection time t."""
        self.own[t] = (x, y)
        while len(self.own) > self.params.own_keep:
            self.own.popitem(last=False)

    def push(self, b: BTracks) -> None:
        """Queue a btracks cycle after checking it (array, time order, x and P)."""
        if b.array != self.array:
            raise Rejected("unknown_array", f"array '{b.array}'")
        if not b.t > self.t_pushed:
            raise Rejected("time_order", f"t={b.t} is not after t={self.t_pushed}")
        for tr in b.tracks:
            n = len(tr.x)
            if n < 2 or len(tr.P) != n * n or not tr.P[0] > 0:
                raise Rejected("bad_btrack", f"track {tr.id}: x needs >= 2 entries, P n*n, P[0] > 0")
            if not 0.0 <= tr.x[0] <= TWO_PI:
                raise Rejected("bad_btrack", f"track {tr.id}: bearing x[0] not in [0, 2pi]")
        self.t_pushed = b.t
        self.pending.append(b)
        self.inputs.observe(b.t, [(tr.id, tr.confirmed) for tr in b.tracks])

    def ready(self) -> tuple[list[BTracks], int]:
        """Queued btracks cycles whose own-ship position is known (in time order), and the
        number dropped because it never came (a later one did, or the queue overflowed)."""
        out: list[BTracks] = []
        dropped = 0
        latest = next(reversed(self.own)) if self.own else -np.inf
        while self.pending:
            t = self.pending[0].t
            if t in self.own:
                out.append(self.pending.popleft())
            elif latest > t or len(self.pending) > self.params.max_pending:
                self.pending.popleft()
                dropped += 1
            else:
                break
        return out, dropped

    def history_wanted(self, b: BTracks) -> list[int]:
        """Confirmed tracks of ``b`` whose history the caller fetches before :meth:`step`:
        those without a TmaTracker yet and those whose TMA cycle is due."""
        return [tr.id for tr in b.tracks if tr.confirmed
                and (tr.id not in self.tracks or b.t - self.tracks[tr.id].t_cycle >= self.params.cycle_dt)]

    def step(self, b: BTracks, histories: Mapping[int, TrackHistory | None]) -> TmaReport:
        """Process one btracks cycle (own ship known) and return the TMA report.

        Tracks no longer confirmed are dropped; a track given its history (its own,
        confirmed) buffers the detections it has not seen; due tracks run a cycle.
        """
        t = b.t
        live = {tr.id for tr in b.tracks if tr.confirmed}
        for tid in [k for k in self.tracks if k not in live]:
            del self.tracks[tid]
        for tid in live:
            trk = self.tracks.get(tid)
            if trk is None:
                trk = self.tracks[tid] = TrackTma(TmaTracker(self.bounds, self.config),
                                                  self.support.supports(t))  # 002 claims 3-10
                self._apply(tid)
            h = histories.get(tid)
            if h is not None and h.status == "confirmed" and h.id == tid:
                rows = h.rows
                trk.add(rows[np.argsort(rows[:, 0], kind="stable")], self.params.sample_dt)
            self.cycles += trk.cycle(t, self.params.cycle_dt)
        sols = [(tid, trk.out) for tid, trk in sorted(self.tracks.items()) if trk.out is not None]
        births = [(tr.id, self.inputs.birth[tr.id]) for tr in b.tracks if tr.id in self.inputs.birth]
        return TmaReport(t, self.array, sols, births)

    def add_support(self, track: int, s: Support, birth: float | None = None) -> Accepted:
        """Give a support value (002 claims 3-10) to a live track (of that birth, if
        given): it enters every later TMA/CTMA solve of the track until the track ends
        or the value is cleared (Rejected: common.sonar.tma.operator_inputs.resolve)."""
        a = self.inputs.resolve(track, birth)
        self.inputs.add_support(a, s)
        self._apply(track)
        return a

    def set_bounds(self, b: Bounds, tid: int | None = None, birth: float | None = None) -> list[int]:
        """Apply seed 003 bounds; returns the tracks changed.

        Without ``tid``: the array's default for the tracks without bounds of their own;
        with it: that live track's own (of that birth, if given; else Rejected as by
        :meth:`add_support`). The bounds are those of the track's current target leg:
        after a manoeuvre they bound the new leg, and the earlier legs keep the bounds
        they had (003 claim 9), so the message needs no leg.
        """
        if tid is None:
            self.bounds = b
            self.inputs.set_default(b)
            ids = list(self.tracks)
        else:
            self.inputs.set_bounds(self.inputs.resolve(tid, birth), b)
            ids = [tid] if tid in self.tracks else []
        for i in ids:
            self._apply(i)
        return [i for i in ids if self.tracks[i].tracker.bounds is b]

    def clear(self, track: int, what: ClearWhat, birth: float | None = None) -> Accepted:
        """Forget the operator's bounds, support values or both of a live track."""
        a = self.inputs.resolve(track, birth)
        self.inputs.clear(a, what)
        self._apply(track)
        return a

    def restore(self, inputs: OperatorInputs) -> None:
        """The operator inputs kept by a previous run (before any btracks cycle)."""
        self.inputs = inputs
        self.bounds = inputs.default or self.bounds

    def _apply(self, tid: int) -> None:
        """Bounds and support values of a track with a TMA: the operator's, else the
        array's bounds and the configured support values."""
        trk = self.tracks.get(tid)
        if trk is None:
            return
        inp = self.inputs.of(tid)
        own = inp.bounds if inp is not None else None
        trk.tracker.bounds = own or self.bounds
        trk.tracker.support[:] = [*trk.config_support, *(inp.support if inp is not None else ())]
