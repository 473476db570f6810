"""Nearest neighbour (001 [12]) and GNN assignment on gated costs."""

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from common.core.assignment import gnn, nearest_neighbour

INF = np.inf


@st.composite
def gated_costs(draw, max_n=4, max_m=4):
    N = draw(st.integers(0, max_n))
    M = draw(st.integers(0, max_m))
    vals = draw(
        st.lists(
            st.one_of(st.just(INF), st.floats(-5.0, 20.0, allow_nan=False)),
            min_size=N * M,
            max_size=N * M,
        )
    )
    return np.array(vals, dtype=float).reshape(N, M)


def _brute_force(cost):
    """Best (n_pairs, -total) over all matchings on finite entries."""
    N, M = cost.shape
    best = (0, 0.0)
    for k in range(1, min(N, M) + 1):
        for rows in itertools.combinations(range(N), k):
            for cols in itertools.permutations(range(M), k):
                c = cost[list(rows), list(cols)]
                if np.all(np.isfinite(c)):
                    best = max(best, (k, -c.sum()))
    return best


def _greedy_reference(cost):
    """Sequential closest-pair-first pass over gated pairs (ties: track, then plot)."""
    pairs = sorted((cost[t, j], t, j) for t, j in zip(*np.nonzero(np.isfinite(cost))))
    used_t, used_j, out = set(), set(), {}
    for _, t, j in pairs:
        if t not in used_t and j not in used_j:
            used_t.add(t)
            used_j.add(j)
            out[t] = j
    return out


def _check_matching(cost, rows, cols):
    assert len(rows) == len(cols)
    assert len(set(rows.tolist())) == len(rows) and len(set(cols.tolist())) == len(cols)
    assert np.all(np.isfinite(cost[rows, cols]))
    assert np.all(np.diff(rows) > 0)


def test_nearest_neighbour_conflict_case():
    # plot 0 is the closest plot of tracks 0 and 1; the pair (0, 0) is the closest,
    # so track 0 keeps it and track 1 (nothing else in its gate) stays unassociated.
    cost = np.array(
        [
            [1.0, 3.0, INF],
            [2.0, INF, INF],
            [INF, INF, 0.5],
        ]
    )
    rows, cols, amb = nearest_neighbour(cost)
    np.testing.assert_array_equal(rows, [0, 2])
    np.testing.assert_array_equal(cols, [0, 2])
    # track 0: two plots in the gate; track 1: shares its best plot; track 2: clear
    np.testing.assert_array_equal(amb, [True, True, False])
    # GNN maximises the number of pairs instead: 0->1, 1->0, 2->2
    g_rows, g_cols = gnn(cost)
    np.testing.assert_array_equal(g_rows, [0, 1, 2])
    np.testing.assert_array_equal(g_cols, [1, 0, 2])


def test_nearest_neighbour_loser_falls_back_to_next_free_plot():
    cost = np.array([[1.0, 4.0], [2.0, 3.0]])
    rows, cols, amb = nearest_neighbour(cost)
    np.testing.assert_array_equal(cols[np.argsort(rows)], [0, 1])
    assert amb.all()


def test_nearest_neighbour_no_conflict_is_argmin_001_12():
    cost = np.array([[5.0, 1.0, INF, 2.0], [INF, INF, 0.3, INF], [INF, INF, INF, INF]])
    rows, cols, amb = nearest_neighbour(cost)
    np.testing.assert_array_equal(rows, [0, 1])
    np.testing.assert_array_equal(cols, [1, 2])
    np.testing.assert_array_equal(amb, [True, False, False])


@settings(max_examples=200, deadline=None)
@given(gated_costs(max_n=6, max_m=6))
def test_nearest_neighbour_equals_sequential_greedy(cost):
    rows, cols, amb = nearest_neighbour(cost)
    _check_matching(cost, rows, cols)
    assert dict(zip(rows.tolist(), cols.tolist())) == _greedy_reference(cost)
    assert amb.shape == (cost.shape[0],)
    assert not np.any(amb[~np.isfinite(cost).any(axis=1)])


@settings(max_examples=300, deadline=None)
@given(gated_costs())
def test_gnn_optimal_vs_brute_force(cost):
    rows, cols = gnn(cost)
    _check_matching(cost, rows, cols)
    k, neg_total = _brute_force(cost)
    assert len(rows) == k
    assert abs(cost[rows, cols].sum() - (-neg_total)) < 1e-9


def test_gnn_empty_and_fully_gated_out():
    for shape in [(0, 0), (0, 5), (4, 0)]:
        r, c = gnn(np.zeros(shape))
        assert r.size == 0 and c.size == 0
        r, c, a = nearest_neighbour(np.zeros(shape))
        assert r.size == 0 and a.shape == (shape[0],)
    r, c = gnn(np.full((3, 3), INF))
    assert r.size == 0


def test_gnn_sparse_many_components():
    rng = np.random.default_rng(5)
    N = 300
    cost = np.full((N, N + 50), INF)
    # clusters of 3 tracks x 3 plots plus singletons, shuffled
    for b in range(0, N, 3):
        cost[b : b + 3, b : b + 3] = rng.uniform(0, 10, size=(3, 3))
    cost[rng.random(cost.shape) < 0.3 * (cost < INF)] = INF
    perm_r, perm_c = rng.permutation(N), rng.permutation(N + 50)
    cost = cost[perm_r][:, perm_c]
    rows, cols = gnn(cost)
    _check_matching(cost, rows, cols)
    # each 3x3 block solved optimally: compare with brute force block by block
    total = 0.0
    inv_r, inv_c = np.argsort(perm_r), np.argsort(perm_c)
    for b in range(0, N, 3):
        block = cost[np.ix_(inv_r[b : b + 3], inv_c[b : b + 3])]
        k, neg = _brute_force(block)
        total += -neg
    assert abs(cost[rows, cols].sum() - total) < 1e-9
