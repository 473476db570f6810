"""common.radar.fusion.merge: duplicate global tracks (disjoint bases, positions within
the gate) are paired closest first; tracks sharing a base never are."""

from __future__ import annotations

import numpy as np

from common.core.gating import chi2_gate
from common.radar.fusion.merge import duplicate_pairs

GAMMA = chi2_gate(0.999, 3)


def _has(*sets: tuple[int, ...]) -> np.ndarray:
    h = np.zeros((len(sets), 4), dtype=bool)
    for k, s in enumerate(sets):
        h[k, list(s)] = True
    return h


def test_disjoint_close_tracks_pair_and_shared_bases_do_not() -> None:
    pos = np.array([[0.0, 0.0, 5000.0], [300.0, 0.0, 5000.0], [0.0, 200.0, 5000.0],
                    [50e3, 0.0, 5000.0]])
    cov = np.tile(np.eye(3) * 500.0**2, (4, 1, 1))
    i, j = duplicate_pairs(pos, cov, _has((0, 1), (2, 3), (0, 2, 3), (2, 3)), GAMMA)
    assert list(zip(i, j)) == [(0, 1)]  # 2 shares bases with 0 and 1; 3 is 50 km away
    i, j = duplicate_pairs(pos, cov, _has((0, 1), (0, 3), (0, 2, 3), (1,)), GAMMA)
    assert i.size == 0  # every close pair shares base 0


def test_gate_uses_both_covariances_and_closest_pair_wins() -> None:
    pos = np.array([[0.0, 0.0, 5000.0], [3000.0, 0.0, 5000.0], [200.0, 0.0, 5000.0]])
    tight = np.tile(np.eye(3) * 200.0**2, (3, 1, 1))
    assert duplicate_pairs(pos[:2], tight[:2], _has((0, 1), (2, 3)), GAMMA)[0].size == 0
    wide = tight.copy()
    wide[1] = np.eye(3) * 2500.0**2  # an uncertain new track: 3 km is within its gate
    i, j = duplicate_pairs(pos[:2], wide[:2], _has((0, 1), (2, 3)), GAMMA)
    assert list(zip(i, j)) == [(0, 1)]
    # track 0 could merge with 1 (d^2 1.4) or 2 (d^2 0.5): 2 wins, 1 then has no partner
    i, j = duplicate_pairs(pos, wide, _has((0, 1), (2, 3), (2, 3)), GAMMA)
    assert list(zip(i, j)) == [(0, 2)]


def test_empty_tracks_and_random_superset() -> None:
    rng = np.random.default_rng(1)
    n = 200
    pos = rng.uniform(-20e3, 20e3, (n, 3))
    A = rng.standard_normal((n, 3, 3)) * 800.0
    cov = A @ np.swapaxes(A, 1, 2) + np.eye(3)
    has = rng.uniform(size=(n, 4)) < 0.4
    i, j = duplicate_pairs(pos, cov, has, GAMMA)
    # brute force over all pairs: the KD-tree search radius misses none
    a, b = np.triu_indices(n, 1)
    d = pos[a] - pos[b]
    d2 = np.einsum("pi,pi->p", d, np.linalg.solve(cov[a] + cov[b], d[..., None])[..., 0])
    ok = (d2 <= GAMMA) & (has[a].any(1) | has[b].any(1)) & ~(has[a] & has[b]).any(1)
    paired = set(i.tolist()) | set(j.tolist())
    assert all(a[p] in paired or b[p] in paired for p in np.flatnonzero(ok))  # maximal
    assert {(x, y) for x, y in zip(i, j)} <= set(zip(a[ok].tolist(), b[ok].tolist()))
    assert len(paired) == 2 * i.size
    assert duplicate_pairs(pos[:1], cov[:1], has[:1], GAMMA)[0].size == 0


def test_a_coasting_track_pairs_with_the_track_that_took_its_target() -> None:
    """A track without contributors (coasting: dense1000.toml seed 2, aircraft 380 near
    the receiver lost every elementary track for 2 scans, its track's prediction stayed
    within 20 m) pairs with a track holding that target's new elementary tracks; two
    tracks without contributors do not."""
    pos = np.array([[0.0, 0.0, 5000.0], [40.0, -20.0, 5050.0]])
    cov = np.tile(np.eye(3) * 30.0**2, (2, 1, 1))
    i, j = duplicate_pairs(pos, cov, _has((), (0, 1, 2)), GAMMA)
    assert list(zip(i, j)) == [(0, 1)]
    assert duplicate_pairs(pos, cov, _has((), ()), GAMMA)[0].size == 0


TRUTH = np.array([18000.0, 120.0, 30000.0, -150.0, 3000.0, 0.0])


def _two_tracks(offset: list[float]) -> tuple:
    """GlobalFusion over two bases with two tracks (slots 0 and 1) near TRUTH, slot 0
    at `offset` from it, slot 1 on it, both holding elementary tracks 4 and 5, and the
    elementary track set E of those two (TRUTH projected): (fusion, slots, E)."""
    from common.deploy.config import RadarBase
    from common.radar.fusion.assoc import ETrackSet
    from common.radar.fusion.cycle import GlobalFusion
    from common.radar.fusion.params import FusionParams
    from common.radar.geometry.bistatic import project

    rx = np.array([0.0, 0.0, 30.0])
    tx = np.array([[-35000.0, 20000.0, 300.0], [45000.0, 10000.0, 500.0]])
    gf = GlobalFusion([RadarBase(f"b{k}", tx[k], rx, ["c1"]) for k in range(2)], FusionParams())
    tab = gf.table
    slots = tab.add(2)
    P = np.diag([40.0**2, 5.0**2, 40.0**2, 5.0**2, 60.0**2, 2.0**2])
    tab.x[slots] = np.stack([TRUTH + offset, TRUTH])
    tab.P[slots] = P
    tab.xm[slots], tab.Pm[slots] = tab.x[slots][:, None], P
    tab.mu[slots] = np.eye(1, tab.mu.shape[1])
    tab.has[slots] = True
    tab.member[slots] = [4, 5]
    y = np.array([project(TRUTH[None], tx[k], rx)[0] for k in range(2)])
    R = np.tile(np.diag([40.0**2, 0.5**2, np.radians(0.3) ** 2]), (2, 1, 1))
    one, no = np.ones(2, dtype=bool), np.zeros(2, dtype=bool)
    E = ETrackSet(np.array([0, 1]), np.array([4, 5]), y, R, np.ones(2), one, one, no, y, R, one)
    return gf, slots, E


def _coasting_and_new(new_confirmed: bool, now: list[int]) -> tuple:
    """Module 61 (_manage) at t = 52 on a confirmed coasting track (slot 0, no
    contributors, born at 2 s) and a track holding the target's new elementary tracks
    (slot 1, born at 50 s, confirmed or not; `now`: the slots confirmed this cycle):
    (the table, the cycle's output)."""
    gf, slots, E = _two_tracks([30.0, 0.0, -20.0, 0.0, 40.0, 0.0])
    tab = gf.table
    tab.has[slots[0]] = False
    tab.confirmed[slots], tab.born[slots] = [True, new_confirmed], [2.0, 50.0]
    out = gf._manage(52.0, E, np.array([[-1, -1], [0, 1]]), np.array(now, dtype=np.intp))
    return tab, out


def test_the_track_with_contributors_is_kept_under_the_coasting_number() -> None:
    """A tentative new track: one track is left, with slot 1's state and elementary
    tracks, under the coasting track's number and birth time, tentative
    (fusion.merge.number_kept)."""
    tab, out = _coasting_and_new(False, [])
    assert out.id.tolist() == [tab.id[0]] and tab.born[0] == 2.0 and not tab.confirmed[0]
    np.testing.assert_array_equal(out.x[0], TRUTH)
    assert out.has[0].tolist() == [True, True] and out.member[0].tolist() == [4, 5]


def test_a_track_confirmed_this_cycle_takes_the_coasting_number_too() -> None:
    """Its own number was never published as confirmed (dense1000: the aircraft kept
    by the coasting number); a track confirmed in an earlier cycle keeps its own."""
    tab, out = _coasting_and_new(True, [1])
    assert out.id.tolist() == [tab.id[0]] and tab.born[0] == 2.0 and tab.confirmed[0]
    tab, out = _coasting_and_new(True, [])
    assert out.id.tolist() == [tab.id[1]] and tab.born[1] == 50.0


def _reconfirmed(published: bool) -> tuple:
    """Module 61 (_manage) on a track confirmed this cycle (slot 1, elementary tracks 4
    and 5) beside the held number of a removed confirmed track that had held them (slot
    0): `published`, the track's number was published as confirmed before (a merge kept
    it, tentative: number_kept). (the table, the cycle's output)."""
    gf, slots, E = _two_tracks([0.0] * 6)
    tab = gf.table
    tab.confirmed[slots], tab.born[slots] = True, [2.0, 3.0]
    tab.published[slots[1]] = published
    gf.succession.vacate(tab, slots[:1])
    tab.remove(slots[:1])
    out = gf._manage(60.0, E, np.array([[-1, -1], [0, 1]]), np.array([1]))
    return tab, out


def test_a_published_number_is_not_given_up_to_a_held_one() -> None:
    """dense1000 seed 16, aircraft 905: its track #530, merged at t = 59 with the track
    of its new elementary tracks (number_kept: tentative under 530), was confirmed again
    at t = 63 and then took the held number of a removed track that had held two of
    those elementary tracks. A number already published stays; a new one is replaced
    (common.radar.fusion.succession)."""
    tab, out = _reconfirmed(True)
    assert out.id.tolist() == [tab.first_id + 1]
    tab, out = _reconfirmed(False)
    assert out.id.tolist() == [tab.first_id] and tab.born[0] == 2.0
