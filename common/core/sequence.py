"""Per-publisher sequence numbers of received samples: the check that makes a lost
sample visible (a counter and a log line) instead of silent.

Every pipeline publisher stamps its samples with (source, n), n = 0, 1, 2, ... per key
(``common.bus.transport.Publisher``); a receiver feeds each stamp to :class:`SequenceCheck`.
A restarted publisher is a new source, so its n = 0 is not a gap.
"""

from __future__ import annotations


class SequenceCheck:
    """Highest sequence number seen per (key, source)."""

    def __init__(self) -> None:
        self._last: dict[tuple[str, str], int] = {}

    def observe(self, key: str, source: str, n: int) -> int:
        """Record stamp ``n`` of ``source`` on ``key``; returns the number of samples
        missed between the highest stamp seen so far and this one (0 for a repeated or
        older stamp). The first stamp of a source counts nothing: what it sent before
        we subscribed was not ours to get."""
        last = self._last.get((key, source))
        self._last[(key, source)] = n if last is None else max(last, n)
        return 0 if last is None or n <= last else n - last - 1
