"""The typed input and output of global fusion (001 step 24): the elementary tracks of
the bases stacked for one cycle (`etrack_set`, with their equivalent measurements) and
the global tracks of a cycle (`GlobalTracks`). The wire messages are built and parsed
in common.wire.radar_messages, once, at the service boundary.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.track_table import Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.assoc import YR, ETrackSet
from common.radar.fusion.decorrelation import Decorrelator


@dataclass(frozen=True)
class GlobalTracks:
    """Live global tracks after a cycle at t (one row per track, ascending slot order).

    bases: the configured base ids (columns of member / has); id (N,), status (N,)
    (common.core.track_table.Status), x (N, 6), P (N, 6, 6), score (N,); member (N, B)
    the number of the elementary track of each base, has (N, B) whether the base
    contributes; ambiguous (N,) (004).
    """

    t: float
    bases: tuple[str, ...]
    id: np.ndarray
    status: np.ndarray
    x: np.ndarray
    P: np.ndarray
    score: np.ndarray
    member: np.ndarray
    has: np.ndarray
    ambiguous: np.ndarray

    def __len__(self) -> int:
        return int(self.id.shape[0])


def etrack_set(reports: dict[int, ElementaryTracks], decorrelator: Decorrelator, t: float
               ) -> ETrackSet:
    """Stack the elementary tracks of one cycle (keyed by base index, in that order) and
    their equivalent measurements at t."""
    rs = list(reports.values())
    n = sum(len(r) for r in rs)
    x = np.concatenate([r.x for r in rs]).reshape(n, 5) if rs else np.zeros((0, 5))
    P = np.concatenate([r.P for r in rs]).reshape(n, 5, 5) if rs else np.zeros((0, 5, 5))

    def col(name: str, dtype: type) -> np.ndarray:
        return (np.concatenate([np.asarray(getattr(r, name), dtype=dtype) for r in rs])
                if rs else np.zeros(0, dtype=dtype))

    base = np.repeat(np.array(list(reports), dtype=np.intp), [len(r) for r in rs])
    ids, updated, ambiguous = col("id", np.int64), col("updated", bool), col("ambiguous", bool)
    eq = decorrelator.step_bases(t, list(reports), base, ids, x, P, updated, ambiguous)
    z, Rz, meas = eq.z, eq.R, eq.ok
    y, R = x[:, YR], P[:, YR][:, :, YR]
    z[~meas], Rz[~meas] = y[~meas], R[~meas]  # finite placeholders, masked by meas
    return ETrackSet(
        base=base, id=ids, y=y, R=R, score=col("score", float),
        confirmed=col("status", np.int64) == Status.CONFIRMED,
        updated=updated, ambiguous=ambiguous, z=z, Rz=Rz, meas=meas,
    )
