"""Module 61 of 001 (management) and the cycle of step 24, "fusion posterior".

`GlobalFusion.push(base, tracks, stale)` takes the elementary tracks of one base and scan
(typed arrays: common.radar.elementary.tracker.ElementaryTracks) and returns the global tracks of
the cycles it completed (common.radar.fusion.report.GlobalTracks); the wire messages are
parsed and built once, at the service (common.wire.radar_messages). A cycle at time t runs
when every base that is not `stale` has reported t or a later time; stale bases (the
judgement of common.radar.fusion.arrival, given wall time: this core has no clock) are
treated as not reporting in that cycle (their memberships are kept, without
measurement). Within a cycle the bases are processed in configured order, so the output
depends neither on the arrival order of one cycle's messages nor on how the bases'
streams interleave, as long as no base is declared stale.

Deviation (stated): 001's rule "every base reported t, or any base reported a later
time" assumes bases in lock step with real time; faster than real time (replay) the
per-base processes drift apart by tens of scans
(docs/decisions/010-global-fusion-wall-time.md): a message-time rule ran cycles
without a merely slow base and depended on process timing.

Cycle at t (001 figure 7):
  predict every component of every global track to t ([55]-[56], IMM mixing);
  module 63: confirm or dissociate the memberships ([48] <= gamma_max in one live
    component of the track's mixture: a stated deviation), then add
    free elementary tracks of non-contributing bases, including to tracks in pure
    prediction (resolution loop); a base whose elementary tracks of two tracks pass
    [48] against each other's track is not used by either this scan
    (fusion.assoc.ambiguous_members says why); a confirmed track that lost a member is
    rebuilt or floored by its sound members, any other confirmed track rebuilt when
    they contradict it (common.radar.fusion.reopen);
  module 62: new tracks from pairs of still free elementary tracks (tests 1-3, [44]-
    [46]); candidates that can be extended to more bases win conflicts, then lower
    residual; a candidate's conflicts include the elementary tracks of the other bases
    it would be extended to (without them, with four bases, pairs {b1, b2} and {b3,
    b4} of one target made two tracks: 193 tracks for 100 targets); step 5 extends
    the new tracks through module 63;
  seed 004: ambiguity of the predicted plan positions (x, y) (CrossingManager),
    alpha as gain; the altitude is left out (stated): the bands' spread made every
    pair of tracks of dense.toml ambiguous and kept them in memory mode (two aircraft
    at one plan position are told apart by the elementary tracks' own crossing
    management); alpha scales the gain of confirmed tracks only (dense300.toml: a new
    track's wide altitude mixture made it ambiguous with any neighbour, alpha = 0
    froze it for 60 s, a false track holding a target's elementary tracks);
  module 64 + 65: per altitude band, localisation from the contributing updated
    elementary tracks (one whose v_b the others contradict is dissociated), then the
    EKF update [49]-[50] of each component; weights, pruning, merging (fusion.track_filter);
  module 61: score = sum of the contributing elementary scores; tracks without any
    contributor stay in pure prediction (status coasting) and are deleted after
    `max_coast` cycles; numbers are stable and recycled (common.core.track_table), a
    removed or orphaned confirmed track's number held for the track that takes its
    elementary tracks (common.radar.fusion.succession), a confirmed track that lost every
    elementary track continued by the track confirmed after it on its aircraft (track
    segment association, common.radar.fusion.segments); a number once published as
    confirmed is not replaced. A track whose contributors were reported
    but gave no measurement (e.g. crossing.toml t = 52, 59) is predicted only but keeps
    its status, unless none was updated at its base for `coast_cycles` cycles
    (common.radar.fusion.status). Duplicates are merged: common.radar.fusion.merge.
    Confirmation: `confirm_cycles` cycles located on `confirm_bases` bases (three of
    four), counted again when a tentative track loses a member (FusionParams says why).
Decorrelation, module 64 per band and the mixture: common.radar.fusion.track_filter. Modules
63 ([48]) and 62 use the elementary tracks' estimates (common.radar.fusion.assoc: why).
Motion model: an IMM of two [51] models (common.radar.fusion.track_filter says why). Seed path
(`FusionParams.filter = "seed"`): 001's single EKF (benchmarks/seed_vs_mixture.py).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from common.core import imm
from common.core.crossing import CrossingManager, CrossingParams
from common.core.gating import chi2_gate
from common.core.rejection import Rejected
from common.core.track_table import TrackTable
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracks
from common.radar.fusion.assoc import (
    ETrackSet,
    ambiguous_members,
    component_gate,
    gated_component_pairs,
    gated_pairs,
    resolve,
)
from common.radar.fusion.decorrelation import Decorrelator
from common.radar.fusion.initiation import InitParams, altitude_bands, azimuth_pairs, pair_candidates, select
from common.radar.fusion.merge import merge_tracks
from common.radar.fusion.params import FusionCrossingParams, FusionParams
from common.radar.fusion.reopen import reopen
from common.radar.fusion.report import GlobalTracks, etrack_set
from common.radar.fusion.segments import segment_pairs
from common.radar.fusion.status import quiet_cycles, reported_status
from common.radar.fusion.succession import Succession
from common.radar.fusion.track_filter import MixtureFilter
from common.radar.geometry.bistatic import POS, BaseGeometry

PLAN = [0, 2]  # (x, y) in the state [x vx y vy z vz]: the plane of the crossing test


class GlobalFusion:
    """Global Cartesian tracks from the elementary tracks of all bases (001 step 24)."""

    def __init__(self, bases: Sequence[BaseGeometry], params: FusionParams | None = None,
                 crossing: CrossingParams | None = None,
                 tracker: ElementaryParams | None = None) -> None:
        """tracker: the elementary trackers' parameters ([radar.tracker]), for the F [19]
        and Q [20] of the decorrelation."""
        no_az = [b.id for b in bases if not b.azimuth]
        if no_az:
            raise ValueError(f"global fusion (001 step 24) needs the azimuth of every base; "
                             f"{', '.join(no_az)} declared azimuth = false (range-Doppler)")
        self.p = params or FusionParams()
        et = tracker or ElementaryParams()
        self.decorrelator = Decorrelator(et.sigma_gamma, et.sigma_omega,
                                         chi2_gate(self.p.eq_gate_prob, 3))
        self.init_p = InitParams(**{f.name: getattr(self.p, f.name)
                                    for f in dataclasses.fields(InitParams)})
        self.base_ids = [b.id for b in bases]
        self.confirm_bases = min(self.p.confirm_bases, max(2, len(bases) - 1))  # FusionParams
        self.index = {b: i for i, b in enumerate(self.base_ids)}
        self.tx = np.array([b.tx for b in bases], dtype=float)
        self.rx = np.array([b.rx for b in bases], dtype=float)
        if len(bases) < 2 or np.ptp(self.rx, axis=0).max() > 1e-6:
            raise ValueError("global fusion needs >= 2 bases sharing one receiver (001)")
        B = len(bases)
        self.filter = MixtureFilter(self.p, self.tx, self.rx)
        self.reopens = self.p.reopen_altitude and self.p.filter == "mixture"
        K = self.filter.A * self.filter.M  # components: altitude bands x motion models
        self.table = TrackTable(6, extra={"member": ((B,), np.int64), "has": ((B,), bool),
                                          "n_good": ((), np.int64), "n_quiet": ((), np.int64),
                                          "born": ((), float), "t_fix": ((), float),
                                          "confirmed": ((), bool), "published": ((), bool),
                                          "located": ((), bool), "ambiguous": ((), bool),
                                          "suspect": ((), bool), "mu": ((K,), float),
                                          "xm": ((K, 6), float), "Pm": ((K, 6, 6), float)})
        self.crossing = CrossingManager(crossing or FusionCrossingParams(method="supnorm"))
        self.succession = Succession(self.p.max_coast)  # common.radar.fusion.succession
        self.gamma_max = chi2_gate(self.p.gate_prob, 3)
        self.swap_gate = chi2_gate(self.p.gate_prob, 1)  # fusion.assoc.ambiguous_members
        self.segment_gate = chi2_gate(self.p.gate_prob, 6)  # fusion.segments
        self.az_gate = np.radians(self.p.az_gate_deg)
        self.pending: dict[float, dict[int, ElementaryTracks]] = {}
        self.t_last: float | None = None

    def is_late(self, t: float) -> bool:
        """True if a message of time t arrives after its cycle already ran."""
        return self.t_last is not None and t <= self.t_last

    def is_duplicate(self, base: str, t: float) -> bool:
        """True if `base` already has a message of time t waiting for its cycle."""
        return self.index[base] in self.pending.get(t, {})

    def push(self, base: str, tracks: ElementaryTracks, stale: frozenset[str] = frozenset()
             ) -> list[GlobalTracks]:
        """Buffer the report of one base (known, not late); run the cycles completed
        by the bases not in `stale` (base ids), oldest first. Raises Rejected for the
        3-state tracks of a range-Doppler base (no theta for 001 step 24)."""
        if tracks.x.shape[1] != 5:
            raise Rejected("no_azimuth", f"base {base}: elementary tracks without theta")
        self.pending.setdefault(tracks.t, {})[self.index[base]] = tracks
        need = {self.index[b] for b in self.base_ids if b not in stale}
        out = []
        while self.pending:
            t0 = min(self.pending)
            seen = {b for m in self.pending.values() for b in m}
            if not need <= seen:
                break  # some live base has reported neither t0 nor a later time
            out.append(self.cycle(t0, self.pending.pop(t0)))
        return out

    def cycle(self, t: float, msgs: dict[int, ElementaryTracks]) -> GlobalTracks:
        """One fusion cycle at time t with the reports of the bases that reported
        (processed in configured base order, whatever the arrival order)."""
        msgs = dict(sorted(msgs.items()))
        E = etrack_set(msgs, self.decorrelator, t)
        reported = np.zeros(len(self.base_ids), dtype=bool)
        reported[list(msgs)] = True
        tab = self.table
        live = tab.active_indices()
        x, P, xm, Pm, c = self.filter.predict(tab, t, live)  # [55]-[56]
        row, lost = self._confirm(live, (c, xm, Pm), E, reported)
        held = live[tab.confirmed[live] & self.reopens]
        held = held if self.p.reopen_watch else held[np.isin(held, lost)]  # fusion.reopen
        redo = reopen(held, self.filter, (x, P, xm, Pm, c), row, E, self.tx, self.rx, self.init_p,
                      self.p.gate_prob, floor=np.isin(held, lost))  # floored: lost a member
        free = np.ones(len(E), dtype=bool)
        free[row[row >= 0]] = False
        self._extend(live, (c, xm, Pm), E, reported, free, row)
        new, used = self._initialise(t, E, reported, free)
        if new.size:
            grow = tab.capacity - x.shape[0]
            x, P, xm, Pm, c = (np.concatenate([a, np.zeros((grow,) + a.shape[1:])])
                               for a in (x, P, xm, Pm, c))
            row = np.concatenate([row, np.full((grow, row.shape[1]), -1, dtype=np.intp)])
            x[new], P[new] = tab.x[new], tab.P[new]
            xm[new], Pm[new], c[new] = tab.xm[new], tab.Pm[new], tab.mu[new]
            for k in range(used.shape[1]):
                row[new, E.base[used[:, k]]] = used[:, k]
            self._extend(new, (c, xm, Pm), E, reported, free, row)
        now = tab.active_indices()
        withheld = ambiguous_members(c, xm, Pm, x, P, row, now[~np.isin(now, np.r_[new, redo])], E,
                                     self.tx, self.rx, self.az_gate, self.gamma_max, self.swap_gate)
        withheld[redo] = True  # rebuilt from this scan's estimates (fusion.reopen)
        confirmed_now = self._update(t, now, new, x, P, (xm, Pm, c), E, row, withheld)
        return self._manage(t, E, row, confirmed_now)

    def _confirm(self, live: np.ndarray, mixture: tuple[np.ndarray, np.ndarray, np.ndarray],
                 E: ETrackSet, reported: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Module 63 task 1: row of E of every membership (cap, B) after dissociating
        members that left or fail the gate [48] in every live component of the
        predicted mixture (weights, means, covariances; fusion.assoc.
        gated_component_pairs says why), -1 where none or base not reported; and the
        slots that lost a member (here, or by module 64's v_b test last cycle; fusion.reopen),
        whose confirmation count restarts if they are tentative."""
        tab = self.table
        row = np.full((tab.capacity, len(self.base_ids)), -1, dtype=np.intp)
        s, b = np.nonzero(tab.has[live] & reported[None, :])
        s = live[s]
        keys = E.base * (1 << 40) + E.id
        order = np.argsort(keys)
        k = b * (1 << 40) + tab.member[s, b]
        r = order[np.clip(np.searchsorted(keys[order], k), 0, len(E) - 1)] if len(E) else k * 0
        ok = (keys[r] == k) if len(E) else np.zeros(k.size, dtype=bool)
        sel = np.flatnonzero(ok)  # all bases at once
        ok[sel] = component_gate(*(a[s[sel]] for a in mixture), E.y[r[sel]], E.R[r[sel]],
                                 self.tx[b[sel]], self.rx[b[sel]], self.gamma_max)  # [48]
        tab.has[s[~ok], b[~ok]] = False  # dissociation
        failed = sel[~ok[sel]]  # reported, failed [48]
        self.succession.dissociated(tab, s[failed], b[failed])
        row[s[ok], b[ok]] = r[ok]
        lost = np.union1d(s[~ok], live[tab.suspect[live]])
        tab.n_good[lost[~tab.confirmed[lost]]] = 0  # confirmation restarts (FusionParams)
        return row, lost

    def _extend(self, slots: np.ndarray, mixture: tuple[np.ndarray, np.ndarray, np.ndarray],
                E: ETrackSet, reported: np.ndarray, free: np.ndarray, row: np.ndarray) -> None:
        """Module 63 tasks 2-3: free elementary tracks of base b to the tracks of
        `slots` that do not contain b, by the resolution loop (gate [48] per mixture
        component: fusion.assoc.gated_component_pairs)."""
        tab = self.table
        for b in np.flatnonzero(reported):
            tracks = slots[~tab.has[slots, b]]
            ets = np.flatnonzero(free & (E.base == b))
            i, m, g = gated_component_pairs(*mixture, tracks, ets, E, self.tx[b], self.rx[b],
                                            self.az_gate, self.gamma_max)
            ti, mi = resolve(i, m, g)
            tab.has[ti, b] = True
            tab.member[ti, b] = E.id[mi]
            row[ti, b] = mi
            free[mi] = False

    def _initialise(self, t: float, E: ETrackSet, reported: np.ndarray,
                    free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Module 62 on the free elementary tracks: (slots of the new tracks, their two
        elementary tracks (n, 2) as rows of E)."""
        none = np.zeros(0, dtype=np.intp), np.zeros((0, 2), dtype=np.intp)
        ok = free & E.updated & (E.confirmed if self.p.init_confirmed_only else True)
        ia, ib = [], []
        for a in np.flatnonzero(reported):
            for b in np.flatnonzero(reported):
                if b <= a:
                    continue
                ra = np.flatnonzero(ok & (E.base == a))
                rb = np.flatnonzero(ok & (E.base == b))
                pa, pb = azimuth_pairs(E.y[ra, 2], E.y[rb, 2], self.az_gate)  # test 1
                ia.append(ra[pa])
                ib.append(rb[pb])
        if not ia:
            return none
        seed = self.p.filter == "seed"
        cand = pair_candidates(E.y, E.R, E.base, np.concatenate(ia), np.concatenate(ib),
                               self.tx, self.rx, self.init_p, seed)  # tests 2-3, step 4
        n_c = cand.rows.shape[0]
        if n_c == 0:
            return none
        ext = np.full((n_c, len(self.base_ids)), -1, dtype=np.intp)
        own = E.base[cand.rows]
        for b in np.flatnonzero(reported):
            ets = np.flatnonzero(free & (E.base == b))
            i, m, g = gated_pairs(cand.x, cand.P, np.arange(n_c), ets, E, self.tx[b],
                                  self.rx[b], self.az_gate, self.gamma_max)
            order = np.lexsort((g, i))
            i, m = i[order], m[order]
            first = np.r_[True, i[1:] != i[:-1]] if i.size else np.zeros(0, dtype=bool)
            ext[i[first], b] = m[first]  # the best elementary track of b for step 5
        ext[np.arange(n_c)[:, None], own] = -1
        n_ext = (ext >= 0).sum(axis=1)
        win = select(np.concatenate([cand.rows, ext], axis=1), cand.cost - 1e6 * n_ext)
        tab = self.table
        slots = tab.add(win.size, avoid=self.succession.held())
        used = cand.rows[win]
        if seed:  # one component: the state and covariance [44]-[46] of the candidate
            xb, Pb, wb = cand.x[win][:, None], cand.P[win][:, None], np.ones((win.size, 1))
        else:
            xb, Pb, wb = altitude_bands(cand.x[win][:, POS], E.y, E.R, E.base, used,
                                        self.tx, self.rx, self.init_p)
        xm, Pm, mu = self.filter.initial(xb, Pb, wb)
        tab.xm[slots], tab.Pm[slots], tab.mu[slots] = xm, Pm, mu
        tab.x[slots], tab.P[slots] = imm.combine(mu, xm, Pm)
        tab.t_last[slots] = tab.born[slots] = tab.t_fix[slots] = t
        for k in range(2):
            tab.has[slots, E.base[used[:, k]]] = True
            tab.member[slots, E.base[used[:, k]]] = E.id[used[:, k]]
            free[used[:, k]] = False
        return slots, used

    def _update(self, t: float, live: np.ndarray, new: np.ndarray, x: np.ndarray,
                P: np.ndarray, models: tuple[np.ndarray, np.ndarray, np.ndarray], E: ETrackSet,
                row: np.ndarray, withheld: np.ndarray) -> np.ndarray:
        """Localisation (64) per altitude band, crossing test (004) on the combined
        prediction (x, P), EKF update (65) of every component of `models` (xm, Pm, c:
        MixtureFilter.predict), weights, pruning, merging at t (fusion.track_filter); status;
        `withheld` (cap, B): ambiguous memberships, not used. Returns the slots
        confirmed this cycle."""
        tab = self.table
        r = row[live]
        active = np.append(E.meas, False)[r] & ~np.isin(live, new)[:, None] & ~withheld[live]
        n_act = active.sum(1)
        multi, single = n_act >= 2, n_act == 1
        xl, Pl, cl = models[0][live], models[1][live], models[2][live]
        fix = self.filter.locate(xl, Pl, cl, multi, r, active, E)  # module 64
        active &= ~fix.dropped  # v_b leave-one-out test (fusion.track_filter): dissociated
        tab.has[live] &= ~fix.dropped
        tab.suspect[live] = fix.dropped.any(axis=1)  # fusion.reopen, next cycle
        row[live] = r = np.where(fix.dropped, -1, r)
        tab.located[live] = located = fix.located  # fusion.merge.explained's held
        alpha, amb = self.crossing.step(t, tab.id[live], x[live][:, PLAN],  # 004, (x, y)
                                        P[live][:, PLAN][:, :, PLAN], z_meas=fix.post[:, :2],
                                        n_meas=int(located.sum()))
        tab.ambiguous[live] = amb
        alpha = np.where(tab.confirmed[live], alpha, 1.0)  # confirmed tracks only (module doc)
        mu = self.filter.update(xl, Pl, cl, fix, single, r, active, E, alpha)  # module 65
        tab.xm[live], tab.Pm[live], tab.mu[live] = xl, Pl, mu
        tab.x[live], tab.P[live] = imm.combine(mu, xl, Pl)
        tab.t_last[live] = t
        updated = located | single
        tab.n_coast[live] = np.where(updated, 0, tab.n_coast[live] + 1)
        tab.t_fix[live] = np.where(updated, t, tab.t_fix[live])
        tab.n_good[live] += located & (n_act >= self.confirm_bases)
        was = tab.confirmed[live]
        tab.confirmed[live] = was | (tab.n_good[live] >= self.p.confirm_cycles)
        tab.n_quiet[live] = quiet_cycles(tab.n_quiet[live], np.append(E.updated, False)[r].any(1))
        tab.status[live] = reported_status(tab.confirmed[live], (r >= 0).any(1), np.isin(live, new),
                                           tab.n_quiet[live], self.p.coast_cycles)  # module 61
        return live[tab.confirmed[live] & ~was]

    def _continue_segments(self, t: float, now: np.ndarray) -> np.ndarray:
        """Track segment association (common.radar.fusion.segments) of the tracks `now`
        (confirmed this cycle) with the confirmed tracks that lost every member; returns
        the tracks of `now` left in their slots."""
        tab = self.table
        live = tab.active_indices()
        old = live[tab.confirmed[live] & ~tab.has[live].any(axis=1) & (tab.n_coast[live] > 0)]
        i, j = segment_pairs(tab.x[old], tab.P[old], t - tab.t_fix[old], tab.x[now], tab.P[now],
                             self.p.segment_accel, self.segment_gate)
        keep = tab.born[now[j]] >= tab.t_fix[old[i]]  # segments disjoint in time
        self.crossing.forget(self.succession.continue_segments(tab, now[j[keep]], old[i[keep]]))
        return now[tab.alive[now]]

    def _manage(self, t: float, E: ETrackSet, row: np.ndarray, now: tuple | np.ndarray = ()) -> GlobalTracks:
        """Module 61: scores, deletion, recycling, succession of `now` (slots confirmed this
        cycle); the global tracks of the cycle."""
        tab = self.table
        live = tab.active_indices()
        r = row[live]
        tab.score[live] = np.append(E.score, 0.0)[r].sum(axis=1)  # module 61
        orphan = ~tab.has[live].any(axis=1)
        dead = live[orphan & (tab.n_coast[live] > self.p.max_coast)]
        now = np.asarray(now, dtype=np.intp)
        now = now[~tab.published[now]]  # new numbers only: a published number is kept
        gone, renamed = merge_tracks(tab, live, r, E, self.tx, self.rx, self.az_gate,
                                     self.gamma_max, now)  # common.radar.fusion.merge
        dead = np.union1d(dead, gone)
        if dead.size:
            self.crossing.forget(tab.id[np.union1d(dead, renamed)])
            self.succession.vacate(tab, dead)
            tab.remove(dead)
        now = now[tab.alive[now]]
        if self.p.segment_accel > 0:
            now = self._continue_segments(t, now)
        self.crossing.forget(self.succession.inherit(tab, now))
        self.t_last = t
        s = tab.active_indices()
        tab.published[s] |= tab.confirmed[s]
        return GlobalTracks(float(t), tuple(self.base_ids), tab.id[s].copy(), tab.status[s].copy(),
                            tab.x[s].copy(), tab.P[s].copy(), tab.score[s].copy(),
                            tab.member[s].copy(), tab.has[s].copy(), tab.ambiguous[s].copy())
