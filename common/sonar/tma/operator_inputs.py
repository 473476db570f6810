"""Operator inputs of the TMA service per track (issue 31): seed 003 bounds (claim 4) and
seed 002 support values (claims 3-10) entered for one bearing track, keyed by (track
number, birth) so that a number reused by a new track never inherits them; pure (no
Zenoh, no files, no clock: message time only).

Birth of a track: the time of the first btracks cycle in which its number appears, or
appears again as tentative after being confirmed (the tracker recycles numbers, and a
new track starts tentative). A number absent from a cycle ends its track: its inputs
are dropped. :meth:`OperatorInputs.state` and :meth:`OperatorInputs.from_state` give the
JSON-able form the service keeps across a restart: the births and last status of the
live tracks and the inputs, so that the first cycle after a restart ends or keeps them
by the same rule (a number deleted and reused while the service was down by a track
already confirmed at the restart is taken for the old track).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from common.core.rejection import Rejected
from common.sonar.tma.bearings_only import Support
from common.sonar.tma.bounds import Bounds

ClearWhat = Literal["bounds", "support", "all"]
STATE_VERSION = 1
SUPPORT_KINDS = ("range", "course", "speed")


@dataclass
class TrackInputs:
    """What an operator entered for one track: its bounds (None: the array's) and its
    support values, in entry order."""

    birth: float
    bounds: Bounds | None = None
    support: list[Support] = field(default_factory=list)


@dataclass(frozen=True)
class Accepted:
    """The (track, birth) an input was accepted for."""

    track: int
    birth: float


class OperatorInputs:
    """Track births of one array and the operator inputs of its live tracks.

    Use: :meth:`observe` per btracks cycle (in time order); :meth:`resolve` then
    :meth:`set_bounds`, :meth:`add_support` or :meth:`clear` per operator request;
    :meth:`of` for the inputs of a live track.
    """

    def __init__(self) -> None:
        self.birth: dict[int, float] = {}
        self.confirmed: dict[int, bool] = {}
        self.inputs: dict[int, TrackInputs] = {}
        self.default: Bounds | None = None
        self.changed = False

    def observe(self, t: float, tracks: list[tuple[int, bool]]) -> list[int]:
        """One btracks cycle at t: (number, confirmed) of its tracks. Returns the
        numbers whose inputs were dropped (their track ended, or the number was reused)."""
        kept = self._kept()
        birth, confirmed = {}, {}
        for tid, conf in tracks:
            reborn = tid not in self.birth or (self.confirmed[tid] and not conf)
            birth[tid] = t if reborn else self.birth[tid]
            confirmed[tid] = conf
        dropped = [tid for tid, inp in self.inputs.items()
                   if tid not in birth or birth[tid] != inp.birth]
        for tid in dropped:
            del self.inputs[tid]
        self.birth, self.confirmed = birth, confirmed
        self.changed |= bool(dropped) or kept != self._kept()
        return dropped

    def _kept(self) -> dict[int, tuple[float, bool]]:
        """(birth, confirmed) of the tracks whose birth a restart keeps: the confirmed
        ones and those with inputs (a tentative track's birth is reset by a restart)."""
        return {tid: (b, self.confirmed[tid]) for tid, b in self.birth.items()
                if self.confirmed[tid] or tid in self.inputs}

    def set_default(self, b: Bounds) -> None:
        """The array's bounds at run time (of the tracks without their own)."""
        self.default = b
        self.changed = True

    def resolve(self, track: int, birth: float | None) -> Accepted:
        """The live track an input names: its number and, if given, its birth (Rejected
        ``unknown_track`` when the number is not live, ``stale_birth`` when it now
        belongs to a track born at another time)."""
        if track not in self.birth:
            raise Rejected("unknown_track", f"track {track} is not a live track of the array")
        if birth is not None and birth != self.birth[track]:
            raise Rejected("stale_birth", f"track {track} was born at t={self.birth[track]}, "
                                          f"not at t={birth} (the number was reused)")
        return Accepted(track, self.birth[track])

    def _entry(self, a: Accepted) -> TrackInputs:
        inp = self.inputs.get(a.track)
        if inp is None:
            inp = self.inputs[a.track] = TrackInputs(a.birth)
        self.changed = True
        return inp

    def set_bounds(self, a: Accepted, b: Bounds) -> None:
        """Seed 003 bounds (claim 4) for the resolved track."""
        self._entry(a).bounds = b

    def add_support(self, a: Accepted, s: Support) -> None:
        """A seed 002 support value (claims 3-10) for the resolved track."""
        self._entry(a).support.append(s)

    def clear(self, a: Accepted, what: ClearWhat) -> None:
        """Forget the resolved track's bounds, support values or both."""
        inp = self.inputs.get(a.track)
        if inp is None:
            return
        if what in ("bounds", "all"):
            inp.bounds = None
        if what in ("support", "all"):
            inp.support.clear()
        if inp.bounds is None and not inp.support:
            del self.inputs[a.track]
        self.changed = True

    def of(self, track: int) -> TrackInputs | None:
        """The inputs of a live track (None: none entered)."""
        return self.inputs.get(track)

    def state(self) -> dict[str, Any]:
        """Births and inputs as JSON-able data (numbers, lists, strings)."""
        inputs = [{"track": tid, "birth": inp.birth, "bounds": _bounds_list(inp.bounds),
                   "support": [[s.kind, s.value, s.sigma, s.t, *s.obs_xy] for s in inp.support]}
                  for tid, inp in sorted(self.inputs.items())]
        births = [[tid, b, c] for tid, (b, c) in sorted(self._kept().items())]
        return {"version": STATE_VERSION, "default": _bounds_list(self.default),
                "births": births, "inputs": inputs}

    @classmethod
    def from_state(cls, doc: dict[str, Any]) -> OperatorInputs:
        """The births and inputs of :meth:`state` (Rejected ``bad_state`` for anything
        else)."""
        out = cls()
        try:
            if doc["version"] != STATE_VERSION:
                raise ValueError(f"version {doc['version']}")
            out.default = _bounds(doc["default"])
            for tid, birth, conf in doc["births"]:
                out.birth[int(tid)], out.confirmed[int(tid)] = float(birth), bool(conf)
            for e in doc["inputs"]:
                tid, birth = int(e["track"]), float(e["birth"])
                if out.birth.get(tid) != birth:
                    raise ValueError(f"inputs of track {tid} born at {birth}: not a live track")
                sup = [Support(k, float(v), float(s), float(t), (float(x), float(y)))
                       for k, v, s, t, x, y in e["support"]]
                if any(s.kind not in SUPPORT_KINDS for s in sup):
                    raise ValueError(f"support kinds of track {tid} not in {SUPPORT_KINDS}")
                out.inputs[tid] = TrackInputs(birth, _bounds(e["bounds"]), sup)
        except (KeyError, TypeError, ValueError) as e:
            raise Rejected("bad_state", f"TMA input state not readable: {e!r}") from None
        return out


def _bounds_list(b: Bounds | None) -> list[float] | None:
    return None if b is None else [b.r_min, b.r_max, b.k_min, b.k_max, b.v_min, b.v_max]


def _bounds(v: list[float] | None) -> Bounds | None:
    return None if v is None else Bounds(*(float(x) for x in v))
