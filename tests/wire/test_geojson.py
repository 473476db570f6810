"""GeoJSON of the global picture (common.wire.geojson, ``pfusion export --geojson``, the
view's /tracks.geojson), checked against RFC 7946 by tests/wire/geojson_rules.py, on
scenarios/geodetic_two_targets.toml (origin 47.0 N, 8.0 E, 450 m)."""

from __future__ import annotations

import asyncio
import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pymap3d
import pytest
from aiohttp.test_utils import TestClient, TestServer

from common.bus.recording import RecordWriter
from common.cli import main as cli_main
from common.deploy.config import load
from common.wire import protocol
from common.wire.geojson import RING, TrackHistory
from common.wire.view_model import ViewModel
from services.view.main import GEOJSON_PATH, geojson_route
from services.view.server import Hub, app
from tests.wire.geojson_rules import rfc7946_errors, signed_area

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "geodetic_two_targets.toml"
WGS84 = pymap3d.Ellipsoid.from_name("wgs84")


def _gtracks(t: float, x0: float) -> dict[str, Any]:
    """A gtracks message of two tracks; track 7 at (x0, 20 km, 9 km) with sigma 400 m
    East, 100 m North."""
    P = np.diag([400.0**2, 25.0, 100.0**2, 25.0, 300.0**2, 4.0]).ravel().tolist()
    return {"v": protocol.VERSION, "t": t, "tracks": [
        {"id": 7, "status": "confirmed", "x": [x0, 200.0, 20e3, 0.0, 9e3, 0.0], "P": P, "score": 12.5,
         "etracks": [["b1", 3], ["b2", 4]], "ambiguous": False},
        {"id": 8, "status": "tentative", "x": [-30e3, 0.0, -5e3, 100.0, 5e3, 0.0], "P": P, "score": 1.0,
         "etracks": [["b3", 1]], "ambiguous": True}]}


def _messages() -> list[dict[str, Any]]:
    return [protocol.decode("gtracks", protocol.encode(_gtracks(float(t), 10e3 + 200.0 * t)))
            for t in range(5)]


def _history() -> TrackHistory:
    h = TrackHistory()
    for m in _messages():
        h.ingest(m)
    return h


def _doc() -> dict[str, Any]:
    cfg = load(SCENARIO)
    assert cfg.origin is not None
    return _history().geojson(cfg, cfg.origin)


def _by(doc: dict[str, Any], kind: str) -> list[dict[str, Any]]:
    return [f for f in doc["features"] if f["properties"]["kind"] == kind]


def test_the_export_keeps_rfc_7946() -> None:
    doc = _doc()
    assert rfc7946_errors(doc) == []
    assert [len(_by(doc, k)) for k in ("site", "track", "ellipse", "trail")] == [4, 2, 2, 2]


def test_positions_are_lon_lat_alt_by_hand() -> None:
    doc = _doc()
    rx = next(f for f in _by(doc, "site") if f["properties"]["roles"] == ["rx"])
    assert rx["geometry"]["coordinates"] == pytest.approx([8.0, 47.0, 450.0], abs=1e-6)
    assert rx["properties"]["bases"] == ["b1", "b2", "b3"]
    track = next(f for f in _by(doc, "track") if f["properties"]["id"] == 7)
    lat, lon, h = pymap3d.enu2geodetic(10e3 + 800.0, 20e3, 9e3, 47.0, 8.0, 450.0, ell=WGS84)
    lo, la, alt = track["geometry"]["coordinates"]
    assert (lo, la) == pytest.approx((lon, lat), abs=1e-7) and alt == pytest.approx(h, abs=0.05)
    assert track["properties"]["status"] == "confirmed" and track["properties"]["vx"] == 200.0
    assert track["properties"]["sigma_m"] == [400.0, 100.0, 300.0]
    trail = next(f for f in _by(doc, "trail") if f["properties"]["id"] == 7)["geometry"]["coordinates"]
    assert len(trail) == 5 and trail[-1] == track["geometry"]["coordinates"]


def test_the_ellipse_is_two_sigma_closed_and_counter_clockwise() -> None:
    doc = _doc()
    ring = next(f for f in _by(doc, "ellipse") if f["properties"]["id"] == 7)["geometry"]["coordinates"][0]
    assert len(ring) == RING + 1 and ring[0] == ring[-1] and signed_area(ring) > 0
    e, n, _ = pymap3d.geodetic2enu(np.array(ring)[:, 1], np.array(ring)[:, 0], np.array(ring)[:, 2],
                                   47.0, 8.0, 450.0, ell=WGS84)
    assert np.ptp(e) == pytest.approx(2 * 2 * 400.0, rel=1e-3)
    assert np.ptp(n) == pytest.approx(2 * 2 * 100.0, rel=1e-3)


@pytest.mark.parametrize("plant,error", [
    (lambda d: d.__setitem__("crs", {"type": "name"}), "crs member"),
    (lambda d: _by(d, "site")[0]["geometry"].__setitem__("coordinates", [47.0, 95.0]), "out of range"),
    (lambda d: _by(d, "ellipse")[0]["geometry"]["coordinates"][0].pop(), "not closed"),
    (lambda d: _by(d, "ellipse")[0]["geometry"]["coordinates"][0].reverse(), "wrong way"),
    (lambda d: _by(d, "trail")[0]["geometry"].__setitem__("coordinates", [[8.0, 47.0]]), ">= 2"),
    (lambda d: d.__setitem__("type", "Feature"), "FeatureCollection"),
])
def test_the_checker_finds_planted_violations(plant: Any, error: str) -> None:
    doc = copy.deepcopy(_doc())
    plant(doc)
    assert any(error in e for e in rfc7946_errors(doc)), rfc7946_errors(doc)


def test_pfusion_export_from_a_recording(tmp_path: Path) -> None:
    with (tmp_path / "run.pfrec").open("wb") as f:
        rec = RecordWriter(f, "pf/v1", 0.0)
        for m in _messages():
            rec.write("pf/v1/radar/gtracks", m["t"], protocol.encode(m))
    out = tmp_path / "tracks.geojson"
    assert cli_main(["export", "--config", str(SCENARIO), "--recording", str(tmp_path / "run.pfrec"),
                     "--geojson", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert rfc7946_errors(doc) == [] and doc == json.loads(json.dumps(_doc()))


def test_export_refuses_a_flat_deployment(tmp_path: Path) -> None:
    flat = Path(__file__).resolve().parents[2] / "scenarios" / "two_targets.toml"
    assert cli_main(["export", "--config", str(flat), "--recording", "x.pfrec", "--geojson", "-"]) == 2


def test_the_view_serves_the_model_as_geojson() -> None:
    cfg = load(SCENARIO)
    model = ViewModel(cfg)
    for m in _messages():
        model.ingest("gtracks", m)

    async def fetch() -> tuple[int, str, Any, int]:
        application = app(Hub(model))
        application.middlewares.append(geojson_route(model))
        async with TestClient(TestServer(application)) as client:
            r = await client.get(GEOJSON_PATH)
            other = await client.get("/nothing.txt")
            return r.status, r.content_type, await r.json(content_type=None), other.status

    status, ctype, doc, other = asyncio.run(fetch())
    assert (status, ctype, other) == (200, "application/geo+json", 404)
    assert rfc7946_errors(doc) == []
    tracks = _by(doc, "track")
    assert sorted(f["properties"]["id"] for f in tracks) == [7, 8]
    assert [len(_by(doc, k)) for k in ("site", "ellipse", "trail")] == [4, 2, 2]
