"""Seed points of initiation by coarse-to-fine voting in the surveillance volume
(issue 29: replaces the enumeration of base triples, cubic in the leftovers).

A leftover i of base b votes for a cell of centre c and half-diagonal d when its
ellipsoidal shell r_b,i +- k sigma_r,i reaches the cell:

    |r_b(c) - r_b,i| <= k sigma_r,i + d (|u_T + u_R|(c) + 2 d / min(|c - T|, |c - R|))  [V]

(r_b 001 [1]; the bracket bounds the gradient of r_b over the cell: its value at c plus
the turn of the unit vectors, so the test never refuses a cell the shell crosses). A
cell's votes are its bases with a hit. From cells of `cell_coarse` over the box of the
sites widened by `volume_margin` (z in the volume's bounds), each level keeps the cells
with votes >= required from >= 2 receivers, at most `max_cells` of the most voted, and
halves them (8 children), down to `cell_fine`. The floor is absolute: a floor relative
to the best cell (best - slack) let a few ghost cells, rejected round after round, shut
out every aircraft seen by fewer bases for good. Cells of equal votes are taken in
the order of a sweep that moves with the round (`turn`): the blocks of the first level
(cell_coarse) ranked by frac(id phi - turn psi) (phi the golden ratio, psi = 1 - phi;
the Weyl sequence visits every block), so a saturated level (dense scenes: every cell
crossed by a shell of every base) refines another part of the volume each round and
reaches all of it within a few tens of rounds.

With the range rates (doppler_cell > 0), every level ranks its cells by the whole nats
of the information [I] of their votes (`votes`) rather than their number (in dense
scenes nearly every cell has every vote, and an aircraft that fewer bases see has fewer
than a ghost cell), ties in the sweep's order; the levels of cells no larger than
doppler_cell rank them by the velocity vote [D] of
common.radar.network.velocity_vote instead: at most `doppler_cells` cells of the range
floor, in the sweep's order, are voted on; those with >= required agreeing bases are
kept, the best first, at most doppler_cells / 8 (refined, or seeds at the last); the
first such level votes over every velocity up to doppler_speed on a doppler_grid^2
grid, the next ones on a LOCAL^2 grid of +- two grid steps around their parent's
velocity. The last level returns each cell's agreeing candidates as members.
"""

from __future__ import annotations

import numpy as np

from common.core.gating import chi2_gate
from common.radar.geometry.bistatic import norm3
from common.radar.network.params import NetworkParams
from common.radar.network.velocity_vote import Shells, Vote, vote

PHI = (np.sqrt(5.0) - 1) / 2  # the sweep's rotation
LOCAL = 8  # side of the local velocity grids
CHILDREN = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) / 4.0


def _grid(tx: np.ndarray, rx: np.ndarray, p: NetworkParams) -> np.ndarray:
    """Level-0 cell centres (C, 3)."""
    sites = np.vstack([tx, rx])
    lo = np.r_[sites[:, :2].min(axis=0) - p.volume_margin, p.z_min]
    hi = np.r_[sites[:, :2].max(axis=0) + p.volume_margin, p.z_max]
    axes = [np.arange(lo[i] + p.cell_coarse / 2, hi[i], p.cell_coarse) for i in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def votes(cells: np.ndarray, size: float, shells: list[tuple[np.ndarray, np.ndarray]],
          tx: np.ndarray, rx: np.ndarray, receiver: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """[V] for cubes of side `size`: votes (C,), receivers with a vote (C,) and the
    information of the votes (C,), the sum over the hits of -log P(hit), P(hit) = 1 -
    exp(-lambda) with lambda = N_b 2 m / (span of the base's N_b shells + 2 m) the shells
    expected in the window [I] (a vote where shells are dense says little). shells: per
    base the sorted ranges and their half-widths k sigma_r (max of the base)."""
    d = size * np.sqrt(3.0) / 2
    n = np.zeros(cells.shape[0], dtype=np.int64)
    info = np.zeros(cells.shape[0])
    rec = np.zeros((cells.shape[0], int(receiver.max()) + 1), dtype=bool)
    for b, (r, w) in enumerate(shells):
        if r.size == 0:
            continue
        d_t, d_r = cells - tx[b], cells - rx[b]
        n_t, n_r = norm3(d_t), norm3(d_r)
        g = norm3(d_t / n_t[:, None] + d_r / n_r[:, None]) + 2 * d / np.minimum(n_t, n_r)
        h = n_t + n_r
        m = d * g + w
        hit = np.searchsorted(r, h + m, side="right") > np.searchsorted(r, h - m)
        lam = r.size * 2 * m / (r[-1] - r[0] + 2 * m)
        n += hit
        info += np.where(hit, -np.log(-np.expm1(-lam)), 0.0)
        rec[:, receiver[b]] |= hit
    return n, rec.sum(axis=1), info


def sweep(cells: np.ndarray, lo: np.ndarray, p: NetworkParams, turn: int) -> np.ndarray:
    """Rank key in [0, 1) of cells (C, 3) in round `turn`: that of their first-level block."""
    idx = np.floor((cells - lo) / p.cell_coarse).astype(np.int64)
    block = idx[:, 0] + 4096 * (idx[:, 1] + 4096 * idx[:, 2])
    return np.mod(block * PHI - turn * (1.0 - PHI), 1.0)


def _doppler_level(cells: np.ndarray, keep: np.ndarray, key: np.ndarray, size: float,
                   sh: Shells, window: tuple[np.ndarray, np.ndarray] | None, tx: np.ndarray,
                   rx: np.ndarray, receiver: np.ndarray, required: int, limit: int,
                   p: NetworkParams) -> tuple[np.ndarray, Vote, int]:
    """The velocity vote of a level on the cells `keep` (key: their sweep key): the cells
    kept (best first, at most limit), their vote, and how many passed but were cut."""
    keep = keep[np.argsort(key, kind="stable")][:p.doppler_cells]
    key = np.sort(key)[:p.doppler_cells]
    if window is None:
        centre = np.zeros((keep.size, 2))
        half, n = np.full(keep.size, p.doppler_speed), p.doppler_grid
    else:
        centre, half, n = window[0][keep], window[1][keep], LOCAL
    v = vote(cells[keep], size, sh, tx, rx, receiver, centre, half, n, p)
    ok = np.flatnonzero(v.score >= required)
    order = ok[np.lexsort((key[ok], -v.score[ok]))][:limit]
    return keep[order], Vote(*(x[order] for x in (v.score, v.velocity, v.step, v.members))), \
        max(0, ok.size - limit)


def vote_cells(base: np.ndarray, r: np.ndarray, sigma: np.ndarray, tx: np.ndarray,
               rx: np.ndarray, receiver: np.ndarray, required: int, p: NetworkParams,
               turn: int = 0, doppler: Shells | None = None,
               extent: tuple[int, float, float] | None = None
               ) -> tuple[np.ndarray, np.ndarray | None, int]:
    """Leaf cell centres (C, 3) of the leftovers (base (L,), range r (L,), sigma_r (L,)),
    most voted first (ties in the sweep's order of round `turn`), their members (C, B)
    from the velocity vote when `doppler` (the same leftovers with their range rates) is
    given and doppler_cell > 0 (else None), and the number of leaf cells beyond the
    limits (left for later). `extent` (axis 0 or 1, lo, hi): only the first level's
    cells that reach lo <= c[axis] < hi are voted (a partition's region)."""
    k = np.sqrt(chi2_gate(p.gate_prob, 1))
    shells = []
    for b in range(tx.shape[0]):
        rows = base == b
        shells.append((np.sort(r[rows]), k * sigma[rows].max(initial=0.0)))
    cells, size = _grid(tx, rx, p), p.cell_coarse
    lo = cells.min(axis=0) - p.cell_coarse / 2
    if extent is not None:
        c = cells[:, extent[0]]
        cells = cells[(c + size / 2 >= extent[1]) & (c - size / 2 < extent[2])]
    window: tuple[np.ndarray, np.ndarray] | None = None
    while True:
        n, n_rec, info = votes(cells, size, shells, tx, rx, receiver)
        keep = np.flatnonzero((n >= required) & (n_rec >= 2))
        key = sweep(cells[keep], lo, p, turn)
        if doppler is not None:  # ranked by whole nats of [I], ties by the sweep
            key = key - np.floor(info[keep])
        last = size / 2 < p.cell_fine or keep.size == 0
        if doppler is not None and size <= p.doppler_cell * (1 + 1e-9):
            limit = max(1, p.doppler_cells // 8)
            sel, v, cut = _doppler_level(cells, keep, key, size, doppler, window, tx, rx,
                                         receiver, required, limit, p)
            cells = cells[sel]
            if last or cells.shape[0] == 0:
                return cells, v.members, cut
            window = (np.repeat(v.velocity, 8, axis=0), np.repeat(2 * v.step, 8))
        else:
            cut = max(0, keep.size - p.max_cells)
            order = np.argsort(key, kind="stable") if doppler is not None else \
                np.lexsort((key, -n[keep]))
            cells = cells[keep[order][:p.max_cells]]
            if last or cells.shape[0] == 0:
                return cells, None, cut
        size /= 2
        cells = (cells[:, None] + CHILDREN * 2 * size).reshape(-1, 3)
