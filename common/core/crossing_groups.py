"""Groups of tracks crossing together, and whether two tracks have crossed, from the
separations of their points (seed 004's line model, eq. 1, on the difference of a pair).

004 models "a track and its closest track" and "supposes that only two tracks cross"
(the text before eq. 1, and eq. 2). Several contacts crossing together are a group:
`ambiguity_groups` links two tracks when one term q^j g(Z^k - Z^j) of eq. 13 alone makes
k ambiguous (common.core.crossing.eq13_test, or the sup-norm test's pairs), and a group is
a connected component of those links; the trackers treat a group as 004 treats the pair.

004 eq. 1 writes each point as X_n = A^f(n) t_n + B^f(n) + W_n with f unknown: which track
a point belongs to is the ambiguity of a crossing. The separation of the two points of a
scan, a_n = |X_a - X_b|, does not depend on f: it is a noisy sample of |d(t_n)|, with
d(t) = (A^a - A^b) t + (B^a - B^b) the pair's difference line. That line vanishes once,
at the crossing time t_c, so |d(t)| = |m| |t - t_c|: a V whose apex is the crossing.
`crossing_time` fits it by least squares (for each candidate t_c, |m| in closed form,
then the candidate of least residual); the pair has crossed at t when t_c <= t, and the
order of its tracks is then the reverse of their order before the ambiguity.
Deviation (not in 004, which leaves the exit of a crossing to the tracker): the fit uses
the separations only, not the points' positions (their common mode is the centroid of
common.sonar.bearing.pairs); a pair that approaches and recedes without crossing is
fitted by the same V (its residual is then larger: `crossing_time` returns it).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

CANDIDATES = 241  # crossing times tried, spread over the samples' span and as much around it


def crossing_time(t: ArrayLike, a: ArrayLike) -> tuple[float, float]:
    """(t_c, rms residual) of the V |m| |t - t_c| fitted to the separations a (n,) at
    times t (n,) by least squares; t_c is tried on a grid over [t_0 - L, t_last + L],
    L = t_last - t_0 (NaN, inf with fewer than 3 samples)."""
    t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
    if t.size < 3:
        return float("nan"), float("inf")
    span = max(float(t.max() - t.min()), 1e-9)
    tc = np.linspace(t.min() - span, t.max() + span, CANDIDATES)
    tau = np.abs(t[None, :] - tc[:, None])  # (C, n)
    m = np.sum(a * tau, axis=1) / np.maximum(np.sum(tau**2, axis=1), 1e-12)  # |m| per t_c
    res = np.sum((m[:, None] * tau - a) ** 2, axis=1)
    best = int(np.argmin(res))
    return float(tc[best]), float(np.sqrt(res[best] / t.size))


def ambiguity_groups(n: int, k: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Labels (n,) of the groups of n tracks linked by the pairs (k, j): the connected
    components; a track without a link is alone in its group."""
    graph = coo_matrix((np.ones(k.size), (k, j)), shape=(n, n))
    return connected_components(graph, directed=False)[1]
