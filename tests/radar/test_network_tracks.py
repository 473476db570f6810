"""The update path of the network fusion centre, vectorised, against what it replaced:
common.radar.network.tracks' (N, B) member, misses and cycle columns give what the
per-track dictionaries gave (`Reference` below is that former bookkeeping, one Python
loop per track), on random sequences of every operation; the candidate gate of step 3
(common.radar.network.fusion.candidate_costs, a range window first) gives the costs of
every pair tested."""

from __future__ import annotations

import numpy as np
import pytest

from common.core.gating import chi2_gate, pair_distances
from common.core.track_table import Status
from common.radar.network.fusion import candidate_costs
from common.radar.network.params import NetworkParams
from common.radar.network.tracks import Tracks

RECEIVER = np.array([0, 0, 0, 0, 1, 2, 2])  # 7 bases on 3 receivers, 4 on one
B = RECEIVER.size


class Reference:
    """The former membership and cycle bookkeeping of Tracks (per-track loops)."""

    def __init__(self, p: NetworkParams) -> None:
        self.p = p
        self.members: list[dict[int, int]] = []
        self.cycle_bases: list[set[int]] = []
        self.owner: dict[tuple[int, int], int] = {}  # (base, eid) -> row
        self.misses: dict[tuple[int, int], int] = {}
        self.hits: list[int] = []

    def _release(self, b: int, eid: int) -> None:
        row = self.owner.pop((b, eid), None)
        self.misses.pop((b, eid), None)
        if row is not None:
            self.members[row].pop(b, None)

    def open(self, members: list[tuple[int, int]]) -> None:
        self.members.append({})
        self.cycle_bases.append(set())
        self.hits.append(0)
        for b, e in members:
            self.add(len(self.members) - 1, b, e)

    def add(self, row: int, b: int, e: int) -> None:
        self.members[row][b] = e
        self.owner[(b, e)] = row

    def member_of(self, b: int, e: int) -> int:
        return self.owner.get((b, e), -1)

    def release_absent(self, b: int, eids: list[int]) -> None:
        for key in [k for k in self.owner if k[0] == b and k[1] not in set(eids)]:
            self._release(*key)

    def count_misses(self, b: int, eids: list[int]) -> None:
        for e in eids:
            n = self.misses.get((b, e), 0) + 1
            self.misses[(b, e)] = n
            if n >= self.p.member_misses:
                self._release(b, e)

    def updated(self, rows: list[int], b: int) -> None:
        for r in rows:
            self.cycle_bases[r].add(b)
            self.misses.pop((b, self.members[r][b]), None)

    def cycle(self, rows: list[int]) -> None:
        for r in rows:
            bs = list(self.cycle_bases[r])
            if len(bs) >= 3 and np.unique(RECEIVER[bs]).size >= 2:
                self.hits[r] += 1
            self.cycle_bases[r] = set()

    def remove(self, dead: list[int]) -> None:
        for r in sorted(dead, reverse=True):
            for b, e in list(self.members[r].items()):
                self._release(b, e)
            del self.members[r], self.cycle_bases[r], self.hits[r]
        self.owner = {k: r - sum(1 for d in dead if d < r) for k, r in self.owner.items()}

    def absorb(self, keep: int, gone: int) -> None:
        for b, e in list(self.members[gone].items()):
            if b not in self.members[keep]:
                self.owner.pop((b, e), None)
                self.misses.pop((b, e), None)
                self.members[gone].pop(b)
                self.add(keep, b, e)


def same(T: Tracks, ref: Reference) -> None:
    assert T.members == ref.members
    assert T.hits.tolist() == ref.hits
    for (b, e), n in ref.misses.items():
        assert T.misses[ref.owner[(b, e)], b] == n
    assert int(T.misses.sum()) == sum(ref.misses.values())
    assert T.n_bases().tolist() == [len(m) for m in ref.members]
    for b in range(B):
        assert T.has_base(b).tolist() == [b in m for m in ref.members]


@pytest.mark.parametrize("seed", range(20))
def test_columns_match_the_per_track_bookkeeping(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = NetworkParams(cycle=1e9)  # cycles closed by hand below (bookkeep's other rules aside)
    T, ref = Tracks(p, RECEIVER), Reference(p)
    x, P = np.array([0.0, 0, 0, 0, 5e3, 0]), np.eye(6)
    for _ in range(300):
        op = rng.integers(7)
        n = len(T)
        if op == 0 or n == 0:
            bases = rng.choice(B, size=int(rng.integers(0, 5)), replace=False)
            mem = []
            for b in bases.tolist():
                e = int(rng.integers(1, 40))
                if ref.member_of(b, e) < 0:
                    mem.append((b, e))
            T.open(0.0, x, P, mem)
            ref.open(mem)
        elif op == 1:
            b = int(rng.integers(B))
            eids = rng.integers(1, 40, size=int(rng.integers(0, 30)))
            T.release_absent(b, eids)
            ref.release_absent(b, eids.tolist())
        elif op == 2:
            b = int(rng.integers(B))
            held = [e for (bb, e) in ref.owner if bb == b]
            eids = rng.permutation(held)[:int(rng.integers(0, len(held) + 1))]
            rows = T.rows_of(b, np.array(eids, dtype=np.int64))
            assert rows.tolist() == [ref.member_of(b, int(e)) for e in eids]
            T.count_misses(b, np.array(eids, dtype=np.int64))
            ref.count_misses(b, [int(e) for e in eids])
        elif op == 3:
            b = int(rng.integers(B))
            free_rows = np.flatnonzero(~T.has_base(b))
            rows = rng.permutation(free_rows)[:int(rng.integers(0, free_rows.size + 1))]
            eids = [e for e in rng.permutation(np.arange(1, 80)).tolist() if ref.member_of(b, e) < 0]
            eids = np.array(eids[:rows.size], dtype=np.int64)
            T.add_members(rows, b, eids)
            for r, e in zip(rows.tolist(), eids.tolist()):
                ref.add(r, b, e)
        elif op == 4:
            b = int(rng.integers(B))
            rows = np.flatnonzero(T.has_base(b))
            rows = rows[rng.random(rows.size) < 0.7]
            T.updated(rows, 1.0, np.tile(x, (rows.size, 1)), np.tile(P, (rows.size, 1, 1)), b)
            ref.updated(rows.tolist(), b)
        elif op == 5:
            due = np.flatnonzero(rng.random(n) < 0.5)
            T.cycle_start[due] = -2e9  # these rows' cycles end at the next bookkeep
            T.bookkeep(0.0)
            ref.cycle(due.tolist())
            T.status[:] = Status.TENTATIVE
        else:
            if n >= 2 and rng.random() < 0.5:
                keep, gone = rng.choice(n, size=2, replace=False).tolist()
                T.absorb(keep, gone, 0.0, x, P)
                ref.absorb(keep, gone)
            dead = rng.random(n) < 0.2
            T.remove(dead)
            ref.remove(np.flatnonzero(dead).tolist())
        same(T, ref)


def _spd(rng: np.random.Generator, n: int, m: int, scale: np.ndarray) -> np.ndarray:
    L = rng.normal(size=(n, m, m)) * scale[None, :, None]
    return L @ np.swapaxes(L, 1, 2) + np.diag(scale**2 * 0.1)[None]


@pytest.mark.parametrize("m", [2, 3])
@pytest.mark.parametrize("seed", range(10))
def test_candidate_costs_equal_every_pair_tested(m: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, k = int(rng.integers(1, 60)), int(rng.integers(1, 60))
    scale = np.array([300.0, 1.0, 0.01])[:m]
    h = np.column_stack([rng.uniform(0, 30e3, n), rng.uniform(-300, 300, n), rng.uniform(0, 6, n)])[:, :m]
    z = h[rng.integers(n, size=k)] + rng.normal(size=(k, m)) * scale * rng.choice([1.0, 5.0], size=(k, 1))
    z[: k // 3, 0] = rng.uniform(0, 30e3, k // 3)  # others anywhere
    A, R = _spd(rng, n, m, scale), _spd(rng, k, m, scale)
    ang = [2] if m == 3 else []
    gam = chi2_gate(0.9999, m)
    cand = np.flatnonzero(rng.random(n) < 0.7)
    free = np.flatnonzero(rng.random(k) < 0.7)
    if not (cand.size and free.size):
        return
    ti, ji = np.repeat(cand, free.size), np.tile(free, cand.size)
    _, _, d2 = pair_distances(h, A, z, R, ti, ji, ang)
    want = np.where(d2 <= gam, d2, np.inf).reshape(cand.size, free.size)
    got = candidate_costs(h, A, z, R, cand, free, ang, gam)
    assert np.isfinite(want).any()
    np.testing.assert_array_equal(got, want)
