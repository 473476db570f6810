"""Per-publisher sequence numbers of received samples: the check that makes a lost
sample visible (a counter and a log line) instead of silent.

Every pipeline publisher stamps its samples with (source, n), n = 0, 1, 2, ... per key
(``common.bus.transport.Publisher``); a receiver feeds each stamp to :class:`SequenceCheck`.
A restarted publisher is a new source, so its n = 0 is not a gap.
"""

from __future__ import annotations

MAX_JUMP = 10_000  # a larger gap between two stamps of one source is no loss but a bad stamp


class StampJump(ValueError):
    """A stamp more than ``max_jump`` past its source's highest: not counted as missed
    samples and not recorded (a forged or corrupted stamp must not hide later losses)."""


class SequenceCheck:
    """Highest sequence number seen per (key, source)."""

    def __init__(self, max_jump: int = MAX_JUMP) -> None:
        self.max_jump = max_jump
        self._last: dict[tuple[str, str], int] = {}

    def observe(self, key: str, source: str, n: int) -> int:
        """Record stamp ``n`` of ``source`` on ``key``; returns the number of samples
        missed between the highest stamp seen so far and this one (0 for a repeated or
        older stamp). The first stamp of a source counts nothing: what it sent before
        we subscribed was not ours to get. Raises StampJump for a gap over max_jump."""
        last = self._last.get((key, source))
        if last is not None and n - last - 1 > self.max_jump:
            raise StampJump(f"stamp {n} of {source} on {key}: {n - last - 1} past {last}, "
                            f"more than {self.max_jump}")
        self._last[(key, source)] = n if last is None else max(last, n)
        return 0 if last is None or n <= last else n - last - 1
