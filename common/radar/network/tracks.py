"""The global tracks of `NetworkFusion`: CV states [x vx y vy z vz], members (base,
elementary id), exclusive (an elementary track belongs to at most one global track, a
global track holds at most one elementary track per base), and the confirmation and
deletion rules of docs/networks.md."""

from __future__ import annotations

import numpy as np

from common.core import kalman
from common.core.gating import chi2_gate, quadratic_form
from common.core.motion import cv_F, cv_Q
from common.core.track_table import Status
from common.radar.geometry.bistatic import POS
from common.radar.network.params import NetworkParams


class Tracks:
    """Rows in ascending id; columns id, status, x, P, t (state time), t_update, born,
    hits (qualifying cycles), cycle_start, and per row its cycle's bases and members."""

    def __init__(self, params: NetworkParams, receiver: np.ndarray) -> None:
        self.p = params
        self.receiver = receiver
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
        self.cycle_bases: list[set[int]] = []
        self.members: list[dict[int, int]] = []
        self.owner: dict[tuple[int, int], int] = {}  # (base, eid) -> track id
        self.misses: dict[tuple[int, int], int] = {}

    def __len__(self) -> int:
        return int(self.id.size)

    def predicted(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """All tracks predicted to t (001 [51], [25]-[26])."""
        dt = np.maximum(t - self.t, 0.0)
        return kalman.predict(self.x, self.P, cv_F(dt), cv_Q(dt, self.p.q, self.p.q_z))

    def _row(self, tid: int) -> int:
        return int(np.searchsorted(self.id, tid))

    def member_of(self, b: int, eid: int) -> int:
        """Row of the track holding (b, eid), or -1."""
        tid = self.owner.get((b, eid))
        return -1 if tid is None else self._row(tid)

    def is_member(self, b: int, eids: np.ndarray) -> np.ndarray:
        return np.array([(b, int(e)) in self.owner for e in eids], dtype=bool)

    def has_base(self, b: int) -> np.ndarray:
        """(N,) tracks holding a member of base b."""
        return np.array([b in m for m in self.members], dtype=bool)

    def n_bases(self) -> np.ndarray:
        return np.array([len(m) for m in self.members], dtype=np.int64)

    def _release(self, b: int, eid: int) -> None:
        tid = self.owner.pop((b, eid), None)
        self.misses.pop((b, eid), None)
        if tid is not None:
            self.members[self._row(tid)].pop(b, None)

    def release_absent(self, b: int, eids: np.ndarray) -> None:
        """Members of base b whose elementary track is no longer reported."""
        now = set(eids.tolist())
        for key in [k for k in self.owner if k[0] == b and k[1] not in now]:
            self._release(*key)

    def count_misses(self, b: int, eids: np.ndarray) -> None:
        """Out-of-gate reports of members; released after member_misses in a row."""
        for e in eids.tolist():
            n = self.misses.get((b, e), 0) + 1
            self.misses[(b, e)] = n
            if n >= self.p.member_misses:
                self._release(b, e)

    def add_member(self, row: int, b: int, eid: int) -> None:
        self.members[row][b] = eid
        self.owner[(b, eid)] = int(self.id[row])

    def updated(self, rows: np.ndarray, t: float, x: np.ndarray, P: np.ndarray, b: int) -> None:
        """Rows updated at t by base b."""
        self.x[rows], self.P[rows], self.t[rows], self.t_update[rows] = x, P, t, t
        for r in rows.tolist():
            self.cycle_bases[r].add(b)
            self.misses.pop((b, self.members[r][b]), None)

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
        already held by another track are left out."""
        r = self._row(tid)
        for name, v in (("id", tid), ("status", status), ("t", t), ("t_update", t_update),
                        ("born", born), ("hits", hits), ("cycle_start", t)):
            setattr(self, name, np.insert(getattr(self, name), r, v))
        self.x = np.insert(self.x, r, x, axis=0)
        self.P = np.insert(self.P, r, P, axis=0)
        self.cycle_bases.insert(r, set())
        self.members.insert(r, {})
        for b, e in members:
            if (b, e) not in self.owner and b not in self.members[r]:
                self.add_member(r, b, e)

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
        for r in np.flatnonzero(t - self.cycle_start >= p.cycle).tolist():
            bs = list(self.cycle_bases[r])
            if len(bs) >= 3 and np.unique(self.receiver[bs]).size >= 2:
                self.hits[r] += 1
            self.cycle_bases[r] = set()
            self.cycle_start[r] = t
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
        for r in np.flatnonzero(dead)[::-1].tolist():
            for b, e in list(self.members[r].items()):
                self._release(b, e)
            del self.cycle_bases[r], self.members[r]
        keep = ~dead
        for name in ("id", "status", "x", "P", "t", "t_update", "born", "hits", "cycle_start"):
            setattr(self, name, getattr(self, name)[keep])

    def absorb(self, keep: int, gone: int, t: float, x: np.ndarray, P: np.ndarray) -> None:
        """Row `keep` takes state (x, P) at t and the members of row `gone` on the bases
        it does not hold; `gone` is left for `remove`."""
        for b, e in list(self.members[gone].items()):
            if b not in self.members[keep]:
                self.owner.pop((b, e), None)
                self.misses.pop((b, e), None)
                self.members[gone].pop(b)
                self.add_member(keep, b, e)
        self.x[keep], self.P[keep], self.t[keep] = x, P, t
