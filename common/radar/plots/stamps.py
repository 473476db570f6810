"""The time rules of a plot stream, shared by the channel plotter and the ingest of
external nodes (`max_ahead` of [radar.plotter]).

A stamp past its reference (the latest tested time of the base) by more than max_ahead
is rejected (`ahead`), unless a majority of the base's streams (two stamps of a
one-stream base) were rejected within max_ahead of it: the base's clock jumped, and the
jump is taken.
"""

from __future__ import annotations

from common.core.rejection import Rejected


def ahead_rule(ahead: dict[str, float], stream: str, t: float, ref: float | None, lim: float,
               n: int) -> None:
    """Raise Rejected `ahead` when t > ref + lim and fewer than a majority of the n
    streams agree on the jump; `ahead` holds each stream's last time rejected (cleared
    once a jump is taken)."""
    if ref is None or t <= ref + lim:
        return
    agree = [c for c, a in ahead.items() if abs(a - t) <= lim and (c != stream or n == 1)]
    ahead[stream] = t
    if not agree or len(agree) + 1 <= n / 2:
        raise Rejected("ahead", f"{stream}: t={t} more than {lim} s ahead of t={ref}")
    ahead.clear()


class StampCheck:
    """The time rules of one stream of stamps: strictly increasing (a repeated stamp is
    `duplicate`, an earlier one `time_backwards`) and the `max_ahead` rule against the
    previous accepted stamp, or against `now` (wall time, passed in) before the first."""

    def __init__(self, stream: str, max_ahead: float) -> None:
        self.stream, self.max_ahead = stream, max_ahead
        self.last: float | None = None
        self._ahead: dict[str, float] = {}

    def accept(self, t: float, now: float | None = None) -> None:
        """Take stamp t or raise Rejected (`duplicate`, `time_backwards`, `ahead`)."""
        if self.last is not None and t == self.last:
            raise Rejected("duplicate", f"{self.stream}: t={t} already taken")
        if self.last is not None and t < self.last:
            raise Rejected("time_backwards", f"{self.stream}: t={t} before t={self.last}")
        ahead_rule(self._ahead, self.stream, t, self.last if self.last is not None else now,
                   self.max_ahead, 1)
        self.last = t
