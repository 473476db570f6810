"""The arrival rule of global fusion: which bases a cycle waits for, and which reports
it refuses (docs/faults.md). Wall time is an argument (`now`, seconds from any origin),
never read from a clock: the service passes its monotonic clock, the in-process chain
the message time.

A base that has sent nothing usable for `max_wait` s of wall time (since its last
accepted report, or since the first report of any base) is stale: the cycles run
without it (common.radar.fusion.cycle says why wall time and not message time).
Rejected (common.core.rejection.Rejected):
- time_backwards: a report whose cycle already ran (late, out of order, or a base whose
  clock jumped back). One at most `max_wait` s of message time behind the latest cycle
  still shows its base alive, so the next cycle waits for it: a stale base whose stream
  runs slightly behind the others' (a site back after a cut link, issue 12) would
  otherwise stay stale for as long as its reports arrive after the others'.
- duplicate: a second report of one base and time.
- clock_ahead: a report more than `max_lead` s of message time after the latest cycle
  (a clock jumped forward; buffering its reports until the other bases reach their time
  would grow the buffer by one report per scan). Its base is stale at once, until it
  sends a report in reach again, or a late one (its clock is back: the next cycle
  waits for it).
"""

from __future__ import annotations

from common.core.rejection import Rejected
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.report import GlobalTracks


class Arrival:
    """A GlobalFusion behind the arrival rule (module doc); `max_wait` and `max_lead`
    are its FusionParams'."""

    def __init__(self, fusion: GlobalFusion) -> None:
        self.fusion = fusion
        self.heard: dict[str, float] = {}  # wall time of each base's last usable report
        self.ahead: set[str] = set()  # bases whose latest report was clock_ahead

    def stale(self, base: str, t: float, now: float) -> frozenset[str]:
        """The stale bases once the report of `base` (configured) at message time t
        arrived at wall time `now`; raises Rejected if that report is not to be fused."""
        core, p = self.fusion, self.fusion.p
        if core.t_last is not None and t <= core.t_last:  # core.is_late(t)
            self.ahead.discard(base)
            if t >= core.t_last - p.max_wait:
                self.heard[base] = now
            raise Rejected("time_backwards", f"t={t} after the cycle of t={core.t_last}")
        if core.is_duplicate(base, t):
            raise Rejected("duplicate", f"base '{base}' sent t={t} twice")
        for b in core.base_ids:  # a base never heard of is silent since the first report
            self.heard.setdefault(b, now)
        self.heard[base] = now
        if core.t_last is not None and t > core.t_last + p.max_lead:
            self.ahead.add(base)
            raise Rejected("clock_ahead", f"base '{base}' t={t} is more than "
                                          f"max_lead={p.max_lead} s after the cycle of "
                                          f"t={core.t_last}: not fused, base stale")
        self.ahead.discard(base)
        return frozenset(b for b, h in self.heard.items() if now - h > p.max_wait) | self.ahead

    def push(self, base: str, tracks: ElementaryTracks, now: float) -> list[GlobalTracks]:
        """The report of `base` (configured) arrived at wall time `now`: the global tracks
        of the cycles it completed (GlobalFusion.push); raises Rejected as `stale`."""
        return self.fusion.push(base, tracks, self.stale(base, tracks.t, now))
