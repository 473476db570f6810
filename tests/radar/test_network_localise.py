"""common.radar.network.localise, per equation: [GN] exact noiseless recovery (also with
no two bases sharing a receiver), [FIM] against the Monte-Carlo spread (NEES ~ 6) and
the residual chi-square (~ 2K - 6), a degenerate geometry reported as such."""

from __future__ import annotations

import numpy as np

from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate
from common.radar.network.localise import localise

SEEDS = np.array([[x, y, z] for x in (-40e3, 40e3) for y in (-40e3, 40e3) for z in (3e3, 10e3)])


def _problem(tx: np.ndarray, rx: np.ndarray, pos: np.ndarray, vel: np.ndarray,
             sig: np.ndarray) -> tuple[np.ndarray, ...]:
    n, k = pos.shape[0], tx.shape[0]
    z = np.stack([np.stack([bistatic_range(pos, tx[i], rx[i]),
                            bistatic_range_rate(pos, vel, tx[i], rx[i])], -1) for i in range(k)], 1)
    R = np.broadcast_to(np.diag(sig ** 2), (n, k, 2, 2)).copy()
    return (z, R, np.broadcast_to(tx, (n, k, 3)).copy(), np.broadcast_to(rx, (n, k, 3)).copy(),
            np.ones((n, k), dtype=bool))


def _targets(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    pos = np.column_stack([rng.uniform(-50e3, 50e3, (n, 2)), rng.uniform(1e3, 12e3, n)])
    return pos, rng.normal(0, 150, (n, 3)) * [1, 1, 0.05]


RX = np.array([[-50e3, -40e3, 200.0], [45e3, -35e3, 50.0], [0.0, 55e3, 400.0]])
TX = np.array([[-20e3, -60e3, 300.0], [70e3, 0.0, 500.0], [30e3, 60e3, 100.0],
               [-60e3, 20e3, 250.0], [10e3, -10e3, 600.0]])
SHARED_RX = RX[[0, 0, 1, 1, 2]]  # five bases, three receivers


def test_noiseless_recovery() -> None:
    pos, vel = _targets(np.random.default_rng(0), 300)
    f = localise(*_problem(TX, SHARED_RX, pos, vel, np.array([300.0, 1.0])), SEEDS, (0, 20e3), 10e3)
    assert f.ok.sum() >= 295 and (f.ok | f.degenerate).all()  # z sigma > 10 km near the ground
    np.testing.assert_allclose(f.x[:, [0, 2, 4]], pos, atol=1e-3)
    np.testing.assert_allclose(f.x[:, [1, 3, 5]], vel, atol=1e-6)


def test_no_two_bases_share_a_receiver() -> None:
    rx = np.array([[-50e3, -40e3, 200.0], [45e3, -35e3, 50.0], [0.0, 55e3, 400.0],
                   [-40e3, 40e3, 300.0]])
    pos, vel = _targets(np.random.default_rng(1), 200)
    f = localise(*_problem(TX[:4], rx, pos, vel, np.array([30.0, 0.5])), SEEDS, (0, 20e3), 10e3)
    assert f.ok.mean() > 0.97  # a few targets sit where four ranges fix z poorly
    good = f.ok
    np.testing.assert_allclose(f.x[good][:, [0, 2, 4]], pos[good], atol=1e-3)


def test_covariance_matches_monte_carlo() -> None:
    rng = np.random.default_rng(2)
    pos0 = np.array([[10e3, 5e3, 8e3]])
    vel0 = np.array([[180.0, -60.0, 0.0]])
    sig = np.array([300.0, 1.0])
    n = 2000
    z, R, tx, rx, valid = _problem(TX, SHARED_RX, np.repeat(pos0, n, 0), np.repeat(vel0, n, 0), sig)
    z = z + rng.standard_normal(z.shape) * sig
    f = localise(z, R, tx, rx, valid, SEEDS, (0, 20e3), 10e3)
    assert f.ok.all()
    e = f.x - np.array([pos0[0, 0], vel0[0, 0], pos0[0, 1], vel0[0, 1], pos0[0, 2], vel0[0, 2]])
    nees = np.einsum("ni,ni->n", e, np.linalg.solve(f.P, e[..., None])[..., 0])
    assert abs(nees.mean() - 6.0) < 0.4, nees.mean()  # 3 sigma of the mean of chi2(6): 0.16
    assert abs(f.chi2.mean() - (2 * 5 - 6)) < 0.4, f.chi2.mean()


def test_degenerate_geometry_is_reported() -> None:
    line = np.array([[-60e3, 0, 0], [-20e3, 0, 0], [20e3, 0, 0], [60e3, 0, 0]], dtype=float)
    rx = line[[0, 0, 3, 3]]
    tx = line[[1, 2, 1, 2]]
    pos, vel = np.array([[5e3, 20e3, 6e3]]), np.array([[100.0, 50.0, 0.0]])
    f = localise(*_problem(tx, rx, pos, vel, np.array([30.0, 0.5])), SEEDS, (0, 20e3), 10e3)
    assert f.degenerate.all() and not f.ok.any()  # every site on one line: rotation about it
