"""Fixed-capacity, growable table of tracks as numpy columns (one row = one slot).

Shared by the radar (001 elementary and global tracks) and sonar (000) trackers. Track
numbers are stable for the life of a track and recycled after deletion, smallest free
number first (001: "se libera su número de identificación de manera que pueda ser
reatribuido"). The table also holds the filter state x (cap, n) and P (cap, n, n) so
that a tracker can run the batched kalman functions on `x[idx]`, `P[idx]` directly.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike, DTypeLike


class Status(IntEnum):
    """Track life-cycle status codes (000: tentative/confirmed/deleted; 001: coasting =
    maintained in pure prediction mode)."""

    TENTATIVE = 0
    CONFIRMED = 1
    COASTING = 2
    DELETED = 3


STATUS_NAME = {Status.TENTATIVE: "tentative", Status.CONFIRMED: "confirmed",
               Status.COASTING: "coasting"}  # the wire's names of the live statuses


class TrackTable:
    """Columns: id, status, score, n_updates, n_coast (consecutive misses), t_last, x, P,
    plus optional tracker-specific `extra` columns {name: (shape per track, dtype)}.

    Track numbers equal slot + first_id: slots are allocated lowest-free-first, which is
    exactly "smallest free number reused first", so the number of a track never changes
    and a slot's id column is -1 while the slot is free. Capacity doubles when full.
    """

    id: np.ndarray
    status: np.ndarray
    score: np.ndarray
    n_updates: np.ndarray
    n_coast: np.ndarray
    t_last: np.ndarray
    x: np.ndarray
    P: np.ndarray

    def __init__(
        self,
        state_dim: int,
        capacity: int = 64,
        first_id: int = 1,
        extra: Mapping[str, tuple[tuple[int, ...], DTypeLike]] | None = None,
    ) -> None:
        self.state_dim = state_dim
        self.first_id = first_id
        self._extra = dict(extra or {})
        n = state_dim
        self._specs: dict[str, tuple[tuple[int, ...], DTypeLike, object]] = {
            "id": ((), np.int64, -1),
            "status": ((), np.int8, int(Status.DELETED)),
            "score": ((), np.float64, 0.0),
            "n_updates": ((), np.int64, 0),
            "n_coast": ((), np.int64, 0),
            "t_last": ((), np.float64, np.nan),
            "x": ((n,), np.float64, 0.0),
            "P": ((n, n), np.float64, 0.0),
        }
        for name, (shape, dtype) in self._extra.items():
            self._specs[name] = (tuple(shape), dtype, 0)
        for name, (shape, dtype, fill) in self._specs.items():
            setattr(self, name, np.full((capacity,) + shape, fill, dtype=dtype))

    @property
    def capacity(self) -> int:
        """Number of slots currently allocated."""
        return self.id.shape[0]

    @property
    def alive(self) -> np.ndarray:
        """(capacity,) mask of slots holding a track (status != DELETED)."""
        return self.status != Status.DELETED

    def active_indices(self) -> np.ndarray:
        """Slot indices of live tracks, ascending."""
        return np.flatnonzero(self.alive)

    @property
    def ids(self) -> np.ndarray:
        """Track numbers of live tracks, in active_indices() order."""
        return self.id[self.alive]

    def __len__(self) -> int:
        return int(np.count_nonzero(self.alive))

    def _grow(self, needed: int) -> None:
        new_cap = max(needed, 2 * self.capacity, 1)
        for name, (shape, dtype, fill) in self._specs.items():
            old = getattr(self, name)
            col = np.full((new_cap,) + shape, fill, dtype=dtype)
            col[: old.shape[0]] = old
            setattr(self, name, col)

    def add(self, k: int, avoid: ArrayLike = ()) -> np.ndarray:
        """Open k tracks in the lowest free slots (smallest free numbers) but the slots
        in `avoid` (numbers held by the caller), reset to TENTATIVE with zero
        score/counters, t_last = nan, x = 0, P = 0 (caller fills). Returns their slot
        indices (ascending)."""
        held = np.asarray(avoid, dtype=np.intp)
        free = np.setdiff1d(np.flatnonzero(~self.alive), held)
        if free.size < k:
            self._grow(self.capacity + k - free.size)
            free = np.setdiff1d(np.flatnonzero(~self.alive), held)
        idx = free[:k]
        for name, (_, _, fill) in self._specs.items():
            getattr(self, name)[idx] = fill
        self.id[idx] = idx + self.first_id
        self.status[idx] = Status.TENTATIVE
        return idx

    def copy_rows(self, src: ArrayLike, dst: ArrayLike, skip: tuple[str, ...] = ("id",)) -> None:
        """Copy every column of slots src into slots dst, but the columns named in skip."""
        for name in self._specs:
            if name not in skip:
                col = getattr(self, name)
                col[dst] = col[src]

    def remove(self, indices: ArrayLike) -> None:
        """Delete the tracks in these slots and release their numbers."""
        idx = np.asarray(indices, dtype=np.intp)
        self.status[idx] = Status.DELETED
        self.id[idx] = -1

    def index_of(self, track_ids: ArrayLike) -> np.ndarray:
        """Slot indices of live tracks with these numbers (KeyError if one is not live)."""
        idx = np.asarray(track_ids, dtype=np.intp) - self.first_id
        ok = (idx >= 0) & (idx < self.capacity)
        if not np.all(ok) or not np.all(self.alive[idx]):
            raise KeyError(f"not live track numbers in {track_ids!r}")
        return idx
