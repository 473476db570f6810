"""Opening global tracks from the leftover elementary tracks of a network (no azimuth).

One round at time t, from the leftovers' [r_b, v_b] predicted to t:

1. seed cells: coarse-to-fine voting of the leftovers' ellipsoidal shells in the
   surveillance volume ([V] of `voting`), and at the cells no larger than doppler_cell
   the velocity vote of their candidates' range rates ([D] of `velocity_vote`, 001 [2]),
   the best cells first;
2. members: per cell and base the candidate agreeing with the cell's velocity ([D]);
   with range votes alone (doppler_cell = 0) the leftover whose r_b is closest to the
   cell centre's r_b within k sigma_r plus the cell's range margin. Cells with fewer than
   `required` bases are dropped (ghosts: an exactly determined triple is always
   consistent, over-determination is what tells them apart), identical member sets kept
   once;
3. `localise` ([GN], [LS], [FIM]) on all members from the cell centre and from its
   (x, y) at each altitude of seed_z (least cost wins: the altitude valley of far
   bases has local minima), a re-gate of
   every base on [r_b, v_b] with S = J P J' + R, `localise` again; a candidate is
   accepted when it still has `required` bases over >= 2 receivers, chi2 <= its
   chi-square(2n - 6) quantile AND chi2_v <= the chi-square(n - 3) quantile
   (range-rate consistency);
4. the accepted candidates claim their members exclusively, most bases first, then
   least chi2 per degree of freedom.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.gating import chi2_gate, quadratic_form, window_pairs
from common.radar.geometry.bistatic import bistatic_range, project, project_jacobian
from common.radar.network.localise import Fix, localise
from common.radar.network.params import NetworkParams
from common.radar.network.velocity_vote import Shells
from common.radar.network.voting import vote_cells


@dataclass(frozen=True)
class Sites:
    """Per base: tx, rx (B, 3), receiver (B,) index of its receiver."""

    tx: np.ndarray
    rx: np.ndarray
    receiver: np.ndarray


@dataclass(frozen=True)
class Leftovers:
    """Unassigned confirmed elementary tracks at one time: base (L,), eid (L,),
    z (L, 2) [r_b, v_b], R (L, 2, 2)."""

    base: np.ndarray
    eid: np.ndarray
    z: np.ndarray
    R: np.ndarray


@dataclass(frozen=True)
class Opened:
    """Accepted candidates: fix (C rows) and members (C, B) leftover index or -1."""

    fix: Fix
    members: np.ndarray


def _closest(pred: np.ndarray, half: np.ndarray, left: Leftovers, rows: np.ndarray
             ) -> np.ndarray:
    """Per candidate (C,), the leftover of `rows` whose r_b is nearest pred within
    +- half (in units of half), or -1."""
    out = np.full(pred.size, -1)
    c, j = window_pairs(pred - half, pred + half, left.z[rows, 0])
    if c.size:
        d = np.abs(left.z[rows[j], 0] - pred[c]) / half[c]
        order = np.lexsort((d, c))
        c, j = c[order], j[order]
        first = np.r_[True, c[1:] != c[:-1]]
        out[c[first]] = rows[j[first]]
    return out


def _nearest_members(pts: np.ndarray, left: Leftovers, sites: Sites, p: NetworkParams
                     ) -> np.ndarray:
    """Step 2 by range alone: per cell and base the leftover of nearest r_b (C, B)."""
    margin = 2 * np.sqrt(3.0) / 2 * p.cell_fine
    k = np.sqrt(chi2_gate(p.gate_prob, 1))
    members = np.full((pts.shape[0], sites.tx.shape[0]), -1)
    for b in range(sites.tx.shape[0]):
        rows = np.flatnonzero(left.base == b)
        if rows.size:
            half = np.full(pts.shape[0], k * np.sqrt(left.R[rows, 0, 0].max()) + margin)
            members[:, b] = _closest(bistatic_range(pts, sites.tx[b], sites.rx[b]), half,
                                     left, rows)
    return members


def localise_members(left: Leftovers, sites: Sites, members: np.ndarray, seeds: np.ndarray,
         p: NetworkParams) -> Fix:
    """`localise` of candidates with members (C, B) (leftover index or -1) from seeds
    (C, S, 3)."""
    valid = members >= 0
    m = np.where(valid, members, 0)
    B = members.shape[1]
    n = members.shape[0]
    return localise(left.z[m], left.R[m], np.broadcast_to(sites.tx, (n, B, 3)),
                    np.broadcast_to(sites.rx, (n, B, 3)), valid, seeds,
                    (p.z_min, p.z_max), p.max_sigma)


def _regate(fix: Fix, left: Leftovers, sites: Sites, p: NetworkParams) -> np.ndarray:
    """Step 4's re-gate: per candidate and base the leftover of least chi-square(2)
    on [r_b, v_b] with S = J P J' + R, or -1. Returns (C, B)."""
    n, B = fix.x.shape[0], sites.tx.shape[0]
    out = np.full((n, B), -1)
    gam = chi2_gate(p.gate_prob, 2)
    for b in range(B):
        rows = np.flatnonzero(left.base == b)
        if rows.size == 0 or n == 0:
            continue
        h = project(fix.x, sites.tx[b], sites.rx[b])[:, :2]
        J = project_jacobian(fix.x, sites.tx[b], sites.rx[b])[:, :2]
        A = J @ fix.P @ np.swapaxes(J, 1, 2)
        half = np.sqrt(gam * (A[:, 0, 0] + left.R[rows, 0, 0].max()))
        c, j = window_pairs(h[:, 0] - half, h[:, 0] + half, left.z[rows, 0])
        if c.size == 0:
            continue
        y = left.z[rows[j]] - h[c]
        S = A[c] + left.R[rows[j]]
        d2 = quadratic_form(y, S)
        keep = d2 <= gam
        c, j, d2 = c[keep], j[keep], d2[keep]
        order = np.lexsort((d2, c))
        c, j = c[order], j[order]
        first = np.r_[True, c[1:] != c[:-1]] if c.size else np.zeros(0, dtype=bool)
        out[c[first], b] = rows[j[first]]
    return out


def accepted(fix: Fix, members: np.ndarray, sites: Sites, required: int, p: NetworkParams
              ) -> np.ndarray:
    """Step 4's tests: (C,) mask."""
    n = (members >= 0).sum(axis=1)
    rec = np.array([np.unique(sites.receiver[m >= 0]).size for m in members], dtype=int)
    dof = np.maximum(2 * n - 6, 1)
    lim = np.array([chi2_gate(p.init_prob, int(d)) for d in dof])
    lim_v = np.array([chi2_gate(p.init_prob, int(max(k - 3, 1))) for k in n])
    return fix.ok & (n >= required) & (rec >= 2) & (fix.chi2 <= lim) & (fix.chi2_v <= lim_v)


def initiate(left: Leftovers, sites: Sites, required: int, p: NetworkParams, turn: int = 0,
             extent: tuple[int, float, float] | None = None) -> tuple[Opened, int]:
    """Steps 1-4 in round `turn`: the accepted candidates, and the number of seed cells
    left for a later round (beyond max_cells, or doppler_cells / 8, at the last level);
    `extent`: the slab of the volume voted (`vote_cells`)."""
    sigma = np.sqrt(left.R[:, :2, :2].diagonal(axis1=1, axis2=2))
    doppler = Shells(left.base, left.z[:, 0], left.z[:, 1], sigma[:, 0], sigma[:, 1])
    pts, members, cut = vote_cells(left.base, left.z[:, 0], sigma[:, 0], sites.tx, sites.rx,
                                   sites.receiver, required, p, turn,
                                   doppler if p.doppler_cell > 0 else None, extent)
    if members is None:
        members = _nearest_members(pts, left, sites, p)
    keep = (members >= 0).sum(axis=1) >= required
    members, first = np.unique(members[keep], axis=0, return_index=True)
    pts = pts[keep][first]
    seeds = np.repeat(pts[:, None, :], 1 + len(p.seed_z), axis=1)
    seeds[:, 1:, 2] = p.seed_z
    fix = localise_members(left, sites, members, seeds, p)
    members = _regate(fix, left, sites, p)
    fix = localise_members(left, sites, members, fix.x[:, None, [0, 2, 4]], p)
    ok = accepted(fix, members, sites, required, p)
    n = (members >= 0).sum(axis=1)
    per_dof = fix.chi2 / np.maximum(2 * n - 6, 1)
    taken: set[int] = set()
    chosen = []
    for c in np.lexsort((per_dof, -n)):
        m = members[c][members[c] >= 0]
        if ok[c] and not taken.intersection(m.tolist()):
            taken.update(m.tolist())
            chosen.append(c)
    sel = np.array(chosen, dtype=int)
    out = Fix(*(getattr(fix, f)[sel] for f in ("x", "P", "chi2", "chi2_r", "chi2_v", "n", "ok",
                                               "degenerate")))
    return Opened(out, members[sel]), cut
