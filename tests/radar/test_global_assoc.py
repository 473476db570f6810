"""Tests of module 63 (common.radar.fusion.assoc): g [47] Jacobian, distance [48], the
per-component gate, the two-best-candidates resolution loop."""

from __future__ import annotations

import numpy as np
import pytest

from common.radar.fusion.assoc import (
    ETrackSet,
    component_gamma,
    component_gate,
    distance,
    gated_component_pairs,
    gated_pairs,
    projections,
    resolve,
)
from common.radar.geometry.bistatic import project, project_jacobian

TX = np.array([-35000.0, 20000.0, 300.0])
RX = np.array([0.0, 0.0, 30.0])


def test_g_jacobian_finite_differences() -> None:
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(-6e4, 6e4, 20), rng.uniform(-250, 250, 20),
                         rng.uniform(-6e4, 6e4, 20), rng.uniform(-250, 250, 20),
                         rng.uniform(1e3, 1.2e4, 20), rng.uniform(-20, 20, 20)])
    G = project_jacobian(x, TX, RX)
    step = np.array([1.0, 1e-3, 1.0, 1e-3, 1.0, 1e-3])
    for j in range(6):
        dx = np.zeros(6)
        dx[j] = step[j]
        num = (project(x + dx, TX, RX) - project(x - dx, TX, RX)) / (2 * step[j])
        np.testing.assert_allclose(G[:, :, j], num, rtol=1e-5, atol=1e-8)


def test_distance_is_48() -> None:
    x = np.array([[-30000.0, 200.0, 50000.0, -50.0, 9000.0, 0.0]])
    P = np.diag([1e4, 25.0, 1e4, 25.0, 4e4, 1.0])[None]
    y_pred, GPG = projections(x, P, TX, RX)
    G = project_jacobian(x, TX, RX)[0]
    np.testing.assert_allclose(GPG[0], G @ P[0] @ G.T)
    R = np.diag([50.0**2, 1.0, np.radians(0.5) ** 2])[None]
    y = y_pred + np.array([[100.0, -2.0, np.radians(0.3)]])
    v = y[0] - y_pred[0]
    expect = v @ np.linalg.solve(GPG[0] + R[0], v)  # [48]
    assert distance(y_pred, GPG, y, R)[0] == pytest.approx(expect)
    # the azimuth residual is wrapped: 2 pi away is the same measurement
    y2 = y.copy()
    y2[0, 2] += 2 * np.pi
    assert distance(y_pred, GPG, y2, R)[0] == pytest.approx(expect)


def _etracks(y: np.ndarray, R: np.ndarray) -> ETrackSet:
    n = y.shape[0]
    ones, zeros = np.ones(n, dtype=bool), np.zeros(n, dtype=bool)
    return ETrackSet(np.zeros(n, dtype=np.intp), np.arange(n), y, R, np.zeros(n), ones, ones,
                     zeros, y, R, ones)


def test_component_gate_passes_when_one_live_component_passes() -> None:
    """A high, close target (truth z 11.1 km) held by two altitude bands, 3.8 km (mass
    0.99) and 11 km (0.01): its elementary track fails [48] against the mixture's
    moments (mean z 3.9 km) but passes against the 11 km band; a dead band (mass 0)
    does not count; gamma is the best band's."""
    truth = np.array([6000.0, 70.0, -31000.0, 150.0, 11100.0, 0.0])
    y_true = project(truth[None], TX, RX)
    R = np.diag([150.0**2, 1.5**2, np.radians(1.0) ** 2])[None]
    xb = np.array([[[6100.0, 70.0, -31200.0, 150.0, 3800.0, 0.0],
                    [6050.0, 70.0, -31100.0, 150.0, 11000.0, 0.0],
                    [0.0] * 6]])
    Pb = np.repeat(np.diag([200.0**2, 20.0**2, 200.0**2, 20.0**2, 600.0**2, 5.0**2])[None, None],
                   3, axis=1)
    mass = np.array([[0.99, 0.01, 0.0]])
    E = _etracks(y_true, R)
    mean = (mass[0, :, None] * xb[0]).sum(axis=0)[None]
    spread = xb[0, :2] - mean
    P_mix = (mass[0, :2, None, None] * (Pb[0, :2] + spread[:, :, None] * spread[:, None, :])).sum(0)
    assert mean[0, 4] == pytest.approx(3872.0)
    gamma_max = 16.3  # chi-square(3) at 0.999
    i, m, g = gated_pairs(mean, P_mix[None], np.array([0]), np.array([0]), E, TX, RX, np.pi,
                          gamma_max)
    assert i.size == 0  # the mixture's single Gaussian rejects it
    i, m, g = gated_component_pairs(mass, xb, Pb, np.array([0]), np.array([0]), E, TX, RX,
                                    np.pi, gamma_max)
    y2, S2 = projections(xb[0, 1:2], Pb[0, 1:2], TX, RX)
    assert (i.tolist(), m.tolist()) == ([0], [0])
    assert g[0] == pytest.approx(distance(y2, S2, y_true, R)[0])
    mass[0, 1] = 0.0  # the 11 km band pruned: nothing left to pass
    assert gated_component_pairs(mass, xb, Pb, np.array([0]), np.array([0]), E, TX, RX, np.pi,
                                 gamma_max)[0].size == 0


def test_resolution_loop_two_candidates() -> None:
    # global track 10 sees etracks 1 (best) and 2; global track 11 is closer to 1.
    # 10 has p1 = 1, p2 = 2 and n_inv = 11 exists -> 10 takes 2 (p1-10 invalidated);
    # then 11 takes 1.
    i = np.array([10, 10, 11])
    m = np.array([1, 2, 1])
    g = np.array([1.0, 2.0, 0.5])
    ti, mi = resolve(i, m, g)
    assert dict(zip(ti.tolist(), mi.tolist())) == {10: 2, 11: 1}
    # without the competing global track, 10 keeps its most likely p1
    ti, mi = resolve(i[:2], m[:2], g[:2])
    assert dict(zip(ti.tolist(), mi.tolist())) == {10: 1}
    # p1 only (no p2): associated even though 11 likes it more, as written
    ti, mi = resolve(np.array([10, 11]), np.array([1, 1]), np.array([1.0, 0.5]))
    assert dict(zip(ti.tolist(), mi.tolist())) == {10: 1}


def _sequential(i: np.ndarray, m: np.ndarray, g: np.ndarray) -> dict[int, int]:
    """The seed's loop literally, one global track after the other."""
    G: dict[int, dict[int, float]] = {}
    for a, b, c in zip(i.tolist(), m.tolist(), g.tolist()):
        G.setdefault(a, {})[b] = c
    taken: set[int] = set()
    out = {}
    for a in sorted(G):
        cand = sorted((c, b) for b, c in G[a].items() if b not in taken)
        if not cand:
            continue
        p1 = cand[0][1]
        choice = p1
        if len(cand) > 1:
            n_inv = any(G[n].get(p1, np.inf) < G[a][p1] for n in G if n != a)
            choice = cand[1][1] if n_inv else p1
        out[a] = choice
        taken.add(choice)
    return out


def test_resolution_loop_vectorised_equals_sequential() -> None:
    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(1, 60))
        i = rng.integers(0, 15, n)
        m = rng.integers(0, 15, n)
        _, keep = np.unique(i * 100 + m, return_index=True)
        i, m = i[keep], m[keep]
        g = rng.uniform(0, 10, i.size)
        ti, mi = resolve(i, m, g)
        assert dict(zip(ti.tolist(), mi.tolist())) == _sequential(i, m, g)
        assert len(set(mi.tolist())) == mi.size  # one global track per elementary track


def test_component_gate_is_smallest_component_gamma_gated() -> None:
    """component_gate (heaviest components first) answers exactly component_gamma <=
    gamma_max on random mixtures around random targets, near and far from the gate,
    with ties of weights and dead components, per-pair geometry."""
    rng = np.random.default_rng(7)
    n, K = 4000, 6
    tx = rng.uniform(-4e4, 4e4, (n, 3)) * [1, 1, 0]
    rx = np.zeros((n, 3))
    truth = np.concatenate([rng.uniform(-6e4, 6e4, (n, 1)), rng.normal(0, 200, (n, 1)),
                            rng.uniform(-6e4, 6e4, (n, 1)), rng.normal(0, 200, (n, 1)),
                            rng.uniform(300, 1e4, (n, 1)), np.zeros((n, 1))], axis=1)
    xc = truth[:, None, :] + rng.normal(0, 1, (n, K, 6)) * [800, 40, 800, 40, 2000, 5]
    Pc = np.tile(np.diag([300.0, 20.0, 300.0, 20.0, 1000.0, 3.0]) ** 2, (n, K, 1, 1))
    w = rng.choice([0.0, 0.1, 0.25, 0.5], (n, K))
    w[:, 0] += 1e-3 * (rng.random(n) < 0.5)
    w[rng.random(n) < 0.02] = 0.0  # no live component: gamma inf
    R = np.tile(np.diag([100.0, 5.0, 0.01]) ** 2, (n, 1, 1))
    y = project(truth, tx, rx) + rng.normal(0, 1, (n, 3)) * [100.0, 5.0, 0.01]
    gam = component_gamma(w, xc, Pc, y, R, tx, rx)
    gamma_max = float(np.median(gam[np.isfinite(gam)]))
    ok = component_gate(w, xc, Pc, y, R, tx, rx, gamma_max)
    assert 0.2 < ok.mean() < 0.8 and np.isinf(gam).any()
    np.testing.assert_array_equal(ok, gam <= gamma_max)
