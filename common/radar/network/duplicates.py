"""Two global tracks of one aircraft: found and merged (docs/networks.md, step 8).

Range-only bases near the ground fix an aircraft's altitude weakly when it flies outside
the network's hull: two solutions, one at its altitude and one kilometres above, can each
explain a subset of its bases, and initiation may open both, each holding the elementary
tracks of its own subset. One aircraft gives at most one elementary track per base, so
two tracks of one aircraft hold nearly disjoint sets of bases (a wrong solution may also
have taken one elementary track of another aircraft); two aircraft seen by the same
bases hold two elementary tracks of each. The test, for two confirmed tracks within
`merge_distance` of each other in the plane sharing at most SHARED of the bases of the
smaller (and at least one base in any case), the older track's member on a shared base: the
localisation (common.radar.network.localise [GN], [LS], [FIM]) of the union of their
members, from the two tracks' positions, passes initiation's acceptance tests (chi-square
of 2n - 6 and of n - 3 degrees of freedom at init_prob). Then the older track takes the
fix and every member it has no base of; the younger is deleted.
"""

from __future__ import annotations

import numpy as np

from common.core.track_table import Status
from common.radar.geometry.bistatic import POS
from common.radar.network.initiation import Leftovers, Sites, accepted, localise_members
from common.radar.network.localise import Fix
from common.radar.network.params import NetworkParams

SHARED = 0.2  # fraction of the smaller track's bases two tracks of one aircraft may share


def candidate_pairs(x: np.ndarray, status: np.ndarray, members: list[dict[int, int]],
                    distance: float) -> np.ndarray:
    """Rows (K, 2), first the older (lower row), of confirmed tracks within `distance`
    in the plane that share few bases (module doc)."""
    conf = np.flatnonzero(status == Status.CONFIRMED)
    if conf.size < 2:
        return np.zeros((0, 2), dtype=int)
    xy = x[conf][:, POS[:2]]
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    i, j = np.nonzero(np.triu(d <= distance, k=1))
    keep = [k for k in range(i.size) if _few_shared(members[conf[i[k]]], members[conf[j[k]]])]
    return np.column_stack([conf[i[keep]], conf[j[keep]]]).astype(int).reshape(-1, 2)


def _few_shared(a: dict[int, int], b: dict[int, int]) -> bool:
    return len(a.keys() & b.keys()) <= max(1.0, SHARED * min(len(a), len(b)))


def merged(pairs: np.ndarray, x: np.ndarray, members: list[dict[int, int]], reports: Leftovers,
           sites: Sites, p: NetworkParams) -> tuple[Fix, np.ndarray]:
    """Per pair (K, 2) of rows of tracks x (N, 6) with `members`: the fix of the union
    of their members, whose [r_b, v_b] at the fix's time are `reports`, and (K,) whether
    it passes the acceptance tests."""
    B = sites.tx.shape[0]
    index = {(int(b), int(e)): k for k, (b, e) in enumerate(zip(reports.base, reports.eid))}
    rows = np.full((pairs.shape[0], B), -1)
    for k, (a, c) in enumerate(pairs.tolist()):
        for b, e in (*members[c].items(), *members[a].items()):
            rows[k, b] = index.get((b, e), -1)
    seeds = np.stack([x[pairs[:, 0]][:, POS], x[pairs[:, 1]][:, POS]], axis=1)
    fix = localise_members(reports, sites, rows, seeds, p)
    return fix, accepted(fix, rows, sites, 3, p)
