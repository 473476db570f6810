"""Truth and tracks of one message time, paired for scoring (`pfusion evaluate`).

Truth and global tracks arrive on separate keys, each stamped with the simulator's
scan time. A step is scored once both of its time have arrived, and steps are scored in
increasing time (the metrics accumulate per step): a pair whose time is not after the
last scored one is not scored but rejected (``Rejected("out_of_order")``, which the
service counts), never dropped silently."""

from __future__ import annotations

from typing import Generic, TypeVar

from common.core.rejection import Rejected

T = TypeVar("T")
U = TypeVar("U")


class StepPairing(Generic[T, U]):
    """Pairs (t, truth) and (t, tracks) reports by their time t."""

    def __init__(self) -> None:
        self._truth: dict[float, T] = {}
        self._tracks: dict[float, U] = {}
        self.last: float | None = None

    def truth(self, t: float, value: T) -> tuple[float, T, U] | None:
        """Keep the truth of time t; the step to score when its tracks are already here."""
        self._truth[t] = value
        return self._pair(t)

    def tracks(self, t: float, value: U) -> tuple[float, T, U] | None:
        """Keep the tracks of time t; the step to score when its truth is already here."""
        self._tracks[t] = value
        return self._pair(t)

    def _pair(self, t: float) -> tuple[float, T, U] | None:
        if t not in self._truth or t not in self._tracks:
            return None
        truth, tracks = self._truth.pop(t), self._tracks.pop(t)
        if self.last is not None and t <= self.last:
            raise Rejected("out_of_order", f"step t={t} not after the last scored t={self.last}")
        self.last = t
        return t, truth, tracks
