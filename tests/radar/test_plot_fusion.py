"""Plot fusion of one base (001 modules 31-34): [5] at the interval edges, [6]-[7],
acceptance rule, channel exclusivity, scan assembly."""

from __future__ import annotations

import numpy as np
import pytest

from common.core.rejection import Rejected
from common.radar.plots.channel_fusion import (
    PlotFusion,
    Plots,
    accept,
    aggregate,
    components,
    fuse,
    fuse_scan,
)


def plots(rows: list[tuple[float, ...]], n_ch: list[int] | None = None) -> Plots:
    """Plots from rows (rb, vb, az, srb, svb, saz)."""
    a = np.asarray(rows, dtype=float).reshape(-1, 6)
    n = np.ones(len(a), dtype=np.int64) if n_ch is None else np.asarray(n_ch)
    return Plots(*(a[:, k] for k in range(6)), n)


BASE = (10000.0, 50.0, 1.0, 100.0, 2.0, 0.01)


def shifted(k: int, d: float) -> tuple[float, ...]:
    row = list(BASE)
    row[k] += d
    return tuple(row)


@pytest.mark.parametrize("k", [0, 1, 2])
def test_eq5_intervals_touching_at_the_edge_aggregate(k: int) -> None:
    # 2-sigma intervals [y - 2s, y + 2s]: with equal sigmas s they touch at |d| = 4 s
    # (001 [5], closed intervals); values chosen exactly representable.
    s = [100.0, 2.0, 0.015625][k]
    row0 = list(BASE)
    row0[3 + k] = s
    row1 = list(row0)
    row1[k] += 4 * s
    p = plots([tuple(row0), tuple(row1)])
    assert aggregate(p, np.array([0, 1])).tolist() == [0, 0]
    row1[k] += 4 * s * 1e-9
    p = plots([tuple(row0), tuple(row1)])
    assert aggregate(p, np.array([0, 1])).tolist() == [0, 1]


def test_eq5_unequal_sigmas_and_azimuth_across_north() -> None:
    # rb: 2 * (100 + 50) = 300 m apart still overlaps, 301 m does not.
    a = plots([(1e4, 0, 1, 100, 2, 0.01), (1e4 + 300, 0, 1, 50, 2, 0.01)])
    b = plots([(1e4, 0, 1, 100, 2, 0.01), (1e4 + 301, 0, 1, 50, 2, 0.01)])
    assert aggregate(a, np.array([0, 1])).tolist() == [0, 0]
    assert aggregate(b, np.array([0, 1])).tolist() == [0, 1]
    # azimuths 0.01 and 2 pi - 0.01 are 0.02 apart on the circle (< 2 (0.01 + 0.01))
    c = plots([(1e4, 0, 0.01, 100, 2, 0.01), (1e4, 0, 2 * np.pi - 0.01, 100, 2, 0.01)])
    assert aggregate(c, np.array([0, 1])).tolist() == [0, 0]


def test_two_plots_of_one_channel_are_never_fused() -> None:
    p = plots([BASE, BASE])
    assert aggregate(p, np.array([0, 0])).tolist() == [0, 1]


def test_plot_compatible_with_two_aggregates() -> None:
    # A (ch 0) - B (ch 1) - C (ch 2): A-C incompatible, no shared channel: one aggregate.
    p = plots([shifted(0, 0.0), shifted(0, 350.0), shifted(0, 700.0)])
    assert aggregate(p, np.array([0, 1, 2])).tolist() == [0, 0, 0]
    # A (ch 0) - B (ch 1) - C (ch 0): B joins its closer neighbour C; A stays alone.
    p = plots([shifted(0, 0.0), shifted(0, 380.0), shifted(0, 700.0)])
    labels = aggregate(p, np.array([0, 1, 0]))
    assert labels[1] == labels[2] != labels[0]


def test_eq6_eq7_identical_plots_divide_variance_by_k() -> None:
    for K in (1, 2, 3, 5):
        p = plots([BASE] * K)
        f = fuse(p, np.zeros(K, dtype=np.intp))
        assert len(f) == 1 and f.n_ch.tolist() == [K]
        np.testing.assert_allclose(f.srb**2, BASE[3] ** 2 / K)
        np.testing.assert_allclose(f.svb**2, BASE[4] ** 2 / K)
        np.testing.assert_allclose(f.saz**2, BASE[5] ** 2 / K)
        np.testing.assert_allclose([f.rb[0], f.vb[0], f.az[0]], BASE[:3])


def test_eq6_eq7_weighted_mean_hand_computed() -> None:
    # y1 = 0 (s 1), y2 = 3 (s 2): R = 1 / (1 + 1/4) = 0.8, y = 0.8 * (0 + 3/4) = 0.6
    p = plots([(1000.0, 0.0, 0.01, 1.0, 1.0, 0.01), (1003.0, 3.0, 2 * np.pi - 0.01, 2.0, 2.0, 0.01)])
    f = fuse(p, np.array([0, 0]))
    assert f.rb[0] == pytest.approx(1000.6)
    assert f.vb[0] == pytest.approx(0.6)
    assert f.srb[0] ** 2 == pytest.approx(0.8)
    assert f.az[0] == pytest.approx(0.0, abs=1e-12) or f.az[0] == pytest.approx(2 * np.pi)


def test_acceptance_rule() -> None:
    f = plots([BASE] * 4, n_ch=[1, 2, 3, 4])
    assert accept(f, 2, 0).n_ch.tolist() == [1, 2, 3, 4]  # two channels: keep all
    assert accept(f, 1, 0).n_ch.tolist() == [1, 2, 3, 4]
    assert accept(f, 4, 1).n_ch.tolist() == [3, 4]  # n > 2: score >= n - p
    assert accept(f, 4, 0).n_ch.tolist() == [4]
    assert accept(f, 3, 2).n_ch.tolist() == [1, 2, 3, 4]


def test_fuse_scan_two_channels_keeps_singles() -> None:
    ch0 = plots([BASE, shifted(0, 5000.0)])
    ch1 = plots([shifted(0, 10.0)])
    f = fuse_scan([ch0, ch1], 2, 0)
    assert sorted(f.n_ch.tolist()) == [1, 2]
    f3 = fuse_scan([ch0, ch1, Plots.empty()], 3, 1)
    assert f3.n_ch.tolist() == [2]


def test_scan_assembly_complete_and_later_time() -> None:
    core = PlotFusion(["a", "b", "c"], p=1)
    one = plots([BASE])
    assert core.push("a", 1.0, one) == []
    assert core.push("b", 1.0, one) == []
    out = core.push("c", 1.0, one)  # every channel reported t = 1
    assert [t for t, _ in out] == [1.0] and out[0][1].n_ch.tolist() == [3]
    assert core.push("a", 2.0, one) == []
    out = core.push("a", 3.0, one)  # a later time completes t = 2 (b, c empty)
    assert [t for t, _ in out] == [2.0] and len(out[0][1]) == 0  # 1 < n - p: rejected
    with pytest.raises(Rejected, match="time_backwards"):
        core.push("a", 3.0, one)
    with pytest.raises(Rejected, match="late_scan"):
        core.push("b", 2.0, one)
    with pytest.raises(Rejected, match="unknown_channel"):
        core.push("z", 4.0, one)
    out = core.push("b", 3.0, Plots.empty()) + core.push("c", 3.0, Plots.empty())
    assert [t for t, _ in out] == [3.0]  # empty channel messages still complete a scan


def test_scan_completed_by_a_time_already_seen_elsewhere() -> None:
    core = PlotFusion(["a", "b"], p=0)
    one = plots([BASE])
    core.push("a", 1.0, one)
    assert [t for t, _ in core.push("a", 5.0, one)] == [1.0]
    # b reports 3 after a reported 5: scan 3 can never be completed by a, emit now
    out = core.push("b", 3.0, one)
    assert [t for t, _ in out] == [3.0] and out[0][1].n_ch.tolist() == [1]


def test_components_as_scipy() -> None:
    """plots.channel_fusion.components labels every node as scipy's connected_components does
    (numbering by smallest node), on random graphs with loops and repeated edges."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(2)
    for _ in range(500):
        n = int(rng.integers(1, 60))
        e = int(rng.integers(0, 2 * n))
        a, b = rng.integers(0, n, e), rng.integers(0, n, e)
        _, ref = connected_components(coo_matrix((np.ones(e), (a, b)), shape=(n, n)),
                                      directed=False)
        np.testing.assert_array_equal(components(n, a, b), ref)
