"""Duplicate global tracks (complement of 001 module 61, stated deviation): two global
tracks that hold elementary tracks of disjoint sets of bases and whose positions agree
within the gate are one target seen twice, and are merged.

Why: module 62 starts a track from any pair of free elementary tracks of two bases; when
a target's elementary tracks are free in two disjoint pairs of bases at once (e.g. {b1,
b2} and {b3, b4}), or after a track lost some bases, two tracks follow one target, each
updated by half of its bases. Module 63 cannot repair it, since an elementary track
belongs to one global track. Such pairs make number switches (the two tracks take turns
as the one nearest the target) and a false track for as long as they last.

Test: d^2 = (p_i - p_j)' (P_i + P_j)^-1 (p_i - p_j) <= gamma on the 3-D positions (the
two estimates use disjoint data, so their errors are independent and P_i + P_j is the
covariance of the difference). Candidate pairs come from a KD-tree (scipy cKDTree) with
each track's own search radius sqrt(2 gamma lambda_max(P_i)), a superset of the pairs
that can pass the test, so the cost is near-linear in the number of tracks. Pairs are
merged closest first, each track at most once per cycle: the older track keeps its
number and takes the other's elementary tracks; the other is deleted.
Tracks that share a base are never merged (two targets, each seen by every base, may
come as close as they like). A track without contributors (coasting) pairs too: when
every base loses a target at once (near the receiver, where the azimuth rate common to
all bases is high), its new elementary tracks can start a new track before the
coasting one gates them. The track with contributors is then the kept one (its state
rests on data), and takes the coasting track's number by `number_kept`.

Second test, in the bases' measurement space (`explained`): the Cartesian test misses
the duplicates whose altitude is wrong with a small sigma_z. Module 62 can start a track
from a pair of two targets' elementary tracks at one azimuth and locates it at the
ellipsoids' fictitious intersection, often 10-20 km up; the first located scans shrink
every altitude band there, and once the other target's elementary track fails [48] and
leaves, the track keeps the first target's bases at that altitude while the target's
own track holds its other bases. The weak altitude geometry of one receiver lets such a
track go on passing [48] with its own elementary tracks. The test: every elementary
track of one track passes [48] against a live component of the other's mixture, and
not the reverse; the track that explains the other keeps its state (and number, but
for `number_kept`) and takes its elementary tracks. A track still holding both targets'
elementary tracks, each explained by another track, is deleted: 001 module 61 removes
"aberrant" global tracks without saying how they are found. A confirmed track located
this cycle (module 64's joint test of its elementary tracks passed, which a pair of two
targets' elementary tracks fails: the confirmation rule of common.radar.fusion.cycle)
is not dissolved.

Numbers (`number_kept`): when only the dropped track of a merged pair is confirmed, the
kept track (its state, elementary tracks and confirmation) takes the dropped track's
number and birth time, so that a target does not change number when the track just
started from its free elementary tracks is confirmed. The kept track stays tentative
until confirmed (moving the confirmation too made false tracks and NEES worse). A kept
track confirmed in this very cycle counts as not confirmed here: its number was never
published as confirmed, so the dropped track's published number goes on (a coasting
confirmed track merged, in the cycle that confirms it, with the track of its
aircraft's new elementary tracks).

Measured figures behind each rule, and the commands that give them:
docs/decisions/002-duplicate-track-merge.md.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from common.core.gating import quadratic_form
from common.core.track_table import TrackTable
from common.radar.fusion.assoc import ETrackSet, gated_component_pairs
from common.radar.geometry.bistatic import POS


def duplicate_pairs(pos: np.ndarray, cov: np.ndarray, has: np.ndarray, gamma: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j) (indices into the N tracks, i < j) of tracks with disjoint base sets,
    not both empty (has (N, B)), whose positions pos (N, 3), covariances cov (N, 3, 3)
    pass d^2 <= gamma (module doc), closest first, each track in at most one pair."""
    e = np.zeros(0, dtype=np.intp)
    if pos.shape[0] < 2:
        return e, e
    radius = np.sqrt(2.0 * gamma * np.linalg.eigvalsh(cov)[:, -1])
    tree = cKDTree(pos)
    lists = tree.query_ball_point(pos, radius)
    i = np.repeat(np.arange(pos.shape[0]), [len(v) for v in lists])
    j = np.fromiter((k for v in lists for k in v), dtype=np.intp, count=i.size)
    a, b = np.minimum(i, j), np.maximum(i, j)
    keep = a < b
    key = np.unique(a[keep] * pos.shape[0] + b[keep])
    a, b = key // pos.shape[0], key % pos.shape[0]
    ok = (has[a].any(axis=1) | has[b].any(axis=1)) & ~(has[a] & has[b]).any(axis=1)
    a, b = a[ok], b[ok]
    d = pos[a] - pos[b]
    d2 = quadratic_form(d, cov[a] + cov[b])
    ok = d2 <= gamma
    a, b, d2 = a[ok], b[ok], d2[ok]
    order = np.argsort(d2, kind="stable")
    used = np.zeros(pos.shape[0], dtype=bool)
    out_a, out_b = [], []
    for p in order:
        if not (used[a[p]] or used[b[p]]):
            used[a[p]] = used[b[p]] = True
            out_a.append(a[p])
            out_b.append(b[p])
    return np.array(out_a, dtype=np.intp), np.array(out_b, dtype=np.intp)


def explained(w: np.ndarray, xc: np.ndarray, Pc: np.ndarray, has: np.ndarray, row: np.ndarray,
              E: ETrackSet, tx: np.ndarray, rx: np.ndarray, az_gate: float, gamma: float,
              busy: np.ndarray, held: np.ndarray | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The second test (module doc) over N tracks (mixtures w, xc, Pc:
    common.radar.fusion.mixture; has (N, B); row (N, B) their elementary tracks this
    cycle, rows of E, -1 = none): (keep, drop, dissolve), indices into the N tracks.

    A track explains an elementary track of base b when it lacks b and the elementary
    track passes [48] against a live component of its mixture. Pairs (keep, drop):
    `keep` explains every elementary track of `drop`, their bases are disjoint and
    `drop` does not explain every one of `keep`'s; the most bases first, each track in
    one pair at most, none of `busy`. dissolve: the other tracks with >= 2 elementary
    tracks each explained by some track, none of which they explain entirely: the
    elementary tracks of several targets (a pair of two targets, module doc); they
    are deleted and module 63 gives their elementary tracks at the next cycle, but for
    the tracks of `held` (N,) (module doc: confirmed and located this cycle)."""
    N, B = has.shape
    owner = np.full(len(E), -1)
    t, b = np.nonzero(row >= 0)
    owner[row[t, b]] = t
    i, j, k = [], [], []
    for base in range(B):
        ti, m, _ = gated_component_pairs(w, xc, Pc, np.flatnonzero(~has[:, base] & has.any(axis=1)),
                                         row[row[:, base] >= 0, base], E, tx[base], rx[base],
                                         az_gate, gamma)  # [48]
        i.append(ti)
        j.append(owner[m])
        k.append(np.full(ti.size, base))
    ia, ja, ka = np.concatenate(i), np.concatenate(j), np.concatenate(k)
    n_meas = (row >= 0).sum(axis=1)
    key, count = np.unique(ia * N + ja, return_counts=True)
    i, j = key // N, key % N
    full = (count == n_meas[j]) & ~(has[i] & has[j]).any(axis=1)
    i, j = i[full], j[full]  # i explains all of j
    covered = np.zeros((N, B), dtype=bool)
    covered[ja, ka] = True
    explains_one = np.zeros(N, dtype=bool)
    explains_one[ja[np.isin(ja * N + ia, i * N + j)]] = True  # j explains all of a track i
    mutual = np.isin(j * N + i, i * N + j)
    i, j = i[~mutual], j[~mutual]
    used = np.zeros(N, dtype=bool)
    used[busy] = True
    keep, drop = [], []
    for p in np.argsort(-has[i].sum(axis=1), kind="stable"):  # the most bases first
        if not (used[i[p]] or used[j[p]]):
            used[i[p]] = used[j[p]] = True
            keep.append(i[p])
            drop.append(j[p])
    dissolve = (covered.sum(axis=1) == n_meas) & (n_meas >= 2) & ~explains_one & ~used
    if held is not None:
        dissolve &= ~held
    return (np.array(keep, dtype=np.intp), np.array(drop, dtype=np.intp),
            np.flatnonzero(dissolve))


def number_kept(keep_confirmed: np.ndarray, drop_confirmed: np.ndarray) -> np.ndarray:
    """Mask of the merged pairs (keep, drop) whose kept track goes under drop's number
    and birth time: drop confirmed and keep not (module doc)."""
    return drop_confirmed & ~keep_confirmed


def merge_tracks(tab: TrackTable, live: np.ndarray, r: np.ndarray, E: ETrackSet,
                 tx: np.ndarray, rx: np.ndarray, az_gate: float, gamma: float,
                 fresh: np.ndarray = np.zeros(0, dtype=np.intp)) -> tuple[np.ndarray, np.ndarray]:
    """Both tests on the live tracks (slots `live` of the global track table, r their rows
    of E): the kept track of each pair (the older, or the one with contributors: module
    doc) takes the other's elementary tracks and score and keeps its number, but for
    `number_kept` (the slots of `fresh`, confirmed this cycle, counted as not
    confirmed; the number keeps its `published` mark: common.radar.fusion.succession).
    Returns (slots to delete: the
    merged-away and the dissolved tracks, slots now under another number)."""
    a, b = duplicate_pairs(tab.x[live][:, POS], tab.P[live][:, POS][:, :, POS],
                           tab.has[live], gamma)
    with_a, with_b = tab.has[live[a]].any(axis=1), tab.has[live[b]].any(axis=1)
    first = np.where(with_a & with_b, tab.born[live[a]] <= tab.born[live[b]], with_a)
    k, d, gone = explained(tab.mu[live], tab.xm[live], tab.Pm[live], tab.has[live], r, E,
                           tx, rx, az_gate, gamma, np.r_[a, b],
                           tab.confirmed[live] & tab.located[live])
    keep, drop = live[np.r_[np.where(first, a, b), k]], live[np.r_[np.where(first, b, a), d]]
    tab.member[keep] = np.where(tab.has[drop], tab.member[drop], tab.member[keep])
    tab.has[keep] |= tab.has[drop]
    tab.score[keep] += tab.score[drop]
    mv = number_kept(tab.confirmed[keep] & ~np.isin(keep, fresh), tab.confirmed[drop])
    tab.copy_rows(keep[mv], drop[mv], ("id", "born", "published"))
    keep, drop = np.where(mv, drop, keep), np.where(mv, keep, drop)
    return np.union1d(drop, live[gone]), keep[mv]
