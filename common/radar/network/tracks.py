"""The global tracks of `NetworkFusion`: CV states [x vx y vy z vz], members (base,
elementary id), exclusive (an elementary track belongs to at most one global track, a
global track holds at most one elementary track per base), and the confirmation and
deletion rules of docs/networks.md.

Members, their misses and the bases of each track's cycle are (N, B) columns, one per
configured base, so that every rule is one numpy operation over the tracks (a report of
one base touches one column), not a loop over them."""

from __future__ import annotations

import numpy as np

from common.core import kalman
from common.core.gating import chi2_gate, quadratic_form
from common.core.motion import cv_F, cv_Q
from common.core.track_table import Status
from common.radar.geometry.bistatic import POS
from common.radar.network.params import NetworkParams

NONE = -1  # `member` of a base the track holds no elementary track of

ROW_COLUMNS = ("id", "status", "x", "P", "t", "t_update", "born", "hits", "cycle_start",
               "member", "misses", "cycle_hit")


class Tracks:
    """Rows in ascending id; columns id, status, x, P, t (state time), t_update, born,
    hits (qualifying cycles), cycle_start, and per row and base (N, B): member (the
    elementary id held, NONE), misses (consecutive misses of that member), cycle_hit
    (updated by that base in the current cycle)."""

    def __init__(self, params: NetworkParams, receiver: np.ndarray) -> None:
        self.p = params
        self.receiver = receiver
        n_b = receiver.size
        self.on_receiver = (receiver[:, None] == np.unique(receiver)[None]).astype(np.int64)
        self.next_id = 1
        self.id_step = 1
        self.id = np.zeros(0, dtype=np.int64)
        self.status = np.zeros(0, dtype=np.int64)
        self.x = np.zeros((0, 6))
        self.P = np.zeros((0, 6, 6))
        self.t = np.zeros(0)
        self.t_update = np.zeros(0)
        self.born = np.zeros(0)
        self.hits = np.zeros(0, dtype=np.int64)
        self.cycle_start = np.zeros(0)
        self.member = np.full((0, n_b), NONE, dtype=np.int64)
        self.misses = np.zeros((0, n_b), dtype=np.int64)
        self.cycle_hit = np.zeros((0, n_b), dtype=bool)

    def __len__(self) -> int:
        return int(self.id.size)

    def _row(self, tid: int) -> int:
        return int(np.searchsorted(self.id, tid))

    @property
    def owner(self) -> dict[tuple[int, int], int]:
        """{(base, elementary id): track number} of every member (partitions)."""
        r, b = np.nonzero(self.member != NONE)
        return {(int(bb), int(self.member[rr, bb])): int(self.id[rr]) for rr, bb in zip(r.tolist(), b.tolist())}

    @property
    def members(self) -> list[dict[int, int]]:
        """Per row {base: elementary id} (common.radar.network.duplicates)."""
        return [{int(b): int(row[b]) for b in np.flatnonzero(row != NONE)} for row in self.member]

    def predicted(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """All tracks predicted to t (001 [51], [25]-[26])."""
        dt = np.maximum(t - self.t, 0.0)
        return kalman.predict(self.x, self.P, cv_F(dt), cv_Q(dt, self.p.q, self.p.q_z))

    def rows_of(self, b: int, eids: np.ndarray) -> np.ndarray:
        """(E,) the row of the track holding (b, eid) for each eid, or -1."""
        eids = np.asarray(eids, dtype=np.int64)
        col = self.member[:, b]
        held = np.flatnonzero(col != NONE)
        if held.size == 0 or eids.size == 0:
            return np.full(eids.size, -1, dtype=np.int64)
        order = held[np.argsort(col[held], kind="stable")]
        j = np.minimum(np.searchsorted(col[order], eids), order.size - 1)
        return np.where(col[order[j]] == eids, order[j], -1)

    def is_member(self, b: int, eids: np.ndarray) -> np.ndarray:
        """(E,) whether (b, eid) is held by a track."""
        return self.rows_of(b, eids) >= 0

    def has_base(self, b: int) -> np.ndarray:
        """(N,) tracks holding a member of base b."""
        return self.member[:, b] != NONE

    def n_bases(self) -> np.ndarray:
        return np.sum(self.member != NONE, axis=1).astype(np.int64)

    def _release(self, rows: np.ndarray, b: int) -> None:
        self.member[rows, b] = NONE
        self.misses[rows, b] = 0

    def release_absent(self, b: int, eids: np.ndarray) -> None:
        """Members of base b whose elementary track is no longer reported."""
        col = self.member[:, b]
        self._release(np.flatnonzero((col != NONE) & ~np.isin(col, eids)), b)

    def count_misses(self, b: int, eids: np.ndarray) -> None:
        """Out-of-gate reports of members; released after member_misses in a row."""
        rows = self.rows_of(b, eids)
        rows = rows[rows >= 0]
        self.misses[rows, b] += 1
        self._release(rows[self.misses[rows, b] >= self.p.member_misses], b)

    def add_members(self, rows: np.ndarray, b: int, eids: np.ndarray) -> None:
        """Rows take the elementary tracks eids of base b (neither held before)."""
        self.member[rows, b] = eids
        self.misses[rows, b] = 0

    def updated(self, rows: np.ndarray, t: float, x: np.ndarray, P: np.ndarray, b: int) -> None:
        """Rows updated at t by base b."""
        self.x[rows], self.P[rows], self.t[rows], self.t_update[rows] = x, P, t, t
        self.cycle_hit[rows, b] = True
        self.misses[rows, b] = 0

    def open(self, t: float, x: np.ndarray, P: np.ndarray, members: list[tuple[int, int]]) -> None:
        """A tentative track at t with its members."""
        self.insert(self.next_id, Status.TENTATIVE, t, x, P, t, t, 0, members)
        self.next_id += self.id_step

    def striped(self, first: int, step: int) -> None:
        """Number new tracks first, first + step, ... (partitions: unique across them)."""
        self.next_id, self.id_step = first, step

    def row_of(self, tid: int) -> int:
        """Row of track number tid, or -1."""
        r = self._row(tid)
        return r if r < len(self) and self.id[r] == tid else -1

    def insert(self, tid: int, status: int, t: float, x: np.ndarray, P: np.ndarray,
               t_update: float, born: float, hits: int, members: list[tuple[int, int]]) -> None:
        """Track number tid with its state (a handed-over track), in id order; members
        already held by another track are left out (and a second one of a base)."""
        r = self._row(tid)
        n_b = self.receiver.size
        member = np.full(n_b, NONE, dtype=np.int64)
        for b, e in members:
            if member[b] == NONE and self.rows_of(b, np.array([e]))[0] < 0:
                member[b] = e
        new = {"id": tid, "status": status, "x": x, "P": P, "t": t, "t_update": t_update,
               "born": born, "hits": hits, "cycle_start": t, "member": member,
               "misses": np.zeros(n_b, dtype=np.int64), "cycle_hit": np.zeros(n_b, dtype=bool)}
        for name in ROW_COLUMNS:
            col = getattr(self, name)
            setattr(self, name, np.insert(col, r, np.asarray(new[name], dtype=col.dtype), axis=0))

    def near(self, t: float, x: np.ndarray, P: np.ndarray) -> bool:
        """A track whose predicted position is within the chi-square(3) gate of x."""
        if not len(self):
            return False
        xp, Pp = self.predicted(t)
        y = xp[:, POS] - x[POS]
        S = Pp[:, POS][:, :, POS] + P[POS][:, POS]
        d2 = quadratic_form(y, S)
        return bool((d2 <= chi2_gate(self.p.gate_prob, 3)).any())

    def bookkeep(self, t: float) -> None:
        """Cycles, confirmation, coasting and deletion at t (also of a track whose
        altitude is below z_min by more than the gate: out of the volume)."""
        p = self.p
        due = np.flatnonzero(t - self.cycle_start >= p.cycle)
        hit = self.cycle_hit[due]
        receivers = np.sum((hit.astype(np.int64) @ self.on_receiver) > 0, axis=1)
        self.hits[due] += (hit.sum(axis=1) >= 3) & (receivers >= 2)
        self.cycle_hit[due] = False
        self.cycle_start[due] = t
        tent = self.status == Status.TENTATIVE
        self.status[tent & (self.hits >= p.confirm_cycles)] = Status.CONFIRMED
        tent = self.status == Status.TENTATIVE
        idle = t - self.t_update
        live = ~tent
        self.status[live & (idle > 2 * p.cycle)] = Status.COASTING
        self.status[live & (idle <= 2 * p.cycle)] = Status.CONFIRMED
        too_old = tent & (t - self.born > (p.confirm_cycles + 2) * p.cycle)
        k = np.sqrt(chi2_gate(p.gate_prob, 1))
        below = self.x[:, 4] + k * np.sqrt(self.P[:, 4, 4]) < p.z_min
        self.remove((live & (idle > p.coast)) | (tent & (idle > p.coast_tentative)) | too_old
                    | below)

    def remove(self, dead: np.ndarray) -> None:
        """Delete the rows of mask `dead` (N,), releasing their members."""
        if not dead.any():
            return
        keep = ~dead
        for name in ROW_COLUMNS:
            setattr(self, name, getattr(self, name)[keep])

    def absorb(self, keep: int, gone: int, t: float, x: np.ndarray, P: np.ndarray) -> None:
        """Row `keep` takes state (x, P) at t and the members of row `gone` on the bases
        it does not hold; `gone` is left for `remove`."""
        move = np.flatnonzero((self.member[gone] != NONE) & (self.member[keep] == NONE))
        self.member[keep, move] = self.member[gone, move]
        self.misses[keep, move] = 0
        self.member[gone, move] = NONE
        self.misses[gone, move] = 0
        self.x[keep], self.P[keep], self.t[keep] = x, P, t
