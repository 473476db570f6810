"""Opening global tracks from the leftover elementary tracks of a network (no azimuth).

One round at time t, from the leftovers' [r_b, v_b] predicted to t, for an anchor triple
of bases (a, b, c) spread over >= 2 receivers:

1. pair gate (cheap, necessary): a point of the ellipsoid r_b of a base lies at a
   distance in [(r_b - L)/2, (r_b + L)/2] from both its sites (L the baseline), so two
   tracks of bases a, b can meet only if these shells, widened by pair_sigmas sigma_r,
   reach each other across every distance between their sites;
2. the triples whose three pairs pass are solved by Gauss-Newton on their three ranges
   ([GN] of `localise`) from the seeds of the volume; every distinct converged solution
   inside the z bounds is a candidate point (three ellipsoids may meet twice);
3. extension: each other base's leftover closest in r_b within the gate of the
   triple's covariance joins the candidate; candidates with fewer than `required`
   bases are dropped (ghosts: an exactly determined triple is always consistent,
   over-determination is what tells them apart);
4. `localise` ([GN], [LS], [FIM]) on all members, a re-gate of every base on [r_b, v_b]
   with S = J P J' + R, `localise` again; a candidate is accepted when it still has
   `required` bases over >= 2 receivers, chi2 <= its chi-square(2n - 6) quantile AND
   chi2_v <= the chi-square(n - 3) quantile (range-rate consistency);
5. the accepted candidates claim their members exclusively, most bases first, then
   least chi2 per degree of freedom.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.gating import chi2_gate, quadratic_form, window_pairs
from common.radar.geometry.bistatic import bistatic_range, norm3, project, project_jacobian
from common.radar.network.localise import Fix, gauss_newton, localise
from common.radar.network.params import NetworkParams


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


def pair_gate(za: np.ndarray, sa: np.ndarray, zb: np.ndarray, sb: np.ndarray,
              sites: Sites, a: int, b: int, k: float) -> np.ndarray:
    """Step 1 for ranges za (n_a,), zb (n_b,) with sigmas sa, sb: (n_a, n_b) mask."""
    la = norm3(sites.tx[a] - sites.rx[a])
    lb = norm3(sites.tx[b] - sites.rx[b])
    lo_a, hi_a = (za - la) / 2 - k * sa, (za + la) / 2 + k * sa
    lo_b, hi_b = (zb - lb) / 2 - k * sb, (zb + lb) / 2 + k * sb
    d = [norm3(u - w) for u in (sites.tx[a], sites.rx[a]) for w in (sites.tx[b], sites.rx[b])]
    d_min, d_max = min(d), max(d)
    return ((lo_a[:, None] - hi_b[None] <= d_min) & (lo_b[None] - hi_a[:, None] <= d_min)
            & (d_max <= hi_a[:, None] + hi_b[None]))


def _seeds(sites: Sites, anchors: tuple[int, int, int], p: NetworkParams) -> np.ndarray:
    """Seeds: the anchor receivers' centroid and four points seed_xy around it, at
    every altitude of seed_z."""
    c = sites.rx[list(anchors), :2].mean(axis=0)
    xy = c + np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]]) * p.seed_xy
    return np.array([[x, y, z] for z in p.seed_z for x, y in xy])


def triple_points(left: Leftovers, sites: Sites, anchors: tuple[int, int, int],
                  p: NetworkParams) -> tuple[np.ndarray, np.ndarray, int]:
    """Steps 1-2: candidate points (C, 3) with their anchor leftovers (C, 3), and the
    number of gated triples left for a later round (max_triples)."""
    rows = [np.flatnonzero(left.base == b) for b in anchors]
    r = [left.z[i, 0] for i in rows]
    s = [np.sqrt(left.R[i, 0, 0]) for i in rows]
    g = {(u, w): pair_gate(r[u], s[u], r[w], s[w], sites, anchors[u], anchors[w], p.pair_sigmas)
         for u, w in ((0, 1), (0, 2), (1, 2))}
    i, j, k = np.nonzero(g[0, 1][:, :, None] & g[0, 2][:, None, :] & g[1, 2][None, :, :])
    waiting = max(0, i.size - p.max_triples)
    trip = np.column_stack([rows[0][i], rows[1][j], rows[2][k]])[:p.max_triples]
    seeds = _seeds(sites, anchors, p)
    n_s = seeds.shape[0]
    base = np.array(anchors)
    rep = np.repeat(trip, n_s, axis=0)
    pos, cost, conv = gauss_newton(
        np.tile(seeds, (trip.shape[0], 1)), left.z[rep, 0], 1.0 / left.R[rep, 0, 0],
        np.broadcast_to(sites.tx[base], (rep.shape[0], 3, 3)),
        np.broadcast_to(sites.rx[base], (rep.shape[0], 3, 3)), iters=25)
    good = conv & (cost <= chi2_gate(p.init_prob, 1)) & (pos[:, 2] >= p.z_min) & (pos[:, 2] <= p.z_max)
    owner = np.repeat(np.arange(trip.shape[0]), n_s)[good]
    cell = np.round(pos[good] / 500.0).astype(np.int64)
    _, first = np.unique(np.column_stack([owner, cell]), axis=0, return_index=True)
    return pos[good][first], trip[owner[first]], waiting


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


def _fix(left: Leftovers, sites: Sites, members: np.ndarray, seeds: np.ndarray,
         p: NetworkParams) -> Fix:
    """`localise` of candidates with members (C, B) (leftover index or -1)."""
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


def _accepted(fix: Fix, members: np.ndarray, sites: Sites, required: int, p: NetworkParams
              ) -> np.ndarray:
    """Step 4's tests: (C,) mask."""
    n = (members >= 0).sum(axis=1)
    rec = np.array([np.unique(sites.receiver[m >= 0]).size for m in members], dtype=int)
    dof = np.maximum(2 * n - 6, 1)
    lim = np.array([chi2_gate(p.init_prob, int(d)) for d in dof])
    lim_v = np.array([chi2_gate(p.init_prob, int(max(k - 3, 1))) for k in n])
    return fix.ok & (n >= required) & (rec >= 2) & (fix.chi2 <= lim) & (fix.chi2_v <= lim_v)


def initiate(left: Leftovers, sites: Sites, anchors: tuple[int, int, int], required: int,
             p: NetworkParams) -> tuple[Opened, int]:
    """Steps 1-5 for one anchor triple: the accepted candidates, and the number of
    triples left waiting (max_triples)."""
    B = sites.tx.shape[0]
    pts, trip, waiting = triple_points(left, sites, anchors, p)
    members = np.full((pts.shape[0], B), -1)
    members[:, list(anchors)] = trip
    if pts.shape[0]:
        base = list(anchors)
        d_t = pts[:, None] - sites.tx[base]
        d_r = pts[:, None] - sites.rx[base]
        J = d_t / norm3(d_t)[..., None] + d_r / norm3(d_r)[..., None]
        info = np.einsum("cki,ck,ckj->cij", J, 1.0 / left.R[trip, 0, 0], J) + 1e-6 * np.eye(3)
        k = np.sqrt(chi2_gate(p.gate_prob, 1))
        for b in range(B):
            rows = np.flatnonzero(left.base == b)
            if b in anchors or rows.size == 0:
                continue
            pred = bistatic_range(pts, sites.tx[b], sites.rx[b])
            g = (pts - sites.tx[b]) / norm3(pts - sites.tx[b])[:, None]
            g += (pts - sites.rx[b]) / norm3(pts - sites.rx[b])[:, None]
            var = quadratic_form(g, info) + left.R[rows, 0, 0].max()  # g' C g, C = info^-1
            members[:, b] = _closest(pred, k * np.sqrt(var), left, rows)
    keep = (members >= 0).sum(axis=1) >= required
    members, pts = members[keep], pts[keep]
    fix = _fix(left, sites, members, pts[:, None, :], p)
    members = _regate(fix, left, sites, p)
    fix = _fix(left, sites, members, fix.x[:, None, [0, 2, 4]], p)
    ok = _accepted(fix, members, sites, required, p)
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
    return Opened(out, members[sel]), waiting
