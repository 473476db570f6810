"""Track-level state of the multiple-hypothesis tracker (common.sonar.mht.tracker) and its
resolution-conflict steps: per-track arrays (000 SA, ZA, IN and the conflict memory),
the duplicate rule of the confirmation test, conflict detection, the modified
correction of conflicting pairs, and the re-link at the end of a conflict.
Equations and deviations: common.sonar.mht.conflict and common.sonar.mht.tracker.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from common.core.angles import wrap_pi
from common.core.gating import quadratic_form
from common.sonar.mht.conflict import interpret, relink_choice, unresolved_probability
from common.sonar.mht.hypotheses import heaviest, pair_distance2
from common.sonar.mht.params import MhtParams


class MhtState(Protocol):
    """What these steps read and change of the multiple-hypothesis tracker
    (common.sonar.mht.tracker.MhtTracker): the flat hypothesis arrays hx, hP, hc, ht,
    hmeas, the track arrays, the cycle number, the parameters and the models."""

    hx: np.ndarray
    hP: np.ndarray
    hc: np.ndarray
    ht: np.ndarray
    hmeas: np.ndarray
    tr: TrackArrays
    k: int
    mp: MhtParams
    q_models: tuple[float, ...]

    def transition(self, T: float) -> np.ndarray: ...

    def process_noise(self, T: float, q_theta: float) -> np.ndarray: ...


_FIELDS: dict[str, tuple[type, float]] = {
    "uid": (np.int64, 0), "SA": (np.int8, 0), "ZA": (np.int64, 0), "IN": (np.int64, -1),
    "k_auf": (np.int64, 0), "born": (np.int64, 0), "no_b": (np.int64, 0),
    "ever_confirmed": (np.bool_, False), "coalesced": (np.bool_, False),
    "pre_t": (np.float64, 0.0), "last_t": (np.float64, 0.0),
}  # and the states pre_x, pre_P, last_x, last_P of TrackArrays(n)


class TrackArrays:
    """One array per track attribute, indexed by track slot: uid (published number),
    SA (1 confirmed, 0 tentative), ZA (SPRT counter), IN (uid of the track in conflict,
    -1 none), k_auf (cycle the conflict began), born (cycle of creation), no_b (cycles
    in a row without LR > B), ever_confirmed, coalesced (the conflicting pair's main
    hypotheses took one measurement or came within d_merge), pre_t, pre_x (N, n), pre_P
    (N, n, n) (time, state and covariance of the main hypothesis before the conflict: its
    bearing rate and level for the re-link), last_t, last_x, last_P (the same, last
    cycle)."""

    uid: np.ndarray
    SA: np.ndarray
    ZA: np.ndarray
    IN: np.ndarray
    k_auf: np.ndarray
    born: np.ndarray
    no_b: np.ndarray
    ever_confirmed: np.ndarray
    coalesced: np.ndarray
    pre_t: np.ndarray
    pre_x: np.ndarray
    pre_P: np.ndarray
    last_t: np.ndarray
    last_x: np.ndarray
    last_P: np.ndarray

    def __init__(self, n: int) -> None:
        """n: the state dimension."""
        self.shapes: dict[str, tuple[int, ...]] = {name: () for name in _FIELDS}
        self.shapes.update({"pre_x": (n,), "last_x": (n,), "pre_P": (n, n), "last_P": (n, n)})
        for name, shape in self.shapes.items():
            dtype = _FIELDS[name][0] if name in _FIELDS else np.float64
            setattr(self, name, np.zeros((0,) + shape, dtype=dtype))
        self.next_uid = 1

    @property
    def size(self) -> int:
        return int(self.uid.size)

    def add(self, k: int, cycle: int) -> np.ndarray:
        """Append k new tentative tracks (000: SA = ZA = 0, no conflict); their slots."""
        start = self.size
        for name, shape in self.shapes.items():
            dtype, default = _FIELDS.get(name, (np.float64, 0.0))
            setattr(self, name, np.concatenate([getattr(self, name),
                                                np.full((k,) + shape, default, dtype=dtype)]))
        self.uid[start:] = np.arange(self.next_uid, self.next_uid + k)
        self.born[start:] = cycle
        self.next_uid += k
        return np.arange(start, start + k)

    def split(self, src: np.ndarray, cycle: int) -> np.ndarray:
        """New tentative tracks split off tracks `src` (000 split; the status is not
        inherited, see common.sonar.mht.tracker); their slots."""
        return self.add(src.size, cycle)

    def keep(self, mask: np.ndarray) -> None:
        """Keep the tracks of `mask` (slot order preserved)."""
        for name in self.shapes:
            setattr(self, name, getattr(self, name)[mask])

    def slot_of(self, uid: int) -> int:
        """Slot of a track number, -1 if not live."""
        hit = np.flatnonzero(self.uid == uid)
        return int(hit[0]) if hit.size else -1


def duplicates(tr: TrackArrays, mmeas: np.ndarray, M: int) -> np.ndarray:
    """Tentative tracks whose main hypothesis took the measurement of a confirmed
    track's or an older track's main hypothesis (they do not pass the SPRT)."""
    has = mmeas >= 0
    if M == 0:
        return has
    by_conf = np.zeros(M, dtype=bool)
    by_conf[mmeas[has & (tr.SA == 1)]] = True
    oldest = np.full(M, np.iinfo(np.int64).max)
    np.minimum.at(oldest, mmeas[has], tr.uid[has])
    safe = np.maximum(mmeas, 0)
    return (tr.SA == 0) & has & (by_conf[safe] | (oldest[safe] < tr.uid))


def conflict_flags(trk: MhtState, t: float) -> None:
    """000 conflict detection: confirmed tracks whose main hypotheses processed the
    same measurement get IN = each other; a conflict whose P_u fell below 1e-3 ends
    (a coalesced pair first gets its crossing order, `crossing_order`)."""
    tr = trk.tr
    main = heaviest(trk.hc, trk.ht, tr.size)
    brg = trk.hx[np.maximum(main, 0), 0]
    res = math.radians(trk.mp.res_deg)
    ended = []
    for i in np.flatnonzero(tr.IN >= 0):
        j = tr.slot_of(int(tr.IN[i]))
        if j < 0 or unresolved_probability(brg[i] - brg[j], res) < 1e-3:
            tr.IN[i] = -1
            if j > i and tr.coalesced[i] and main[i] >= 0 and main[j] >= 0:
                ended.append((int(i), j))
        elif j > i and _coalesced(trk, main, i, j):
            tr.coalesced[[i, j]] = True
    if any([crossing_order(trk, i, j, main, t) for i, j in ended]):
        main = heaviest(trk.hc, trk.ht, tr.size)
    tr.coalesced[tr.IN < 0] = False
    meas = np.where(main >= 0, trk.hmeas[np.maximum(main, 0)], -1)
    conf = np.flatnonzero((tr.SA == 1) & (meas >= 0) & (tr.IN < 0))
    _pair_sharing(tr, conf, meas[conf], trk.k)
    ok = main >= 0
    m = main[ok]
    tr.last_t[ok], tr.last_x[ok], tr.last_P[ok] = t, trk.hx[m], trk.hP[m]


def _coalesced(trk: MhtState, main: np.ndarray, i: int, j: int) -> bool:
    """The main hypotheses of a conflicting pair took one measurement or are closer than
    d_merge (both follow one target)."""
    mi, mj = int(main[i]), int(main[j])
    if mi < 0 or mj < 0:
        return False
    if trk.hmeas[mi] >= 0 and trk.hmeas[mi] == trk.hmeas[mj]:
        return True
    return _merged(trk, mi, mj)


def _duplicate(trk: MhtState, w: int, a: int, b: int) -> bool:
    """A new track's main hypothesis w beside a conflicting pair's main hypotheses a, b
    that are not within d_merge (`_merged`: the pair holds two targets, unresolved) and
    not resolved from them (its bearing inside the gate lambda of a or b, in the sigma of
    the bearing difference): a duplicate of one of the pair's targets."""
    d = np.abs(wrap_pi(trk.hx[w, 0] - trk.hx[[a, b], 0]))
    inside = d < trk.mp.gate * np.sqrt(trk.hP[w, 0, 0] + trk.hP[[a, b], 0, 0])
    return bool(inside.any()) and not _merged(trk, a, b)


def _merged(trk: MhtState, a: int, b: int) -> bool:
    """Hypotheses a and b closer than d_merge (000 d^2 < d_merge^2 over the whole state:
    bearing, bearing rate, level and its rate)."""
    return bool(pair_distance2(trk.hx[[a]], trk.hP[[a]], trk.hx[[b]], trk.hP[[b]])[0] < trk.mp.d_merge**2)


def _innovation(trk: MhtState, s: int, x: np.ndarray, P: np.ndarray, t: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """y, S of a state x, P at t (bearing, rate, level) against track s's state from before
    its conflict, predicted with the quiet model's F and Q."""
    tr = trk.tr
    T = t - tr.pre_t[s]
    F = trk.transition(T)
    xp = F @ tr.pre_x[s]
    S = (P + F @ tr.pre_P[s] @ F.T + trk.process_noise(T, trk.q_models[0]))[:3, :3]
    y = x[:3] - xp[:3]
    y[0] = wrap_pi(y[0])
    return y, S


def continuation(trk: MhtState, s: int, x: np.ndarray, P: np.ndarray, t: float) -> float:
    """ln N of a state x, P at t as the continuation of track s's state from before its
    conflict (`_innovation`)."""
    y, S = _innovation(trk, s, x, P, t)
    return float(-0.5 * (quadratic_form(y, S) + np.linalg.slogdet(S)[1]))


def _off_bearing(trk: MhtState, s: int, w: int, t: float) -> bool:
    """Hypothesis w's bearing outside the gate lambda of track s's prediction from before
    its conflict (`_innovation`, bearing alone)."""
    y, S = _innovation(trk, s, trk.hx[w], trk.hP[w], t)
    return bool(y[0] ** 2 > trk.mp.gate**2 * S[0, 0])


def _coalesced_pick(trk: MhtState, i: int, j: int, w: int, m: int, t: float) -> int:
    """Member (0: i, 1: j) of a coalesced pair whose place omega (hypothesis w) takes, the
    pair's main hypothesis m on the other: both pairings (`exchanged_likelier`); when
    omega's bearing is outside the gate of both members' predictions (deviation: omega
    continues neither, how far outside is no evidence), the member whose state m
    continues likelier keeps m (sonar_cross_4dpm_uneq seed 169: omega, 5 and 8 sigma from
    the predictions, went to the one it missed by less, a member whose rate before the
    conflict was 11 sigma wrong; the pair continued the other's state)."""
    if _off_bearing(trk, i, w, t) and _off_bearing(trk, j, w, t):
        x, P = trk.hx[m], trk.hP[m]
        return int(continuation(trk, i, x, P, t) > continuation(trk, j, x, P, t))
    return int(exchanged_likelier(trk, i, j, w, m, t))


def exchanged_likelier(trk: MhtState, i: int, j: int, a: int, b: int, t: float) -> bool:
    """Whether hypotheses a (now on track i) and b (on j) continue j's and i's states from
    before the conflict better than i's and j's (`continuation`, both pairings)."""
    hx, hP = trk.hx, trk.hP
    held = continuation(trk, i, hx[a], hP[a], t) + continuation(trk, j, hx[b], hP[b], t)
    swapped = continuation(trk, i, hx[b], hP[b], t) + continuation(trk, j, hx[a], hP[a], t)
    return swapped > held


def crossing_order(trk: MhtState, i: int, j: int, main: np.ndarray, t: float) -> bool:
    """End of a coalesced conflict (deviation, common.sonar.mht.tracker): while the two tracks
    followed one target their hypotheses no longer told which target each had; when their
    main hypotheses continue the other's state from before the conflict better than their
    own (`exchanged_likelier`), the two exchange their hypotheses (each number continues
    on the target it had before). Returns whether they did."""
    if not exchanged_likelier(trk, i, j, int(main[i]), int(main[j]), t):
        return False
    own, theirs = trk.ht == i, trk.ht == j
    trk.ht[own], trk.ht[theirs] = j, i
    return True


def _pair_sharing(tr: TrackArrays, slots: np.ndarray, meas: np.ndarray, k: int) -> None:
    """Start a conflict (IN, k_auf, bearing rate and level from before it) for tracks
    of `slots` that share a measurement `meas` and are in no conflict yet."""
    order = np.argsort(meas, kind="stable")
    for a, b in zip(order[:-1], order[1:]):
        s, t = int(slots[a]), int(slots[b])
        if meas[a] == meas[b] and s != t and tr.IN[s] < 0 and tr.IN[t] < 0:
            tr.IN[s], tr.IN[t] = tr.uid[t], tr.uid[s]
            tr.k_auf[s] = tr.k_auf[t] = k
            for name in ("t", "x", "P"):
                getattr(tr, "pre_" + name)[[s, t]] = getattr(tr, "last_" + name)[[s, t]]


def conflict_pairs(tr: TrackArrays) -> list[tuple[int, int]]:
    """Slots (i, j) of the pairs in a resolution conflict, each pair once."""
    out = []
    for i in np.flatnonzero(tr.IN >= 0):
        j = tr.slot_of(int(tr.IN[i]))
        if j > i:
            out.append((int(i), j))
    return out


def resolve_conflicts(
    trk: MhtState, xp: np.ndarray, Pp: np.ndarray, pd: np.ndarray, hi: np.ndarray,
    lj: np.ndarray, lgN: np.ndarray, z: np.ndarray, Rd: np.ndarray, cx: np.ndarray,
    cP: np.ndarray, cc: np.ndarray, cpar: np.ndarray, cmeas: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """000 modified correction: for every conflicting pair whose main hypotheses are again
    gated with a common measurement, the children of the two main hypotheses are replaced
    by the moment-matched joint interpretations (1)-(5); each main hypothesis keeps the
    total weight of its children. lgN: log N(z_l) of every child (0 for misses)."""
    tr, mp = trk.tr, trk.mp
    main = heaviest(trk.hc, trk.ht, tr.size)
    free = main[(tr.SA == 1) & (main >= 0) & (tr.IN < 0)]
    sel = np.isin(hi, free)
    _pair_sharing(tr, trk.ht[hi[sel]], lj[sel], trk.k)  # main predictions gate one measurement
    pairs = conflict_pairs(tr)
    if not pairs:
        return cx, cP, cc, cpar, cmeas
    new: list[tuple[int, int, np.ndarray, np.ndarray, float]] = []
    cc = cc.copy()
    cx, cP = cx.copy(), cP.copy()
    for i, j in pairs:
        mi, mj = int(main[i]), int(main[j])
        if mi < 0 or mj < 0 or not np.intersect1d(lj[hi == mi], lj[hi == mj]).size:
            continue
        kids = [np.flatnonzero(cpar == mi), np.flatnonzero(cpar == mj)]
        hits = [{int(cmeas[q]): (cx[q], cP[q], float(lgN[q])) for q in ks if cmeas[q] >= 0}
                for ks in kids]
        res = interpret(((xp[mi], Pp[mi]), (xp[mj], Pp[mj])), (hits[0], hits[1]),
                        (float(pd[mi]), float(pd[mj])), z, Rd, mp.rho_f,
                        math.radians(mp.res_deg), mp.p_d_max, mp.d_thr)
        for parent, ks, marg in ((mi, kids[0], res[0]), (mj, kids[1], res[1])):
            evidence = cc[ks].sum()
            seen = set()
            for q in ks:
                key = int(cmeas[q])
                seen.add(key)
                if key in marg:
                    cx[q], cP[q], cc[q] = marg[key][0], marg[key][1], evidence * marg[key][2]
                else:
                    cc[q] = 0.0
            for key in sorted(set(marg) - seen):
                new.append((parent, key, marg[key][0], marg[key][1], evidence * marg[key][2]))
    if new:
        cx = np.concatenate([cx, np.array([r[2] for r in new])])
        cP = np.concatenate([cP, np.array([r[3] for r in new])])
        cc = np.concatenate([cc, [r[4] for r in new]])
        cpar = np.concatenate([cpar, np.array([r[0] for r in new], dtype=np.intp)])
        cmeas = np.concatenate([cmeas, np.array([r[1] for r in new], dtype=np.intp)])
    return cx, cP, cc, cpar, cmeas


def relink(trk: MhtState, newly: np.ndarray, t: float) -> np.ndarray:
    """000 end of a resolution conflict: a track omega confirmed this cycle (time t),
    younger than the conflict of (i, j), whose main hypothesis is within d_Auf of a
    hypothesis of i or j is linked to that track's past (by the bearing-rate sign, then
    the level from before the conflict, when near both); when i and j have coalesced
    (`_coalesced`) and omega is within relink_deg of them, to the one whose state from
    before the conflict omega continues likelier (`_coalesced_pick`) if their main
    hypotheses are closer than d_merge (`_merged`: both follow one target, omega is the
    other); if they only took one measurement (000's unresolved interpretation (1) of two
    targets with distinct states), the pair holds both targets and omega inside their gate
    (`_duplicate`) is deleted, the pair untouched. Returns the mask of tracks to delete."""
    tr, mp = trk.tr, trk.mp
    drop = np.zeros(tr.size, dtype=bool)
    if newly.size == 0:
        return drop
    main = heaviest(trk.hc, trk.ht, tr.size)
    for i, j in conflict_pairs(tr):
        for w in newly:
            if drop[w] or tr.born[w] <= tr.k_auf[i] or main[w] < 0:
                continue
            mw = int(main[w])
            near = []
            for s in (i, j):
                h = np.flatnonzero(trk.ht == s)
                d2 = pair_distance2(np.repeat(trk.hx[mw][None], h.size, 0),
                                    np.repeat(trk.hP[mw][None], h.size, 0), trk.hx[h], trk.hP[h])
                near.append(bool((d2 < mp.d_auf**2).any()))  # 000 d^2 < d_Auf^2
            coalesced = False
            if not any(near) and _coalesced(trk, main, i, j):  # deviation, common.sonar.mht.tracker
                off = abs(float(wrap_pi(trk.hx[mw, 0] - trk.hx[main[i], 0])))
                near = [off < math.radians(mp.relink_deg)] * 2
                coalesced = near[0]
            if not any(near):
                continue
            if coalesced and _duplicate(trk, mw, int(main[i]), int(main[j])):
                drop[w] = True  # deviation: the pair holds both targets, omega is a duplicate
                continue
            if coalesced:  # deviation: omega and the pair's main hypothesis on the two
                pick = _coalesced_pick(trk, i, j, mw, int(main[j]), t)
            elif all(near):
                pick = relink_choice(trk.hx[mw, 1], trk.hx[mw, 2], tr.pre_x[i, 1], tr.pre_x[j, 1],
                                     tr.pre_x[i, 2], tr.pre_x[j, 2])
            else:
                pick = 0 if near[0] else 1
            s = (i, j)[pick]
            own, theirs = trk.ht == s, trk.ht == w
            trk.ht[own], trk.ht[theirs] = w, s  # s continues with omega's hypotheses
            drop[w] = True
            _end_by_relink(tr, i, j, s, w)
            break
    return drop


def _end_by_relink(tr: TrackArrays, i: int, j: int, s: int, w: int) -> None:
    """000 end of the conflict of (i, j) by the re-link of omega (slot w) to track s: the
    conflict memory goes with it (IN, coalesced), and s's state of this cycle, from which
    a conflict starting next cycle takes its state from before the conflict, is omega's."""
    tr.IN[[i, j]] = -1
    tr.coalesced[[i, j]] = False
    for name in ("t", "x", "P"):
        getattr(tr, "last_" + name)[s] = getattr(tr, "last_" + name)[w]
