"""`NetworkFusion`: global tracks of a multistatic network from unsynchronised base
reports (docs/networks.md).

push(base, t, ElementaryTracks) buffers a report; reports leave the reordering window
(`window` s behind the newest stamp) in time order and each runs one step at its own
time t (no common scan time):
  1. equivalent measurements of the report (common.radar.fusion.decorrelation, 3-state
     [r_b, v_b] or 5-state [r_b, v_b, theta] tracks), shifted by the base's clock
     offset estimate (common.radar.network.clocks [C3]);
  2. every global track predicted to t (CV, 001 [51]: cv_F, cv_Q);
  3. a member's measurement is gated (chi-square, S = H P~ H' + R, H the rows of 001
     [47]'s Jacobian) on its own track; outside the gate it counts a miss (released
     after member_misses); the range innovations of the members of confirmed tracks
     in the gate update the base's clock offset ([C1]-[C2]); a member whose equivalent
     measurement failed its test (its elementary track changed aircraft) counts a miss
     too; an unassigned confirmed elementary track is gated on every track without a
     member of this base and assigned by global nearest neighbour (`candidate_costs`:
     only the pairs whose range innovation alone passes the gate are tested);
  4. one batched EKF update (001 [55]-[62], common.core.kalman) of the tracks hit;
  5. bookkeeping: a cycle with updates from >= 3 bases over >= 2 receivers counts one
     hit, confirm_cycles hits confirm; deletion after coast (coast_tentative) s;
  6. every init_period s, two confirmed tracks of one aircraft merged
     (common.radar.network.duplicates), then initiation (common.radar.network.initiation)
     on the leftovers of all bases predicted to t; a candidate inside the gate of an
     existing track is not opened;
  7. every report_period s, a `NetworkReport` of all live tracks predicted to t.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from common.core import kalman
from common.core.assignment import gnn
from common.core.gating import chi2_gate, pair_distances, window_pairs
from common.core.motion import bistatic_F, bistatic_Q
from common.core.rejection import Rejected
from common.core.track_table import Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.decorrelation import Decorrelator
from common.radar.geometry.bistatic import BaseGeometry, project, project_jacobian
from common.radar.network.clocks import Clocks
from common.radar.network.duplicates import candidate_pairs, merged
from common.radar.network.initiation import Leftovers, Sites, initiate
from common.radar.network.params import NetworkParams
from common.radar.network.tracks import Tracks

RANGE_SLACK = 1.0 + 1e-6  # widens the range window past the rounding of d2 (step 3)


@dataclass(frozen=True)
class NetworkReport:
    """Live global tracks at t: id, status (Status codes), x (N, 6), P (N, 6, 6),
    n_bases (N,) members; member (N, B) the elementary track number of each configured
    base, has (N, B) whether that base has a member."""

    t: float
    id: np.ndarray
    status: np.ndarray
    x: np.ndarray
    P: np.ndarray
    n_bases: np.ndarray
    member: np.ndarray
    has: np.ndarray


def candidate_costs(h: np.ndarray, A: np.ndarray, z: np.ndarray, R: np.ndarray, cand: np.ndarray,
                    free: np.ndarray, ang: list[int], gam: float) -> np.ndarray:
    """(C, F) d2 of tracks `cand` (predicted h, H P H' A) and measurements `free` (z, R)
    inside the gate `gam`, inf outside (step 3). Only the pairs whose range innovation
    alone passes are tested: y' S^-1 y >= y_r^2 / S_rr for S > 0, a window on r_b
    (common.core.gating.window_pairs) that drops no pair the gate keeps."""
    half = np.sqrt(RANGE_SLACK * gam * (A[cand, 0, 0] + R[free, 0, 0].max()))
    i, j = window_pairs(h[cand, 0] - half, h[cand, 0] + half, z[free, 0])
    _, _, d2 = pair_distances(h, A, z, R, cand[i], free[j], ang)
    cost = np.full((cand.size, free.size), np.inf)
    inside = d2 <= gam
    cost[i[inside], j[inside]] = d2[inside]
    return cost


class NetworkFusion:
    """The fusion centre (module doc); `rejected` counts refused reports by reason,
    `waiting` the seed cells deferred by max_cells, `merged` the tracks merged into
    another. Hooks of a partition (common.radar.network.partition): `region(x)` whether
    a fix may open a track here (None: everywhere), `extent` the slab (cell axis, lo, hi)
    its initiation votes over (None: the whole volume), `excluded` the (base, elementary
    id) pairs held by other partitions, left out of initiation."""

    def __init__(self, bases: Sequence[BaseGeometry], params: NetworkParams | None = None,
                 sigma_gamma: float = 5.0, sigma_omega: float = 1e-3) -> None:
        """`sigma_gamma` (m/s^3), `sigma_omega` (rad/s^2): Q [20] of the elementary
        trackers, with which the decorrelation predicts their previous report."""
        self.p = params or NetworkParams()
        self.sigma_gamma = sigma_gamma
        self.ids = [b.id for b in bases]
        rx = np.array([b.rx for b in bases], dtype=float)
        _, rec = np.unique(np.round(rx, 3), axis=0, return_inverse=True)
        self.sites = Sites(np.array([b.tx for b in bases], dtype=float), rx, rec.ravel())
        unknown = sorted(set(self.p.clock_reference) - set(self.ids))
        if unknown:
            raise ValueError(f"clock_reference names unknown bases: {', '.join(unknown)}")
        self.clocks = Clocks(len(bases), self.p.clock_sigma, self.p.clock_drift,
                             np.isin(self.ids, list(self.p.clock_reference)))
        self.dec = Decorrelator(sigma_gamma, sigma_omega, self.p.decor_gate)
        self.tracks = Tracks(self.p, self.sites.receiver)
        self.heap: list[tuple[float, int, int, ElementaryTracks]] = []
        self.serial = 0
        self.newest = -np.inf
        self.done = -np.inf
        self.last: dict[int, ElementaryTracks] = {}
        self.last_init = -np.inf
        self.next_report = -np.inf
        self.rejected: dict[str, int] = {}
        self.waiting = 0
        self.rounds = 0
        self.merged = 0
        self.region: Callable[[np.ndarray], bool] | None = None
        self.extent: tuple[int, float, float] | None = None
        self.excluded: set[tuple[int, int]] = set()

    def _reject(self, reason: str, detail: str) -> Rejected:
        self.rejected[reason] = self.rejected.get(reason, 0) + 1
        return Rejected(reason, detail)

    def push(self, base: str, t: float, tracks: ElementaryTracks) -> list[NetworkReport]:
        """Buffer the report of `base` stamped t; run every report that left the window."""
        if base not in self.ids:
            raise self._reject("unknown_base", base)
        if t <= self.done:
            raise self._reject("too_late", f"{base} at {t:.3f} s, processed up to {self.done:.3f} s")
        if tracks.x.ndim != 2 or tracks.x.shape[1] not in (3, 5):
            raise self._reject("state_size", f"{base}: x of shape {tracks.x.shape}")
        self.serial += 1
        heapq.heappush(self.heap, (t, self.serial, self.ids.index(base), tracks))
        self.newest = max(self.newest, t)
        return self._drain(self.newest - self.p.window)

    def flush(self) -> list[NetworkReport]:
        """Run every buffered report (end of input)."""
        return self._drain(np.inf)

    def _drain(self, until: float) -> list[NetworkReport]:
        out: list[NetworkReport] = []
        while self.heap and self.heap[0][0] <= until:
            t, _, b, tr = heapq.heappop(self.heap)
            self.done = t
            out += self._step(b, t, tr)
        return out

    def _step(self, b: int, t: float, tr: ElementaryTracks) -> list[NetworkReport]:
        """Steps 1-7 of the module doc for one report."""
        eq = self.dec.step(b, t, tr.id, tr.x, tr.P, tr.updated, tr.ambiguous)
        z, R = self.clocks.correct(b, eq.z, eq.R)
        self.last[b] = tr
        T = self.tracks
        T.release_absent(b, tr.id)
        xp, Pp = T.predicted(t)
        m = z.shape[1]
        rows = np.flatnonzero(eq.ok)
        trk = T.rows_of(b, tr.id[rows])
        mem, free = rows[trk >= 0], rows[(trk < 0) & (tr.status[rows] == Status.CONFIRMED)]
        trk = trk[trk >= 0]
        h = project(xp, self.sites.tx[b], self.sites.rx[b])[:, :m] if len(T) else np.zeros((0, m))
        H = project_jacobian(xp, self.sites.tx[b], self.sites.rx[b])[:, :m] if len(T) else \
            np.zeros((0, m, 6))
        A = H @ Pp @ np.swapaxes(H, 1, 2)
        ang = [2] if m == 3 else []
        gam = chi2_gate(self.p.gate_prob, m)
        _, _, d2 = pair_distances(h, A, z, R, trk, mem, ang)
        hit = d2 <= gam
        use = hit & (T.status[trk] == Status.CONFIRMED)
        self.clocks.update(b, t, z[mem[use], 1], z[mem[use], 0] - h[trk[use], 0],
                           A[trk[use], 0, 0] + eq.R[mem[use], 0, 0])
        T.count_misses(b, tr.id[mem[~hit]])
        torn = np.flatnonzero(~eq.ok & tr.updated & ~tr.ambiguous)
        T.count_misses(b, tr.id[torn[T.is_member(b, tr.id[torn])]])
        up_t, up_r = trk[hit], mem[hit]
        cand = np.flatnonzero(~T.has_base(b))
        if free.size and cand.size:
            r_i, c_i = gnn(candidate_costs(h, A, z, R, cand, free, ang, gam))
            T.add_members(cand[r_i], b, tr.id[free[c_i]])
            up_t, up_r = np.concatenate([up_t, cand[r_i]]), np.concatenate([up_r, free[c_i]])
        if up_t.size:
            k, r = up_t.astype(int), up_r.astype(int)
            x, P, _, _ = kalman.ekf_update(xp[k], Pp[k], z[r], h[k], H[k], R[r], ang)
            T.updated(k, t, x, P, b)
        T.bookkeep(t)
        if t - self.last_init >= self.p.init_period:
            self.last_init = t
            self._merge(t)
            self._initiate(t)
        return self._report(t)

    def _leftovers(self, t: float, members: bool = False) -> Leftovers:
        """Confirmed non-member (`members`: member) elementary tracks of fresh reports,
        [r_b, v_b] at t."""
        parts = []
        for b, tr in self.last.items():
            dt = t - tr.t
            keep = (tr.status == Status.CONFIRMED) & (self.tracks.is_member(b, tr.id) == members)
            if self.excluded and not members:
                keep &= ~np.array([(b, int(e)) in self.excluded for e in tr.id], dtype=bool)
            if dt > self.p.stale or not keep.any():
                continue
            F = bistatic_F(dt)[:3, :3]
            x = tr.x[keep][:, :3] @ F.T
            P = F @ tr.P[keep][:, :3, :3] @ F.T + bistatic_Q(dt, self.sigma_gamma, 0.0)[:3, :3]
            zc, R = self.clocks.correct(b, x[:, :2], P[:, :2, :2])
            parts.append((np.full(x.shape[0], b), tr.id[keep], zc, R))
        if not parts:
            return Leftovers(np.zeros(0, int), np.zeros(0, int), np.zeros((0, 2)),
                             np.zeros((0, 2, 2)))
        return Leftovers(*(np.concatenate(c) for c in zip(*parts)))

    def _merge(self, t: float) -> None:
        """Step 6's merge (common.radar.network.duplicates)."""
        T = self.tracks
        if self.p.merge_distance <= 0 or len(T) < 2:
            return
        xp, _ = T.predicted(t)
        pairs = candidate_pairs(xp, T.status, T.members, self.p.merge_distance)
        if pairs.shape[0] == 0:
            return
        fix, ok = merged(pairs, xp, T.members, self._leftovers(t, members=True), self.sites,
                         self.p)
        gone = np.zeros(len(T), dtype=bool)
        used: set[int] = set()
        for k in np.flatnonzero(ok).tolist():
            a, c = pairs[k].tolist()
            if not used & {a, c}:
                used |= {a, c}
                T.absorb(a, c, t, fix.x[k], fix.P[k])
                gone[c] = True
        self.merged += int(gone.sum())
        T.remove(gone)

    def _initiate(self, t: float) -> None:
        """Step 6 (common.radar.network.initiation)."""
        left = self._leftovers(t)
        with_left = np.unique(left.base)
        if with_left.size < 3 or np.unique(self.sites.receiver[with_left]).size < 2:
            return
        required = max(3, min(self.p.init_bases, with_left.size))
        self.rounds += 1
        opened, waiting = initiate(left, self.sites, required, self.p, self.rounds,
                                   self.extent)
        self.waiting += waiting
        for c in range(opened.members.shape[0]):
            x, P = opened.fix.x[c], opened.fix.P[c]
            if self.tracks.near(t, x, P) or (self.region is not None and not self.region(x)):
                continue
            mem = [(int(b), int(left.eid[i])) for b, i in enumerate(opened.members[c]) if i >= 0]
            self.tracks.open(t, x, P, mem)

    def _report(self, t: float) -> list[NetworkReport]:
        """Step 7."""
        if t < self.next_report:
            return []
        self.next_report = max(self.next_report + self.p.report_period, t) \
            if np.isfinite(self.next_report) else t + self.p.report_period
        T = self.tracks
        x, P = T.predicted(t)
        member = T.member.copy()
        return [NetworkReport(t, T.id.copy(), T.status.copy(), x, P, T.n_bases(), member,
                              member >= 0)]

