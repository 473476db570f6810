"""The one interface of seed 000's bearing tracker in its two association modes, and the
one factory that picks the mode: ``mode_association`` "gnn" the single-hypothesis mode
(common.sonar.bearing.tracker.BearingTracker), "mht" the multiple-hypothesis mode
(common.sonar.mht.tracker.MhtTracker). Callers build either through the factory alone."""

from __future__ import annotations

from dataclasses import replace
from typing import Protocol

import numpy as np

from common.core.crossing import CrossingParams
from common.sonar.bearing.range_noise import TmaHint
from common.sonar.bearing.tracker import BearingTracker, Cycle
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.mht.tracker import MhtTracker

__all__ = ["BearingTrackerCore", "Cycle", "TmaHint", "bearing_tracker"]


class BearingTrackerCore(Protocol):
    """Seed 000 bearing tracker of one array: one `step` per detection list (time order),
    the bearing register (000 register 13) of a confirmed track by `history_of`."""

    narrowband: bool
    t: float | None

    def step(self, t: float, brg: np.ndarray, amp: np.ndarray, heading: float,
             own_x: float = 0.0, own_y: float = 0.0, freq: np.ndarray | None = None,
             sbrg: np.ndarray | None = None) -> Cycle:
        """Process the detection list of time t and return the tracks."""
        ...

    def tma_hint(self, track_id: int, hint: TmaHint) -> None:
        """Give a track its contact's latest TMA solution (common.sonar.bearing.range_noise)."""
        ...

    def history_of(self, track_id: int, as_of: float | None = None
                   ) -> tuple[str, dict[str, np.ndarray]] | None:
        """("confirmed" | "deleted", register columns) of a confirmed track, else None;
        with ``as_of``, as of that cycle time (common.sonar.history_as_of)."""
        ...


def bearing_tracker(params: SonarTrackerParams, mht: MhtParams, array_kind: str, sigma0: float,
                    crossing: CrossingParams | None = None, has_freq: bool = False) -> BearingTrackerCore:
    """The seed 000 tracker of ``params.mode_association`` for one array; mode "auto" is
    resolved by the first detection list (``has_freq``: it carries frequencies, so
    narrowband). ``crossing`` (seed 004) is the single-hypothesis mode's only."""
    mode = params.mode if params.mode != "auto" else ("narrowband" if has_freq else "broadband")
    p = replace(params, mode=mode)
    if params.mode_association == "mht":
        return MhtTracker(p, mht, array_kind, sigma0)
    return BearingTracker(p, array_kind, sigma0, crossing)
