"""The one input-rejection error of the project.

A core (or a decoder) that cannot use an input raises ``Rejected(reason, detail)``; the
service shell (common.bus.service) catches it alone, adds one to ``rejected[reason]``,
logs ``detail`` and goes on with the next sample. Nothing else is lost.
"""

from __future__ import annotations


class Rejected(ValueError):
    """Input that cannot be used: ``reason`` names the counter (e.g. ``time_backwards``,
    ``decode:tracks[3].P``), ``detail`` says what was wrong, for the log."""

    def __init__(self, reason: str, detail: str, message: str | None = None) -> None:
        super().__init__(message if message is not None else f"{reason}: {detail}")
        self.reason = reason
        self.detail = detail
