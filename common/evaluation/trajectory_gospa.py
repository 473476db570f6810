"""Truth-to-track assignment of the trajectory GOSPA metric, jointly over time.

Trajectory GOSPA (Garcia-Fernandez, Rahmathullah, Svensson, "A metric on the space of
finite sets of trajectories for evaluation of multi-target tracking algorithms", IEEE
TSP 68, 2020, section IV, the linear-programming relaxation) chooses one assignment per
step, W^1 .. W^T, minimising
    sum_t [ sum_(i,j) W^t_ij d(x_i, y_j)^p + c^p/2 (n_t + m_t - 2 sum_(i,j) W^t_ij) ]
  + gamma^p/2 sum_t sum_i sum_j |W^t_ij - W^(t+1)_ij|
with sum_j W^t_ij <= 1, sum_i W^t_ij <= 1, 0 <= W <= 1: localisation, missed and false
as in the per-step GOSPA of common.evaluation.metrics, plus gamma^p for a truth changing
tracks between two steps (gamma^p/2 between a track and none). The per-step optimum of
`metrics.gospa` ignores the last term, so a truth that two tracks pass at comparable
distances changes track each time the nearer one changes; here it keeps its track
unless the exchange pays for its switches.
Restrictions of the paper's LP, stated: a pair is assignable at a step only when both
are present and d < c (the per-step GOSPA's pairs), and the switching term is taken for
the truths present at both steps (the definition of common.evaluation.metrics); in the
paper a pair may be held at cost c^p while apart or absent. The LP is solved by HiGHS
(scipy.optimize.linprog); an assignment is read as W > 1/2 (each row and column sums
to at most 1, so at most one such pair per truth and per track).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import sparse
from scipy.optimize import linprog
from scipy.spatial import cKDTree

Frame = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # truth ids, pos, track ids, pos


def close_pairs(truth_pos: np.ndarray, track_pos: np.ndarray, c: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and distances of the (truth, track) pairs closer than c."""
    if np.size(truth_pos) == 0 or np.size(track_pos) == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty, np.zeros(0)
    truth_pos, track_pos = np.atleast_2d(truth_pos), np.atleast_2d(track_pos)
    m = cKDTree(truth_pos).sparse_distance_matrix(cKDTree(track_pos), c, output_type="ndarray")
    keep = m["v"] < c
    return m["i"][keep].astype(np.intp), m["j"][keep].astype(np.intp), m["v"][keep]


def joint_assignment(frames: Sequence[Frame], c: float, gamma: float, p: float = 2.0
                     ) -> list[dict[int, int | None]]:
    """Per step, truth id -> track id (None: missed) of the trajectory GOSPA assignment
    minimised over all steps at once (the LP of the module docstring)."""
    keys: list[tuple[int, int, int]] = []  # (step, truth id, track id) of each W variable
    cost: list[float] = []
    for k, (tid, tpos, kid, kpos) in enumerate(frames):
        r, col, d = close_pairs(np.asarray(tpos, dtype=float), np.asarray(kpos, dtype=float), c)
        keys += zip([k] * r.size, np.asarray(tid)[r].tolist(), np.asarray(kid)[col].tolist())
        cost += (d**p - c**p).tolist()  # an assigned pair replaces a miss and a false track
    index = {key: n for n, key in enumerate(keys)}
    half = 0.5 * gamma**p
    w_cost = np.array(cost)
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    bound: list[float] = []
    groups: dict[tuple[str, int, int], list[int]] = {}  # a truth's or a track's W at one step
    for n, (k, i, j) in enumerate(keys):
        groups.setdefault(("truth", k, i), []).append(n)
        groups.setdefault(("track", k, j), []).append(n)
    for members in groups.values():  # sum of W <= 1 over each group
        if len(members) > 1:
            rows += [len(bound)] * len(members)
            cols += members
            vals += [1.0] * len(members)
            bound.append(1.0)
    present = [set(np.asarray(f[0]).tolist()) for f in frames]
    n_e = 0
    for n, (k, i, j) in enumerate(keys):  # W^k_ij against W^(k+1)_ij, truth i at both steps
        if k > 0 and i in present[k - 1] and (k - 1, i, j) not in index:
            w_cost[n] += half  # |W^k - 0|: the pair is not assignable at k - 1
        if k + 1 == len(frames) or i not in present[k + 1]:
            continue
        nxt = index.get((k + 1, i, j))
        if nxt is None:
            w_cost[n] += half
            continue
        e = len(keys) + n_e  # |W^k - W^(k+1)| <= e, both signs
        r = len(bound)
        rows += [r, r, r, r + 1, r + 1, r + 1]
        cols += [n, nxt, e, n, nxt, e]
        vals += [1.0, -1.0, -1.0, -1.0, 1.0, -1.0]
        bound += [0.0, 0.0]
        n_e += 1
    result: list[dict[int, int | None]] = [{int(i): None for i in np.asarray(f[0]).tolist()} for f in frames]
    if not keys:
        return result
    A = sparse.csr_matrix((vals, (rows, cols)), shape=(len(bound), len(keys) + n_e)) if bound else None
    sol = linprog(np.concatenate([w_cost, np.full(n_e, half)]), A_ub=A,
                  b_ub=np.array(bound) if bound else None, bounds=(0.0, 1.0), method="highs")
    if sol.status != 0:
        raise RuntimeError(f"trajectory GOSPA LP: {sol.message}")
    for n in np.flatnonzero(sol.x[:len(keys)] > 0.5):
        k, i, j = keys[n]
        result[k][i] = j
    return result
