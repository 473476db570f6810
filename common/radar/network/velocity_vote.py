"""Range-rate (Doppler) vote of initiation's seed cells: do the leftovers whose shells
reach a cell agree on one velocity?

A leftover i of base b is a candidate of the cell of centre c and half-diagonal d when
its shell reaches the cell ([V] of common.radar.network.voting). Its range rate
constrains the aircraft's velocity v (001 [2]; in the plane, the rows of 001 [43]):

    |g_b(c) . v - v_b,i| <= k sigma_v,i + d s_max (1/|c - T| + 1/|c - R|) + |g_b,z| vz_max   [D]

with g_b = u_T + u_R the sum of the unit vectors at the cell centre. The second term
bounds the change of g_b . v over the cell (|grad_p (u . v)| <= |v| / |p - S| for speeds
up to s_max), the third the vertical speed (the vote is over (vx, vy)). A cell's score is
the largest number of bases, each counted once, over >= 2 receivers, with a candidate
satisfying [D] somewhere in one cell of a grid over (vx, vy): an aircraft's candidates
agree on its velocity, the candidates of a ghost cell come from different aircraft and
scatter. Its members are per base the agreeing candidate of least (residual /
tolerance)^2 + (range residual / half-width of [V])^2.

Hough transform on an n x n grid of (vx, vy) per cell: per candidate and grid column
the rows its strip [D] (widened by the grid cell) crosses, marked in a difference array
per (cell, base), so each base counts once. Cost O(cells x (bases x n^2 + candidates x
n)), processed in chunks of cells (bounded memory).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.core.gating import chi2_gate, window_pairs
from common.radar.geometry.bistatic import norm3
from common.radar.network.params import NetworkParams

CHUNK = 256  # cells per Hough array


@dataclass(frozen=True)
class Shells:
    """Leftovers of the vote: base (L,), r_b (L,), v_b (L,), sigma_r (L,), sigma_v (L,)."""

    base: np.ndarray
    r: np.ndarray
    v: np.ndarray
    sigma_r: np.ndarray
    sigma_v: np.ndarray


@dataclass(frozen=True)
class Candidates:
    """(cell, leftover) pairs sorted by cell: cell (K,), base (K,), leftover (K,), the
    plane components of g_b at the cell (K, 2), v_b (K,), tolerance of [D] (K,), and
    |r_b(c) - r_b,i| over the half-width of [V] (K,)."""

    cell: np.ndarray
    base: np.ndarray
    left: np.ndarray
    g: np.ndarray
    v: np.ndarray
    tol: np.ndarray
    dr: np.ndarray


@dataclass(frozen=True)
class Vote:
    """Per cell: score (C,), velocity (C, 2) the centre of the best grid cell, step (C,)
    of its grid, members (C, B) leftover index or -1."""

    score: np.ndarray
    velocity: np.ndarray
    step: np.ndarray
    members: np.ndarray


def candidates(cells: np.ndarray, size: float, sh: Shells, tx: np.ndarray, rx: np.ndarray,
               p: NetworkParams) -> Candidates:
    """The pairs whose shell reaches a cube of side `size` ([V]) with the tolerances of [D]."""
    d = size * np.sqrt(3.0) / 2
    k = np.sqrt(chi2_gate(p.gate_prob, 1))
    parts = []
    for b in range(tx.shape[0]):
        rows = np.flatnonzero(sh.base == b)
        if rows.size == 0:
            continue
        d_t, d_r = cells - tx[b], cells - rx[b]
        n_t, n_r = norm3(d_t), norm3(d_r)
        u = d_t / n_t[:, None] + d_r / n_r[:, None]
        h = n_t + n_r
        m = d * (norm3(u) + 2 * d / np.minimum(n_t, n_r)) + k * sh.sigma_r[rows].max()
        c, j = window_pairs(h - m, h + m, sh.r[rows])
        i = rows[j]
        tol = (k * sh.sigma_v[i] + d * p.doppler_speed * (1 / n_t[c] + 1 / n_r[c])
               + np.abs(u[c, 2]) * p.doppler_vz)
        dr = np.abs(h[c] - sh.r[i]) / m[c]
        parts.append((c, np.full(c.size, b), i, u[c, :2], sh.v[i], tol, dr))
    if not parts:
        z = np.zeros(0, dtype=int)
        return Candidates(z, z, z, np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0))
    cat = [np.concatenate(x) for x in zip(*parts)]
    order = np.argsort(cat[0], kind="stable")
    return Candidates(*(x[order] for x in cat))


def _rows(k: Candidates, x0: np.ndarray, y0: np.ndarray, s: np.ndarray, n: int
          ) -> tuple[np.ndarray, np.ndarray]:
    """Per candidate and grid column (K, n): first and last grid row its strip [D],
    widened by the half grid cell, crosses (last < first: none). In grid units the
    strip's centre line is row alpha + beta j and its half-width gamma."""
    gy = np.where(np.abs(k.g[:, 1]) < 1e-6, np.copysign(1e-6, k.g[:, 1]), k.g[:, 1])
    T = k.tol + s / 2 * np.abs(k.g).sum(axis=1)
    alpha = ((k.v - k.g[:, 0] * x0) / gy - y0) / s
    beta = -k.g[:, 0] / gy
    gamma = T / (np.abs(gy) * s)
    mid = alpha[:, None] + beta[:, None] * np.arange(n)
    first = np.clip(np.ceil(mid - gamma[:, None] - 1e-9), 0, n)
    last = np.clip(np.floor(mid + gamma[:, None] + 1e-9), -1, n - 1)
    return first.astype(int), last.astype(int)


def _counts(k: Candidates, cell: np.ndarray, ncell: int, x0: np.ndarray, y0: np.ndarray,
            s: np.ndarray, n: int) -> np.ndarray:
    """Bases agreeing at every grid cell (ncell, n, n); `cell` the pairs' cell in 0..ncell,
    pairs sorted by cell then base."""
    first, last = _rows(k, x0, y0, s, n)
    new = np.r_[True, (cell[1:] != cell[:-1]) | (k.base[1:] != k.base[:-1])]
    group = np.cumsum(new) - 1  # one per (cell, base): each base counts once
    ok = first <= last
    col = np.broadcast_to(np.arange(n), ok.shape)
    at = ((group[:, None] * n + col) * (n + 1))[ok]
    size = (int(group[-1]) + 1) * n * (n + 1)
    diff = (np.bincount(at + first[ok], minlength=size)
            - np.bincount(at + last[ok] + 1, minlength=size)).astype(np.int16)
    cover = (np.cumsum(diff.reshape(-1, n, n + 1), axis=-1)[..., :n] > 0).astype(np.int16)
    starts = np.flatnonzero(new)
    at_cell = np.r_[True, cell[starts][1:] != cell[starts][:-1]]
    out = np.zeros((ncell, n, n), dtype=np.int16)
    out[cell[starts][at_cell]] = np.add.reduceat(cover, np.flatnonzero(at_cell), axis=0)
    return out


def vote(cells: np.ndarray, size: float, sh: Shells, tx: np.ndarray, rx: np.ndarray,
         receiver: np.ndarray, centre: np.ndarray, half: np.ndarray, n: int,
         p: NetworkParams) -> Vote:
    """[D] for cubes of side `size` over the velocity windows centre (C, 2) +- half (C,)
    on n x n grids."""
    C, B = cells.shape[0], tx.shape[0]
    k = candidates(cells, size, sh, tx, rx, p)
    s = 2 * half / n
    x0, y0 = centre[:, 0] - half + s / 2, centre[:, 1] - half + s / 2
    score = np.zeros(C, dtype=int)
    best = np.zeros(C, dtype=int)
    bounds = np.searchsorted(k.cell, np.arange(0, C + CHUNK, CHUNK))
    for start, (a, e) in enumerate(zip(bounds[:-1], bounds[1:])):
        c0 = start * CHUNK
        nc = min(CHUNK, C - c0)
        if nc <= 0:
            break
        if a == e:
            continue
        sub = Candidates(*(getattr(k, f)[a:e] for f in ("cell", "base", "left", "g", "v", "tol", "dr")))
        cell = sub.cell - c0
        counts = _counts(sub, cell, nc, x0[sub.cell], y0[sub.cell], s[sub.cell], n)
        flat = counts.reshape(nc, -1)
        best[c0:c0 + nc] = flat.argmax(axis=1)
        score[c0:c0 + nc] = flat.max(axis=1)
    velocity = np.column_stack([x0 + s * (best // n), y0 + s * (best % n)])
    members, rec = _members(k, velocity, s, C, B, receiver)
    score = np.where(rec >= 2, score, 0)
    return Vote(score, velocity, s, members)


def _members(k: Candidates, velocity: np.ndarray, s: np.ndarray, C: int, B: int,
             receiver: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per cell and base the candidate agreeing at the best grid cell of least
    (residual / tolerance)^2 + dr^2 (C, B) (the range tells apart aircraft flying
    together), and the receivers with one (C,)."""
    members = np.full((C, B), -1)
    T = k.tol + s[k.cell] / 2 * np.abs(k.g).sum(axis=1)
    res = np.abs((k.g * velocity[k.cell]).sum(axis=1) - k.v) / T
    agree = np.flatnonzero(res <= 1.0)
    cost = res ** 2 + k.dr ** 2
    order = agree[np.lexsort((cost[agree], k.base[agree], k.cell[agree]))]
    c, b = k.cell[order], k.base[order]
    first = np.r_[True, (c[1:] != c[:-1]) | (b[1:] != b[:-1])] if order.size else order > 0
    members[c[first], b[first]] = k.left[order[first]]
    rec = np.zeros((C, int(receiver.max()) + 1), dtype=bool)
    rec[c[first], receiver[b[first]]] = True
    return members, rec.sum(axis=1)
