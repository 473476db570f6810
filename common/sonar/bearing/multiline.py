"""Multi-line bearing tracks of seed 000 claims 12-13 (narrowband LOFAR / DEMON).

Each confirmed single-frequency-line track carries a multi-line label (a stable number).
Once per cycle, `MultiLineGrouper.step`:
  1. claim 13: computes each multi-line track's average bearing (circular mean) and
     bearing rate over its lines; a line whose bearing or rate departs from that
     average by more than the bounds leaves the group and is treated as new.
     Deviation: at most the worst line of a group leaves per cycle, so that when a
     two-line group separates the older number stays with one of its lines (with two
     lines both deviate equally from the average).
  2. claim 12: a new line joins the existing multi-line track whose average agrees
     within the bounds (the closest one, normalised by the bounds);
  3. the remaining new lines that agree with each other (connected components of the
     pairwise agreement) form new multi-line tracks; a line agreeing with none is a
     multi-line track with one line (claim 13, last sentence).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from common.core.angles import wrap_2pi, wrap_pi

NEW = -1


def group_means(labels: np.ndarray, brg: np.ndarray, rate: np.ndarray) -> tuple[np.ndarray, ...]:
    """(group numbers, circular mean bearing, mean rate, inverse index of each line)."""
    groups, inv = np.unique(labels, return_inverse=True)
    n = np.bincount(inv).astype(float)
    mean_brg = wrap_2pi(np.arctan2(np.bincount(inv, np.sin(brg)), np.bincount(inv, np.cos(brg))))
    return groups, np.asarray(mean_brg), np.bincount(inv, rate) / n, inv


def _distance(db: np.ndarray, dr: np.ndarray, brg_tol: float, rate_tol: float) -> np.ndarray:
    """Sup-norm of (bearing, rate) differences normalised by the bounds (<= 1: agree)."""
    return np.maximum(np.abs(wrap_pi(db)) / brg_tol, np.abs(dr) / rate_tol)


class MultiLineGrouper:
    """Stable multi-line labels over the confirmed line tracks (claims 12-13)."""

    def __init__(self, brg_tol: float, rate_tol: float) -> None:
        self.brg_tol = brg_tol
        self.rate_tol = rate_tol

    def step(self, labels: np.ndarray, brg: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """New labels (N,) for confirmed lines with current labels (NEW for unlabelled),
        bearings and bearing rates (N,)."""
        labels = np.asarray(labels, dtype=np.int64).copy()
        brg, rate = np.asarray(brg, dtype=float), np.asarray(rate, dtype=float)
        old = labels != NEW
        if old.any():  # claim 13: split off the worst departing line of each group
            groups, mb, mr, inv = group_means(labels[old], brg[old], rate[old])
            dev = _distance(brg[old] - mb[inv], rate[old] - mr[inv], self.brg_tol, self.rate_tol)
            order = np.lexsort((-dev, inv))
            first = np.zeros(order.size, dtype=bool)
            first[np.unique(inv[order], return_index=True)[1]] = True
            worst = order[first]
            leave = np.flatnonzero(old)[worst[dev[worst] > 1.0]]
            labels[leave] = NEW
        new = np.flatnonzero(labels == NEW)
        if new.size == 0:
            return labels
        kept = labels != NEW
        if kept.any():  # claim 12: join the closest agreeing multi-line track
            groups, mb, mr, _ = group_means(labels[kept], brg[kept], rate[kept])
            dist = _distance(
                brg[new, None] - mb[None, :], rate[new, None] - mr[None, :],
                self.brg_tol, self.rate_tol,
            )
            best = np.argmin(dist, axis=1)
            ok = dist[np.arange(new.size), best] <= 1.0
            labels[new[ok]] = groups[best[ok]]
            new = new[~ok]
        if new.size:  # claim 12/13: combine the remaining lines among themselves
            agree = _distance(
                brg[new, None] - brg[None, new], rate[new, None] - rate[None, new],
                self.brg_tol, self.rate_tol,
            ) <= 1.0
            i, j = np.nonzero(agree)
            graph = coo_matrix((np.ones(i.size), (i, j)), shape=(new.size, new.size))
            n_comp, comp = connected_components(graph, directed=False)
            labels[new] = self._free_numbers(labels, n_comp)[comp]
        return labels

    @staticmethod
    def _free_numbers(labels: np.ndarray, k: int) -> np.ndarray:
        """The k smallest positive numbers not used by a current label."""
        used = labels[labels != NEW]
        return np.setdiff1d(np.arange(1, used.size + k + 1), used)[:k]


@dataclass(frozen=True)
class MultiLineTrack:
    """A multi-line track (claims 12-13): its number, line track ids, mean bearing/rate."""

    id: int
    lines: np.ndarray
    brg: float
    brg_rate: float


def multiline_tracks(grouper: MultiLineGrouper, ids: np.ndarray, labels: np.ndarray,
                     brg: np.ndarray, rate: np.ndarray) -> tuple[np.ndarray, list[MultiLineTrack]]:
    """One cycle of claims 12-13 over the confirmed line tracks (ids, previous labels,
    bearings, bearing rates): their new labels and the multi-line tracks."""
    labels = grouper.step(labels, brg, rate)
    groups, mb, mr, inv = group_means(labels, brg, rate)
    return labels, [MultiLineTrack(int(g), ids[inv == i], float(mb[i]), float(mr[i]))
                    for i, g in enumerate(groups)]
