"""The global picture of a geodetic deployment as RFC 7946 GeoJSON, for map tools
(``pfusion export --geojson``, the view's ``/tracks.geojson``).

One FeatureCollection, WGS-84 positions [lon, lat, alt] (alt: ellipsoidal height, m),
no ``crs`` member. Features, each with ``properties.kind``: ``site`` (Point, a
receiver or transmitter and its bases), ``track`` (Point, the track's fields),
``ellipse`` (Polygon, the 2-sigma horizontal position ellipse of common.wire.view_model
at the track's height: a closed ring, counter-clockwise), ``trail`` (LineString, the
track's past positions). Lines crossing the antimeridian are not split.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from common.core.angles import TWO_PI
from common.deploy.config import Config
from common.radar.geometry.geodesy import LocalFrame
from common.wire.view_model import ellipses

RING = 36  # points of an ellipse
MIN_AXIS = 1.0  # m: a degenerate ellipse still encloses an area
DEGREES, METRES = 7, 1  # decimals of lon / lat (~1 cm) and of heights
XYZ = [0, 2, 4]  # position in a global state [x vx y vy z vz]


@dataclass(frozen=True)
class TrackShape:
    """One track to draw: its properties, ENU position (3,), ellipse [a, b, angle]
    (m, m, rad counter-clockwise from East) and trail (k, 3) ENU."""

    props: dict[str, Any]
    pos: np.ndarray
    ell: np.ndarray
    trail: np.ndarray


def positions(origin: LocalFrame, enu: np.ndarray) -> list[list[float]]:
    """[lon, lat, alt] of ENU points (k, 3), rounded."""
    lat, lon, h = origin.to_geodetic(np.asarray(enu, dtype=float).reshape(-1, 3))
    return np.column_stack([np.round(lon, DEGREES), np.round(lat, DEGREES), np.round(h, METRES)]).tolist()


def _feature(kind: str, geometry: dict[str, Any], props: dict[str, Any]) -> dict[str, Any]:
    return {"type": "Feature", "geometry": geometry, "properties": {"kind": kind, **props}}


def ellipse_ring(pos: np.ndarray, ell: np.ndarray) -> np.ndarray:
    """(RING, 3) ENU points of an ellipse [a, b, angle] around pos, counter-clockwise."""
    a, b = max(float(ell[0]), MIN_AXIS), max(float(ell[1]), MIN_AXIS)
    th = np.arange(RING) * (TWO_PI / RING)
    u, v = np.array([np.cos(ell[2]), np.sin(ell[2])]), np.array([-np.sin(ell[2]), np.cos(ell[2])])
    xy = pos[:2] + np.outer(a * np.cos(th), u) + np.outer(b * np.sin(th), v)
    return np.column_stack([xy, np.full(RING, pos[2])])


def site_features(cfg: Config, origin: LocalFrame) -> list[dict[str, Any]]:
    """A Point per distinct site of the bases, with its roles and bases."""
    sites: dict[tuple[float, ...], dict[str, Any]] = {}
    for b in cfg.bases:
        for role, p in (("rx", b.rx), ("tx", b.tx)):
            s = sites.setdefault(tuple(np.round(p, 1).tolist()), {"pos": p, "roles": [], "bases": []})
            s["roles"] += [role] if role not in s["roles"] else []
            s["bases"] += [b.id] if b.id not in s["bases"] else []
    return [_feature("site", {"type": "Point", "coordinates": positions(origin, s["pos"])[0]},
                     {"roles": s["roles"], "bases": s["bases"]}) for s in sites.values()]


def track_features(shapes: list[TrackShape], origin: LocalFrame) -> list[dict[str, Any]]:
    """Point, ellipse Polygon and trail LineString (two points or more) of each track."""
    out = []
    for s in shapes:
        tid = {"id": s.props["id"]}
        out.append(_feature("track", {"type": "Point", "coordinates": positions(origin, s.pos)[0]}, s.props))
        ring = positions(origin, ellipse_ring(s.pos, s.ell))
        out.append(_feature("ellipse", {"type": "Polygon", "coordinates": [ring + ring[:1]]}, tid))
        if len(s.trail) >= 2:
            out.append(_feature("trail", {"type": "LineString", "coordinates": positions(origin, s.trail)}, tid))
    return out


def collection(features: list[dict[str, Any]]) -> dict[str, Any]:
    return {"type": "FeatureCollection", "features": features}


def gtracks_shapes(msg: dict[str, Any], trails: dict[int, list[np.ndarray]]) -> list[TrackShape]:
    """The shapes of a decoded radar/gtracks message; ``trails``: past ENU positions per id."""
    out = []
    for k in msg["tracks"]:
        x, P = np.asarray(k["x"], dtype=float), np.asarray(k["P"], dtype=float).reshape(6, 6)
        sig = np.sqrt(np.maximum(np.diagonal(P)[XYZ], 0.0))
        props = {"id": int(k["id"]), "status": k["status"], "score": round(float(k["score"]), 2),
                 "ambiguous": bool(k["ambiguous"]), "t": float(msg["t"]),
                 "vx": round(float(x[1]), 2), "vy": round(float(x[3]), 2), "vz": round(float(x[5]), 2),
                 "sigma_m": np.round(sig, 1).tolist(), "etracks": [[b, int(e)] for b, e in k["etracks"]]}
        trail = np.array(trails.get(int(k["id"]), []), dtype=float).reshape(-1, 3)
        out.append(TrackShape(props, x[XYZ], ellipses(P[np.ix_([0, 2], [0, 2])])[0], trail))
    return out


def view_shapes(state: dict[str, Any]) -> list[TrackShape]:
    """The shapes of the view model's ``gtracks`` topic (common.wire.view_model): its
    trails are horizontal, drawn at the track's present height."""
    out = []
    for k in state["tracks"]:
        x = np.asarray(k["x"], dtype=float)
        trail = np.array([[p[0], p[1], x[4]] for p in k["trail"]], dtype=float).reshape(-1, 3)
        props = {"id": k["id"], "status": k["status"], "score": k["score"], "ambiguous": k["amb"],
                 "t": state["t"], "vx": x[1], "vy": x[3], "vz": x[5], "sigma_m": [k["sig"][i] for i in XYZ],
                 "etracks": k["et"]}
        out.append(TrackShape(props, x[XYZ], np.asarray(k["ell"], dtype=float), trail))
    return out


class TrackHistory:
    """Decoded radar/gtracks messages in, the picture of the last one out, each track
    with its trail since the first message."""

    def __init__(self) -> None:
        self.last: dict[str, Any] | None = None
        self.trails: dict[int, list[np.ndarray]] = {}

    def ingest(self, msg: dict[str, Any]) -> None:
        for k in msg["tracks"]:
            self.trails.setdefault(int(k["id"]), []).append(np.asarray(k["x"], dtype=float)[XYZ])
        self.last = msg

    def geojson(self, cfg: Config, origin: LocalFrame) -> dict[str, Any]:
        shapes = gtracks_shapes(self.last, self.trails) if self.last is not None else []
        return collection(site_features(cfg, origin) + track_features(shapes, origin))
