"""Duplicate global tracks (complement of 001 module 61, stated deviation): two global
tracks that hold elementary tracks of disjoint sets of bases and whose positions agree
within the gate are one target seen twice, and are merged.

Why: module 62 starts a track from any pair of free elementary tracks of two bases; when
a target's elementary tracks are free in two disjoint pairs of bases at once (e.g. {b1,
b2} and {b3, b4}), or after a track lost some bases, two tracks follow one target, each
updated by half of its bases. Module 63 cannot repair it, since an elementary track
belongs to one global track. Measured on dense300.toml (300 targets, 4 bases, 120 s):
such pairs made 3 of the 6 number switches (the two tracks took turns as the one
nearest the target) and a false track for as long as they lasted.

Test: d^2 = (p_i - p_j)' (P_i + P_j)^-1 (p_i - p_j) <= gamma on the 3-D positions (the
two estimates use disjoint data, so their errors are independent and P_i + P_j is the
covariance of the difference). Candidate pairs come from a KD-tree (scipy cKDTree) with
each track's own search radius sqrt(2 gamma lambda_max(P_i)), a superset of the pairs
that can pass the test, so the cost is near-linear in the number of tracks. Pairs are
merged closest first, each track at most once per cycle: the older track keeps its
number and takes the other's elementary tracks; the other is deleted.
Tracks that share a base are never merged (two targets, each seen by every base, may
come as close as they like).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def duplicate_pairs(pos: np.ndarray, cov: np.ndarray, has: np.ndarray, gamma: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j) (indices into the N tracks, i < j) of tracks with disjoint, non-empty
    base sets (has (N, B)) whose positions pos (N, 3), covariances cov (N, 3, 3) pass
    d^2 <= gamma (module doc), closest first, each track in at most one pair."""
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
    ok = has[a].any(axis=1) & has[b].any(axis=1) & ~(has[a] & has[b]).any(axis=1)
    a, b = a[ok], b[ok]
    d = pos[a] - pos[b]
    d2 = np.einsum("pi,pi->p", d, np.linalg.solve(cov[a] + cov[b], d[..., None])[..., 0])
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
