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
out every aircraft seen by fewer bases for good. Cells of equal votes are taken in an
order that changes with the round (`turn`), so a saturated level (dense scenes: every
cell crossed by a shell of every base) does not refine the same part of the volume in
every round.
"""

from __future__ import annotations

import numpy as np

from common.core.gating import chi2_gate
from common.radar.geometry.bistatic import norm3
from common.radar.network.params import NetworkParams

CHILDREN = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) / 4.0


def _grid(tx: np.ndarray, rx: np.ndarray, p: NetworkParams) -> np.ndarray:
    """Level-0 cell centres (C, 3)."""
    sites = np.vstack([tx, rx])
    lo = np.r_[sites[:, :2].min(axis=0) - p.volume_margin, p.z_min]
    hi = np.r_[sites[:, :2].max(axis=0) + p.volume_margin, p.z_max]
    axes = [np.arange(lo[i] + p.cell_coarse / 2, hi[i], p.cell_coarse) for i in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def votes(cells: np.ndarray, size: float, shells: list[tuple[np.ndarray, np.ndarray]],
          tx: np.ndarray, rx: np.ndarray, receiver: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[V] for cubes of side `size`: votes (C,) and receivers with a vote (C,). shells:
    per base the sorted ranges and their half-widths k sigma_r (max of the base)."""
    d = size * np.sqrt(3.0) / 2
    n = np.zeros(cells.shape[0], dtype=np.int64)
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
        n += hit
        rec[:, receiver[b]] |= hit
    return n, rec.sum(axis=1)


def vote_cells(base: np.ndarray, r: np.ndarray, sigma: np.ndarray, tx: np.ndarray,
               rx: np.ndarray, receiver: np.ndarray, required: int, p: NetworkParams,
               turn: int = 0) -> tuple[np.ndarray, int]:
    """Leaf cell centres (C, 3) of the leftovers (base (L,), range r (L,), sigma_r (L,)),
    most voted first (ties in the order of round `turn`), and the number of leaf cells
    beyond max_cells (left for later)."""
    rng = np.random.default_rng(turn)
    k = np.sqrt(chi2_gate(p.gate_prob, 1))
    shells = []
    for b in range(tx.shape[0]):
        rows = base == b
        shells.append((np.sort(r[rows]), k * sigma[rows].max(initial=0.0)))
    cells, size = _grid(tx, rx, p), p.cell_coarse
    while True:
        n, n_rec = votes(cells, size, shells, tx, rx, receiver)
        keep = np.flatnonzero((n >= required) & (n_rec >= 2))
        cut = max(0, keep.size - p.max_cells)
        order = np.lexsort((rng.permutation(keep.size), -n[keep]))
        cells = cells[keep[order][:p.max_cells]]
        if size / 2 < p.cell_fine or cells.shape[0] == 0:
            return cells, cut
        size /= 2
        cells = (cells[:, None] + CHILDREN * 2 * size).reshape(-1, 3)
