"""Ambiguous memberships of global tracks (common.radar.fusion.assoc.ambiguous_members):
two tracks whose elementary tracks of one base pass [48] against each other's track do
not use that base's measurements this scan (dense1000.toml: the swapped elementary
tracks of two aircraft 540 m apart pulled both tracks' altitudes 0.6-1.1 km off)."""

from __future__ import annotations

import numpy as np

from common.core.gating import chi2_gate
from common.radar.fusion.assoc import ETrackSet, ambiguous_members
from common.radar.geometry.bistatic import project

GAMMA = chi2_gate(0.999, 3)
SWAP = chi2_gate(0.999, 1)
AZ = np.radians(3.0)
RX = np.zeros((4, 3)) + [0.0, 0.0, 30.0]
TX = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0],
               [5000.0, -52000.0, 400.0], [-22000.0, -18000.0, 250.0]])
A = np.array([38700.0, 165.0, 13430.0, -2.0, 1156.0, 0.0])
B = A + [-520.0, -10.0, -270.0, 10.0, 1680.0, 0.0]
FAR = A + [-20000.0, 0.0, 15000.0, 0.0, 0.0, 0.0]
R1 = np.diag([30.0**2, 1.0**2, np.radians(0.3) ** 2])


def _table(states: np.ndarray, sigma_pos: np.ndarray, sigma_vel: np.ndarray
           ) -> tuple[ETrackSet, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Track k holds the elementary track of its own state at each of the four bases:
    (E, row (n, 4), mixture weights (n, 1), means (n, 1, 6), covariances (n, 1, 6, 6))."""
    n = states.shape[0]
    bases = np.tile(np.arange(4), n)
    y = np.array([project(states[k // 4][None], TX[b], RX[b])[0] for k, b in enumerate(bases)])
    R = np.tile(R1, (4 * n, 1, 1))
    ones, zeros = np.ones(4 * n, dtype=bool), np.zeros(4 * n, dtype=bool)
    E = ETrackSet(bases, np.arange(4 * n), y, R, np.ones(4 * n), ones, ones, zeros, y, R, ones)
    row = np.arange(4 * n).reshape(n, 4)
    P = np.array([np.diag([p**2, v**2, p**2, v**2, p**2, v**2])
                  for p, v in zip(sigma_pos, sigma_vel)])
    return E, row, np.ones((n, 1)), states[:, None], P[:, None]


def test_two_young_tracks_of_close_aircraft_are_ambiguous_at_every_base() -> None:
    """Just after initialisation (sigma 1 km, 100 m/s) each aircraft's elementary tracks
    pass [48] against the other's track at every base: no base is used by either; a
    third track far away keeps its bases."""
    states = np.stack([A, B, FAR])
    E, row, w, xc, Pc = _table(states, np.array([1000.0] * 3), np.array([100.0] * 3))
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.arange(3), E, TX, RX, AZ,
                            GAMMA, SWAP)
    assert amb[:2].all() and not amb[2].any()


def test_settled_tracks_of_the_same_aircraft_pair_are_not_ambiguous() -> None:
    """The same pair once the tracks are settled (sigma 50 m, 3 m/s): each elementary
    track fails [48] against the other aircraft's track at every base, nothing is
    withheld."""
    E, row, w, xc, Pc = _table(np.stack([A, B]), np.array([50.0, 50.0]), np.array([3.0, 3.0]))
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.arange(2), E, TX, RX, AZ,
                            GAMMA, SWAP)
    assert not amb.any()


def test_one_way_gating_is_not_ambiguous() -> None:
    """Only the young track gates the settled track's elementary tracks (not the
    reverse): the settled track's measurements decide, nothing is withheld; and a
    track outside `tracks` (e.g. born this scan) is never marked."""
    E, row, w, xc, Pc = _table(np.stack([A, B]), np.array([1000.0, 50.0]), np.array([100.0, 3.0]))
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.arange(2), E, TX, RX, AZ,
                            GAMMA, SWAP)
    assert not amb.any()
    E, row, w, xc, Pc = _table(np.stack([A, B]), np.array([1000.0] * 2), np.array([100.0] * 2))
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.array([0]), E, TX, RX, AZ,
                            GAMMA, SWAP)
    assert not amb.any()


def test_a_pairing_the_data_prefer_clearly_is_not_ambiguous() -> None:
    """Sigma 150 m, 5 m/s: each elementary track passes [48] against the other track at
    every base (gamma 5-14), but only at base 1 is the swapped pairing within the
    chi-square(1) quantile of the held one (gamma sum 9.9 against 0); at bases 0, 2
    and 3 (sums 23-28) the held pairing is kept and used (crossing.toml: settled
    tracks crossing)."""
    E, row, w, xc, Pc = _table(np.stack([A, B]), np.array([150.0, 150.0]), np.array([5.0, 5.0]))
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.arange(2), E, TX, RX, AZ,
                            GAMMA, SWAP)
    assert amb.tolist() == [[False, True, False, False]] * 2
    amb = ambiguous_members(w, xc, Pc, xc[:, 0], Pc[:, 0], row, np.arange(2), E, TX, RX, AZ,
                            GAMMA, np.inf)
    assert amb.all()
