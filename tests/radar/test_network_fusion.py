"""NetworkFusion on the synthetic network of tests/radar/network_scene.py (>= 8
receivers, >= 20 bases over ~150 km, range-Doppler only, unsynchronised, pd 0.9,
elementary reports from per-base Kalman filters on simulated plots), seeds 1-3.

After a 15 s warm-up, at every global report: every aircraft held by exactly one
confirmed track (within 2 km), no confirmed track farther than 2 km from every
aircraft, per-aircraft position RMSE <= 1.3 x the rms of its single-snapshot CRLB (one
report of every base, `crlb_position`). Ghost scene: 24 aircraft on a line across the
network, confirmed false tracks < 1 % of the aircraft per report."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from common.core.rejection import Rejected
from common.core.track_table import Status
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.network.fusion import NetworkFusion, NetworkReport
from tests.radar import network_scene as ns


@functools.lru_cache(maxsize=None)
def run(seed: int, kind: str = "random", clock: float = 0.0, duration: float = 45.0
        ) -> tuple[ns.Scene, list[NetworkReport], NetworkFusion]:
    """The scene of `seed`; clock offsets uniform in +-clock from their own generator
    (the same aircraft and noise as without)."""
    rng = np.random.default_rng(seed)
    bases = ns.network(rng)
    if clock:
        off = np.random.default_rng(seed + 1000).uniform(-clock, clock, len(bases))
        bases = [dataclasses.replace(b, clock=float(c)) for b, c in zip(bases, off)]
    p0, v = ns.aircraft(rng, 20) if kind == "random" else ns.line(24)
    scene = ns.simulate(rng, bases, p0, v, duration)
    fusion = NetworkFusion(bases)
    out: list[NetworkReport] = []
    for b, t, rep in scene.reports:
        out += fusion.push(bases[b].id, t, rep)
    return scene, out + fusion.flush(), fusion


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_aircraft_held_accurately(seed: int) -> None:
    scene, reports, fusion = run(seed)
    assert len(scene.bases) >= 20 and len({tuple(b.rx) for b in scene.bases}) >= 8
    s = ns.score(scene, reports)
    assert s.scans >= 25 and fusion.rejected == {}
    assert (s.missed, s.duplicates, s.false) == (0, 0, 0)
    ratio = np.sqrt(s.err2 / s.crlb2)
    assert ratio.max() <= 1.3, ratio
    assert 1.0 < s.nees < 6.0, s.nees


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_ghost_line(seed: int) -> None:
    scene, reports, _ = run(seed, "line")
    s = ns.score(scene, reports)
    assert s.false < 0.01 * 24 * s.scans
    assert s.missed == 0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_clock_offsets_up_to_0_2_s(seed: int) -> None:
    """Node clocks off by up to 0.2 s, estimated per base (common.radar.network.clocks):
    every aircraft held, no false track, the offsets of the DVB-T bases (30 m) found to
    within 0.05 s up to their common part (unobservable). Not asserted: NEES and RMSE
    against the run without offsets (not met, docs/networks.md)."""
    scene, reports, fusion = run(seed, clock=0.2)
    s = ns.score(scene, reports)
    assert (s.missed, s.duplicates, s.false) == (0, 0, 0)
    off = np.array([b.clock for b in scene.bases])
    est = fusion.clocks.c
    err = (est - est.mean()) - (off - off.mean())
    fine = np.array([b.sigma_r for b in scene.bases]) <= ns.DVBT[0]
    assert np.abs(err[fine]).max() < 0.05, err


def test_reordering_window() -> None:
    rng = np.random.default_rng(5)
    bases = ns.network(rng)
    p0, v = ns.aircraft(rng, 3)
    scene = ns.simulate(rng, bases, p0, v, 12.0, latency=1.5)  # out of order within 2 s
    fusion = NetworkFusion(bases)
    times = []
    for b, t, rep in scene.reports:
        times += [r.t for r in fusion.push(bases[b].id, t, rep)]
    assert fusion.rejected == {} and times == sorted(times)
    b, t, rep = scene.reports[0]
    with pytest.raises(Rejected) as err:
        fusion.push(bases[b].id, t, rep)
    assert err.value.reason == "too_late" and fusion.rejected == {"too_late": 1}


def test_five_state_reports_accepted() -> None:
    bases = ns.network(np.random.default_rng(6))
    fusion = NetworkFusion(bases)
    x = np.array([[60e3, -100.0, 0.0, 1.0, 0.0]])
    rep = ElementaryTracks(0.0, np.array([1]), np.array([Status.CONFIRMED]), x,
                           np.diag([1e4, 1.0, 1.0, 1e-4, 1e-6])[None], np.zeros(1),
                           np.ones(1, dtype=np.int64), np.array([True]), np.array([False]))
    fusion.push(bases[0].id, 0.0, rep)
    assert fusion.flush()[0].x.shape == (0, 6)
    assert fusion.dec.last[0][2].shape == (1, 5)
    with pytest.raises(Rejected):
        fusion.push(bases[0].id, 1.0, dataclasses.replace(rep, x=x[:, :4]))


KNOWN_GHOSTS = pytest.mark.xfail(strict=True, reason="a false track at 5 % of the aircraft per "
                                 "report (docs/networks.md, Limits): a fix makes this fail")


FLIPPED = pytest.mark.xfail(strict=True, reason="false tracks at 1.8 % of the aircraft per report since the "
                            "common clock offset is not applied (0.5 % before; docs/decisions/024-network-altitude.md)")


@pytest.mark.parametrize("seed", [pytest.param(1, marks=KNOWN_GHOSTS), pytest.param(2, marks=KNOWN_GHOSTS),
                                  pytest.param(3, marks=FLIPPED)])
def test_ghost_formation(seed: int) -> None:
    """20 aircraft within 2 km between 4 receivers: confirmed false tracks (farther than
    2 km from every aircraft) < 1 % of the aircraft per report."""
    rng = np.random.default_rng(seed)
    bases = ns.network(rng, n_rx=4, span=100e3)
    p0, v = ns.formation(rng, 20)
    scene = ns.simulate(rng, bases, p0, v, 45.0)
    fusion = NetworkFusion(bases)
    out: list[NetworkReport] = []
    for b, t, rep in scene.reports:
        out += fusion.push(bases[b].id, t, rep)
    s = ns.score(scene, out + fusion.flush())
    assert s.false < 0.01 * 20 * s.scans


def test_radar_network_table_reaches_the_core() -> None:
    """[radar.network] of a deployment file sets the network core's parameters (a list
    becomes the tuple seed_z); the decorrelation takes [radar.tracker]'s Q [20]."""
    from common.deploy.config import parse
    from common.wire.radar_chain import global_fusion

    bases = ns.network(np.random.default_rng(3))
    doc = {"radar": {"base": [{"id": b.id, "tx": list(b.tx), "rx": list(b.rx), "channels": ["c"],
                               "azimuth": False} for b in bases],
                     "network": {"init_bases": 4, "seed_z": [2000.0], "window": 0.5},
                     "tracker": {"sigma_gamma": 7.0}}}
    core = global_fusion(parse(doc))
    fusion = core.core  # type: ignore[attr-defined]
    assert (fusion.p.init_bases, fusion.p.seed_z, fusion.p.window) == (4, (2000.0,), 0.5)
    assert fusion.sigma_gamma == 7.0


def test_reference_clocks_are_trusted_and_unknown_ones_refused() -> None:
    """[radar.network] clock_reference: a reference base's offset stays 0 and adds nothing
    to R ([C3]); the others are estimated; a name that is no base is refused."""
    from common.radar.network.clocks import Clocks
    from common.radar.network.params import NetworkParams

    clocks = Clocks(2, 0.1, 1e-6, np.array([True, False]))
    v, y, S = np.array([200.0, -150.0]), np.array([8.0, -6.0]), np.array([25.0, 25.0])
    for b in (0, 1):
        clocks.update(b, 1.0, v, y, S)
    assert clocks.c[0] == 0.0 and clocks.V[0] == 0.0 and clocks.c[1] != 0.0
    z, R = np.array([[1e5, 200.0]]), np.diag([25.0, 1.0])[None]
    assert clocks.correct(0, z, R)[1][0, 0, 0] == 25.0
    assert clocks.correct(1, z, R)[1][0, 0, 0] > 25.0
    bases = ns.network(np.random.default_rng(3))
    fusion = NetworkFusion(bases, NetworkParams(clock_reference=(bases[2].id,)))
    assert np.flatnonzero(fusion.clocks.reference).tolist() == [2]
    with pytest.raises(ValueError, match="nobase"):
        NetworkFusion(bases, NetworkParams(clock_reference=("nobase",)))


def test_applied_offsets_have_mean_zero_without_a_reference() -> None:
    """[C4]: without a reference base the common part of the estimates (unobservable) is
    not applied: the offsets applied to the reports have mean 0; with a reference every
    estimate is applied as it is."""
    from common.radar.network.clocks import Clocks

    v, S = np.array([200.0, -150.0, 90.0]), np.full(3, 25.0)
    for reference in (np.zeros(3, dtype=bool), np.array([True, False, False])):
        clocks = Clocks(3, 0.1, 1e-6, reference)
        for b, y in ((0, 8.0), (1, 5.0), (2, 3.0)):
            clocks.update(b, 1.0, v, np.full(3, y), S)
        applied = np.array([clocks.applied(b) for b in range(3)])
        z, R = np.array([[1e5, 200.0]]), np.diag([25.0, 1.0])[None]
        shifted = np.array([clocks.correct(b, z, R)[0][0, 0] for b in range(3)]) - 1e5
        assert np.allclose(shifted, 200.0 * applied)
        if reference.any():
            assert np.array_equal(applied, clocks.c)
        else:
            assert abs(applied.sum()) < 1e-12 and abs(clocks.c.sum()) > 1e-3
