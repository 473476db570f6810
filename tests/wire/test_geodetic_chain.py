"""A geodetic deployment end to end in one process (issue 29): scenarios/geodetic_two_targets.toml
through common.wire.radar_chain; confirmed global tracks against the simulator's truth,
and the published lat, lon, alt against the truth's WGS-84 position."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from common.deploy.config import load
from common.sim.scenario import load_scenario
from common.wire import protocol
from common.wire.radar_chain import RadarChain
from common.wire.sim_messages import run_scenario

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "geodetic_two_targets.toml"
XYZ = [0, 2, 4]
EARTH_R = 6371e3


def _run(seed: int) -> list[tuple[dict[str, Any], np.ndarray]]:
    """(confirmed track as decoded from the wire, the nearest truth ENU position) per
    cycle and confirmed track."""
    cfg = load(SCENARIO)
    chain, out = RadarChain(cfg), []
    truth: dict[float, dict[str, Any]] = {}
    for t, msgs in run_scenario(load_scenario(cfg.doc), cfg.bases, cfg.arrays, seed):
        truth[t] = next(m for k, m in msgs if k == "sim/truth/radar")
        for g in chain.step(msgs):
            g = protocol.decode("gtracks", protocol.encode(g))
            tr = truth[g["t"]]
            pos = np.c_[tr["x"], tr["y"], tr["z"]]
            for track in g["tracks"]:
                if track["status"] == "confirmed":
                    near = pos[np.argmin(np.linalg.norm(pos - track["x"][XYZ], axis=1))]
                    out.append((track, near))
    return out


@pytest.fixture(scope="module", params=[1, 2])
def confirmed(request: pytest.FixtureRequest) -> list[tuple[dict[str, Any], np.ndarray]]:
    return _run(request.param)


def test_the_scenario_spans_more_than_150_km() -> None:
    cfg = load(SCENARIO)
    assert cfg.origin is not None
    sites = np.array([b.tx for b in cfg.bases] + [cfg.bases[0].rx])
    span = max(np.linalg.norm(a[:2] - b[:2]) for a in sites for b in sites)
    assert span > 150e3


def test_confirmed_tracks_follow_the_truth_within_their_sigma(confirmed: list) -> None:
    assert len(confirmed) > 2 * 100  # both aircraft confirmed for most of the 120 scans
    nees = []
    for track, truth in confirmed:
        P = track["P"].reshape(6, 6)[np.ix_(XYZ, XYZ)]
        e = track["x"][XYZ] - truth
        assert np.all(np.abs(e) < 4.0 * np.sqrt(np.diag(P))), (track["id"], e, np.diag(P))
        nees.append(e @ np.linalg.solve(P, e))
    assert np.mean(nees) < 6.0  # 3 for a consistent 3-D estimate


def test_published_lat_lon_alt_match_the_truths_geodetic_position(confirmed: list) -> None:
    frame = load(SCENARIO).origin
    assert frame is not None
    for track, truth in confirmed:
        lat, lon, alt = frame.to_geodetic(truth)
        np.testing.assert_allclose([track["lat"], track["lon"], track["alt"]],
                                   frame.to_geodetic(track["x"][XYZ]), rtol=0, atol=1e-9)
        s = np.sqrt(np.diag(track["P"].reshape(6, 6)))[XYZ]
        north = np.radians(track["lat"] - lat) * EARTH_R
        east = np.radians(track["lon"] - lon) * EARTH_R * np.cos(np.radians(lat))
        assert np.hypot(east, north) < 4.0 * np.hypot(s[0], s[1])
        assert abs(track["alt"] - alt) < 4.0 * s[2]
    # the aircraft fly at constant ellipsoidal height: the truth says so too
    heights = {round(float(frame.to_geodetic(t)[2]), 3) for _, t in confirmed}
    assert heights <= {10500.0, 8500.0}
