"""Retrodiction of seed 000 ("nueva valoracion de los estados anteriores") for the
multiple-hypothesis tracker, and the bearing register it serves.

Every cycle the tracker pushes a `CycleRecord`: its hypotheses (x, P, c), the owning
track of each, the parent hypothesis in the previous record and the prediction x^pre,
P^pre that was updated into it. `Retrodiction.push` then smooths the last n_retro cycles
backwards, vectorised over all hypotheses:
    W_h(l) = P_h(l) F' P^pre_h(l+1)^-1
    x^retro_h(l) = x_h(l) + W_h(l) (x^retro(l+1) - x^pre(l+1))
    P^retro_h(l) = P_h(l) + W_h(l) (P^retro(l+1) - P^pre(l+1)) W_h(l)'
    c^retro_h(l) = sum of c^retro of the hypotheses of l+1 formed from h.
and writes the tracks' smoothed bearings (mixture moments of the retro hypotheses) into
the register rows of those cycles; a row older than n_retro cycles keeps its last value.

Deviations (stated): a hypothesis of cycle l usually has several children at l+1, each
giving its own smoothed state of h; the seed gives only the weight rule, so x^retro_h(l)
and P^retro_h(l) are the moment-matched mixture of these child-conditioned states with
the children's retro weights. A merged hypothesis (000 hypothesis merge) continues the
lineage of its heaviest member only. The newest cycle's retro weights are the filtered
weights normalised per track. The seed smooths confirmed tracks only; the smoother runs
on all hypotheses (one batched pass costs less than selecting) and the register serves
confirmed tracks only.

The register (issue 13): TMA needs independent bearings with their true sigma, and the
smoothed bearings are correlated from cycle to cycle (the single-hypothesis register,
common.sonar.bearing.history, says by how much). So every record also keeps, per
hypothesis, the detection it was formed from (bearing and sigma; none for a missed
detection, and none while the track is in a resolution conflict of 000, whose
detections may be the other target's). The register row of a track at cycle l is the
detection of its main hypothesis by the retro weights c^retro(l): retrodiction re-judges
which detection was the track's, and the smoothed bearing is served beside it
(`smoothed`). A row whose main hypothesis has no detection is not served. Since the
window's rows change every cycle, the register is also served as of an earlier cycle
(common.sonar.mht.register_versions).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from common.sonar.bearing.history import HISTORY_COLUMNS
from common.sonar.mht.hypotheses import heaviest, mixture_moments, state_diff, track_sums
from common.sonar.mht.register_versions import RegisterVersions

SMOOTHED_COLUMNS = ("t", "brg", "sbrg")
# columns of a record's rows: time, smoothed bearing and sigma, own position, detection
T, SMOOTH, OWN, DET = 0, slice(1, 3), slice(3, 5), slice(5, 7)


@dataclass
class CycleRecord:
    """One cycle: hypotheses x (H, n), P (H, n, n), c (H,), track (H,) index into uid
    (T,), parent (H,) index into the previous record's hypotheses (-1: none), x_pre,
    P_pre the prediction updated into each hypothesis, F (n, n) or (H, n, n) its transition
    from the previous cycle (000 F; zero bearing rows where the bearing block was predicted
    from the contact's TMA solution, common.sonar.bearing.tma_prediction), rows (T, 7) the
    register block of this cycle (t, smoothed brg and sbrg, own x and y, the main
    hypothesis's detection brg and sbrg), det (H, 2) the detection (brg, sbrg) each
    hypothesis was formed from (NaN: none)."""

    x: np.ndarray
    P: np.ndarray
    c: np.ndarray
    track: np.ndarray
    uid: np.ndarray
    parent: np.ndarray
    x_pre: np.ndarray
    P_pre: np.ndarray
    F: np.ndarray
    rows: np.ndarray
    det: np.ndarray


def smooth(records: list[CycleRecord]) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """000 retrodiction over the records (oldest first): (x^retro, P^retro, c^retro) per
    record, same order."""
    last = records[-1]
    n_t = last.uid.size
    ci = track_sums(last.c, last.track, n_t)
    out = [(last.x, last.P, last.c / np.where(ci > 0, ci, 1.0)[last.track])]
    for l in range(len(records) - 2, -1, -1):
        rec, nxt = records[l], records[l + 1]
        xr_n, Pr_n, cr_n = out[0]
        ch = np.flatnonzero(nxt.parent >= 0)
        p = nxt.parent[ch]
        Pp = rec.P[p]
        # W' = P^pre^-1 F P (P^pre symmetric): 000 W_h(l) = P_h(l) F' P^pre^-1(l+1)
        Fc = nxt.F[ch] if nxt.F.ndim == 3 else nxt.F  # one F (n, n) or one per hypothesis
        Wt = np.linalg.solve(nxt.P_pre[ch], Fc @ Pp)
        W = np.swapaxes(Wt, 1, 2)
        xs = rec.x[p] + (W @ state_diff(xr_n[ch], nxt.x_pre[ch])[..., None])[..., 0]  # 000 x^retro
        Ps = Pp + W @ (Pr_n[ch] - nxt.P_pre[ch]) @ Wt  # 000 P^retro
        H = rec.c.size
        cr = np.bincount(p, weights=cr_n[ch], minlength=H)  # 000 c^retro = sum over children
        xr, Pr = rec.x.copy(), rec.P.copy()
        has = cr > 0
        if ch.size:
            w = cr_n[ch]
            ok = w > 0
            _, xm, Pm = mixture_moments(xs[ok], Ps[ok], w[ok], p[ok], H)
            xr[has], Pr[has] = xm[has], Pm[has]
        out.insert(0, (xr, Pr, cr))
    return out


class Retrodiction:
    """The last n_retro cycle records, their smoothing, and the bearing register
    (rows per track from its first detection; the last n_retro rows retrodicted), and
    the window as each of the last ``keep_versions`` cycles left it."""

    def __init__(self, n_retro: int, keep_deleted: int = 64, keep_versions: int = 0) -> None:
        self.n_retro = max(1, n_retro)
        self.keep_deleted = keep_deleted
        self.window: deque[CycleRecord] = deque(maxlen=self.n_retro)
        self._blocks: list[tuple[np.ndarray, np.ndarray]] = []  # (uid (T,), rows (T, 5))
        self.retired: list[int] = []
        self._inherits: dict[int, tuple[int, float]] = {}
        self.versions = RegisterVersions(keep_versions)

    def push(self, rec: CycleRecord) -> None:
        """Add a cycle, smooth the window, rewrite the window's register rows."""
        self.window.append(rec)
        self._blocks.append((rec.uid, rec.rows))
        _main_detections(rec, rec.c)
        recs = list(self.window)
        if len(recs) > 1:
            for r, (xr, Pr, cr) in zip(recs[:-1], smooth(recs)[:-1]):
                n_t = r.uid.size
                live = track_sums(cr, r.track, n_t) > 0
                if not live.any():
                    continue
                keep = live[r.track] & (cr > 0)
                _, xt, Pt = mixture_moments(xr[keep], Pr[keep], cr[keep], r.track[keep], n_t)
                good = live & (Pt[:, 0, 0] > 0)  # else precision lost (Q >> P): keep the filtered row
                r.rows[good, 1] = xt[good, 0]
                r.rows[good, 2] = np.sqrt(Pt[good, 0, 0])
                _main_detections(r, cr)
        self.versions.record([(r.uid, r.rows) for r in self.window])

    def retire(self, uid: int) -> None:
        """A deleted confirmed track stays queryable (the last keep_deleted of them)."""
        self.retired = (self.retired + [uid])[-self.keep_deleted:]

    def inherit(self, uid: int, parent: int, t: float) -> None:
        """Track `uid`, split off `parent` at time t, shares the parent's rows before t."""
        self._inherits[uid] = (parent, t)

    def _block(self, uid: int, as_of: float | None = None) -> np.ndarray:
        sel = [rows[u == uid] for u, rows in self._blocks]
        own = np.concatenate(sel) if sel else np.zeros((0, DET.stop))
        if as_of is not None:
            own = self.versions.rows_as_of(uid, own, as_of)
        if uid in self._inherits:
            parent, t = self._inherits[uid]
            before = self._block(parent, as_of)
            own = np.concatenate([before[before[:, 0] < t], own])
        return own

    def rows(self, uid: int, as_of: float | None = None) -> dict[str, np.ndarray]:
        """Register of one track, time order: the detections of its main hypothesis
        (by the retro weights where in the window) with the own position; with
        ``as_of``, as the cycle of that time left it (RegisterVersions.rows_as_of)."""
        block = self._block(uid, as_of)
        block = block[np.isfinite(block[:, DET.start])]
        cols = np.column_stack([block[:, T], block[:, DET], block[:, OWN]])
        return {c: cols[:, i].copy() for i, c in enumerate(HISTORY_COLUMNS)}

    def smoothed(self, uid: int, as_of: float | None = None) -> dict[str, np.ndarray]:
        """Retrodicted bearings of one track at every cycle, time order (000
        retrodiction; rows older than the window keep their last smoothed value), as of
        a cycle time as by :meth:`rows`."""
        block = self._block(uid, as_of)
        cols = np.column_stack([block[:, T], block[:, SMOOTH]])
        return {c: cols[:, i].copy() for i, c in enumerate(SMOOTHED_COLUMNS)}

    def compact(self, live_uids: np.ndarray) -> None:
        """Drop register rows nobody can query (neither live nor retired tracks) once 256
        cycles are outside the window; rows of the window stay in their own blocks (they
        are still rewritten)."""
        n_old = len(self._blocks) - len(self.window)
        if n_old < 256:
            return
        keep_ids = np.concatenate([live_uids, np.asarray(self.retired, dtype=np.int64),
                                   np.array([p for p, _ in self._inherits.values()], dtype=np.int64)])
        u = np.concatenate([b[0] for b in self._blocks[:n_old]])
        r = np.concatenate([b[1] for b in self._blocks[:n_old]])
        k = np.isin(u, keep_ids)
        self._blocks = [(u[k], r[k])] + self._blocks[n_old:]


def _main_detections(rec: CycleRecord, c: np.ndarray) -> None:
    """Register detections of a record: for every track with weight in c (H,), the
    detection of its heaviest hypothesis (NaN where that hypothesis has none); a track
    without weight (no descendant: deleted since) keeps its rows."""
    main = heaviest(c, rec.track, rec.uid.size)
    has = main >= 0
    has[has] = c[main[has]] > 0
    rec.rows[has, DET] = rec.det[main[has]]
