"""Bearing register of seed 000 (register 13): the detections associated with every track
of one array (bearing, its sigma), with the own-ship position, from the track's first
detection, for TMA (common.sonar.tma.manager). Filled by common.sonar.bearing.tracker once
per cycle; served on sonar/history/<array>/<id> (docs/protocol.md).

Deviation (issue 13): 000 registers the estimated bearings. Those are correlated from
cycle to cycle, so a TMA that treats them as independent publishes an optimistic
covariance. The detections are independent with a known sigma (figures:
docs/decisions/008-tma-on-detections.md). A cycle without a detection for the track adds no row; the detections of a
track flagged by 004 crossing management are left out (they may be the other target's).
"""

from __future__ import annotations

import numpy as np

HISTORY_COLUMNS = ("t", "brg", "sbrg", "own_x", "own_y")


class BearingHistory:
    """Bearing register (000 register 13): rows (t, brg, sbrg, own_x, own_y) appended
    once per cycle for all live tracks in one block, keyed by a never-recycled serial
    number (uid). A deleted confirmed track stays queryable under its number until the
    number is reused or `keep_deleted` later confirmed tracks were deleted; rows nobody
    can query any more are dropped by an amortised compaction."""

    def __init__(self, keep_deleted: int = 64, min_compact_rows: int = 100_000) -> None:
        self.keep_deleted = keep_deleted
        self.min_compact_rows = min_compact_rows
        self._uid: list[np.ndarray] = []
        self._rows: list[np.ndarray] = []
        self._n = 0
        self._compact_at = min_compact_rows
        self.retired_ids = np.zeros(0, dtype=np.int64)
        self.retired_uids = np.zeros(0, dtype=np.int64)

    def __len__(self) -> int:
        return self._n

    def append(self, t: float, uid: np.ndarray, brg: np.ndarray, sbrg: np.ndarray,
               own_x: float, own_y: float) -> None:
        """Log one cycle: one row per live track."""
        k = uid.size
        block = np.column_stack([np.full(k, t), brg, sbrg, np.full(k, own_x), np.full(k, own_y)])
        self._uid.append(np.asarray(uid, dtype=np.int64))
        self._rows.append(block)
        self._n += k

    def retire(self, ids: np.ndarray, uids: np.ndarray) -> None:
        """Keep the history of deleted confirmed tracks queryable under their numbers."""
        self.release(ids)
        self.retired_ids = np.concatenate([self.retired_ids, ids])[-self.keep_deleted:]
        self.retired_uids = np.concatenate([self.retired_uids, uids])[-self.keep_deleted:]

    def release(self, ids: np.ndarray) -> None:
        """Track numbers reused by new tracks: their retired history is no longer served."""
        keep = ~np.isin(self.retired_ids, ids)
        self.retired_ids, self.retired_uids = self.retired_ids[keep], self.retired_uids[keep]

    def retired_uid(self, track_id: int) -> int | None:
        """uid of the deleted confirmed track that had this number, if still kept."""
        hit = np.flatnonzero(self.retired_ids == track_id)
        return int(self.retired_uids[hit[-1]]) if hit.size else None

    def _consolidate(self) -> tuple[np.ndarray, np.ndarray]:
        if len(self._rows) > 1:
            self._uid = [np.concatenate(self._uid)]
            self._rows = [np.concatenate(self._rows)]
        if not self._rows:
            return np.zeros(0, dtype=np.int64), np.zeros((0, len(HISTORY_COLUMNS)))
        return self._uid[0], self._rows[0]

    def rows(self, uid: int) -> dict[str, np.ndarray]:
        """The logged columns of one track, in time order."""
        uids, rows = self._consolidate()
        sel = rows[uids == uid]
        return {c: sel[:, i] for i, c in enumerate(HISTORY_COLUMNS)}

    def maybe_compact(self, live_uids: np.ndarray) -> None:
        """Drop rows of tracks that are neither live nor retired, once the log has
        doubled since the last compaction (amortised O(1) per row)."""
        if self._n < self._compact_at:
            return
        uids, rows = self._consolidate()
        keep = np.isin(uids, np.concatenate([live_uids, self.retired_uids]))
        self._uid, self._rows = [uids[keep]], [rows[keep]]
        self._n = int(keep.sum())
        self._compact_at = max(2 * self._n, self.min_compact_rows)
