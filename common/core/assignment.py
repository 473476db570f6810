"""Track-to-plot assignment on gated cost matrices (np.inf marks a pair outside the gate).

nearest_neighbour: seed 001 [12] with closest-pair-first conflict resolution.
gnn: global nearest neighbour (seed 000, cost-matrix GNN) via linear_sum_assignment.
Both return (rows, cols) int arrays sorted by row; only gated (finite) pairs are returned.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

_EMPTY = np.zeros(0, dtype=np.intp)


def _first_occurrence(a: np.ndarray) -> np.ndarray:
    """Mask of the first occurrence of each value of a."""
    mask = np.zeros(a.size, dtype=bool)
    mask[np.unique(a, return_index=True)[1]] = True
    return mask


def _gated_pairs(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gated pairs (t, j, c) sorted by cost, ties broken by track then plot index."""
    t, j = np.nonzero(np.isfinite(cost))
    c = cost[t, j]
    order = np.lexsort((j, t, c))
    return t[order], j[order], c[order]


def nearest_neighbour(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest-neighbour association (001 [12]) -> (rows, cols, ambiguous).

    Each track t takes its closest gated plot j^_t = argmin_j {d[t, j] <= gamma} (001 [12]).
    The seed does not say what happens when one plot is the closest of several tracks;
    we resolve it closest pair first: gated pairs are accepted in increasing cost while
    both the track and the plot are free, so a track that loses its best plot falls back
    to its closest still-free gated plot (without conflicts this is exactly [12]).
    Vectorised as rounds of "locally dominant" pairs (first in cost order for both its
    track and its plot), which yields the same matching as the sequential greedy pass.

    ambiguous[t] (N,) is True when the decision [12] for track t was not clear-cut: more
    than one plot inside t's gate, or t's closest plot j^_t is also the closest plot of
    another track. It feeds the score penalty for association difficulties of 001
    (step 23, elementary-track score) and the crossing ambiguity of seed 004.
    """
    cost = np.asarray(cost, dtype=float)
    N, M = cost.shape
    ambiguous = np.zeros(N, dtype=bool)
    t, j, _ = _gated_pairs(cost)
    if t.size == 0:
        return _EMPTY, _EMPTY, ambiguous

    first = _first_occurrence(t)
    best = np.full(N, -1, dtype=np.intp)
    best[t[first]] = j[first]  # 001 [12]
    has = best >= 0
    shared = np.bincount(best[has], minlength=M)[best[has]] > 1
    ambiguous[has] = (np.bincount(t, minlength=N)[has] > 1) | shared

    row_taken = np.zeros(N, dtype=bool)
    col_taken = np.zeros(M, dtype=bool)
    assigned = np.full(N, -1, dtype=np.intp)
    live = np.ones(t.size, dtype=bool)
    while live.any():
        lt, lj = t[live], j[live]
        win = _first_occurrence(lt) & _first_occurrence(lj)
        assigned[lt[win]] = lj[win]
        row_taken[lt[win]] = True
        col_taken[lj[win]] = True
        live &= ~(row_taken[t] | col_taken[j])
    rows = np.flatnonzero(row_taken)
    return rows, assigned[rows], ambiguous


def gnn(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Global nearest neighbour: among matchings that use only gated (finite) pairs, the
    one with the most pairs, and among those the least total cost.

    The gate bipartite graph is split into connected components; one-edge components are
    assigned directly, the others are solved independently with linear_sum_assignment,
    non-gated entries set to a finite cost B > hi + K (hi - lo) (lo, hi: gated cost range,
    K: component size), large enough that dropping a gated pair never pays off; pairs
    landing on B are discarded, so out-of-gate pairs are never returned.
    """
    cost = np.asarray(cost, dtype=float)
    N, M = cost.shape
    t, j = np.nonzero(np.isfinite(cost))
    if t.size == 0:
        return _EMPTY, _EMPTY
    graph = coo_matrix((np.ones(t.size), (t, N + j)), shape=(N + M, N + M))
    _, labels = connected_components(graph, directed=False)
    edge_lab = labels[t]
    single = np.bincount(edge_lab)[edge_lab] == 1
    rows = [t[single]]
    cols = [j[single]]

    multi = np.unique(edge_lab[~single])
    row_lab, col_lab = labels[:N], labels[N:]
    row_order = np.argsort(row_lab, kind="stable")
    col_order = np.argsort(col_lab, kind="stable")
    r_lo = np.searchsorted(row_lab[row_order], multi, "left")
    r_hi = np.searchsorted(row_lab[row_order], multi, "right")
    c_lo = np.searchsorted(col_lab[col_order], multi, "left")
    c_hi = np.searchsorted(col_lab[col_order], multi, "right")
    for a, b, c, d in zip(r_lo, r_hi, c_lo, c_hi):
        r = row_order[a:b]
        c_idx = col_order[c:d]
        sub = cost[np.ix_(r, c_idx)]
        fin = np.isfinite(sub)
        lo, hi = sub[fin].min(), sub[fin].max()
        big = abs(hi) + min(sub.shape) * (hi - lo) + 1.0
        ri, ci = linear_sum_assignment(np.where(fin, sub, big))
        keep = fin[ri, ci]
        rows.append(r[ri[keep]])
        cols.append(c_idx[ci[keep]])
    rows_a = np.concatenate(rows)
    cols_a = np.concatenate(cols)
    order = np.argsort(rows_a)
    return rows_a[order], cols_a[order]
