"""The rules of RFC 7946 that a FeatureCollection of ``pfusion export --geojson`` must
keep, as a checker that returns every violation (empty: valid)."""

from __future__ import annotations

import json
import math
from typing import Any

GEOMETRIES = {"Point", "MultiPoint", "LineString", "MultiLineString", "Polygon", "MultiPolygon",
              "GeometryCollection"}


def _no_crs(o: Any, where: str, errors: list[str]) -> None:
    """Section 4: no ``crs`` member anywhere."""
    if isinstance(o, dict):
        if "crs" in o:
            errors.append(f"{where}: crs member")
        for k, v in o.items():
            _no_crs(v, f"{where}.{k}", errors)
    elif isinstance(o, list):
        for i, v in enumerate(o):
            _no_crs(v, f"{where}[{i}]", errors)


def _position(p: Any, where: str, errors: list[str]) -> bool:
    """Section 3.1.1: [lon, lat] or [lon, lat, alt], numbers, lon / lat in range."""
    if not (isinstance(p, list) and len(p) in (2, 3) and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in p)):
        errors.append(f"{where}: not a position [lon, lat(, alt)]: {p!r}")
        return False
    if not (-180 <= p[0] <= 180 and -90 <= p[1] <= 90):
        errors.append(f"{where}: lon {p[0]} / lat {p[1]} out of range")
        return False
    return True


def signed_area(ring: list[list[float]]) -> float:
    """Shoelace area in lon / lat (> 0: counter-clockwise)."""
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(ring, ring[1:]))


def _ring(ring: Any, where: str, exterior: bool, errors: list[str]) -> None:
    """Section 3.1.6: >= 4 positions, closed, exterior counter-clockwise, holes clockwise."""
    if not isinstance(ring, list) or len(ring) < 4:
        errors.append(f"{where}: a linear ring needs >= 4 positions")
        return
    if not all([_position(p, f"{where}[{i}]", errors) for i, p in enumerate(ring)]):
        return
    if ring[0] != ring[-1]:
        errors.append(f"{where}: ring not closed")
    elif (signed_area(ring) > 0) != exterior:
        errors.append(f"{where}: {'exterior' if exterior else 'hole'} ring wound the wrong way")


def _geometry(g: Any, where: str, errors: list[str]) -> None:
    if g is None:
        return
    if not isinstance(g, dict) or g.get("type") not in GEOMETRIES:
        errors.append(f"{where}: not a geometry")
        return
    c = g.get("coordinates")
    kind = g["type"]
    if kind == "Point":
        _position(c, where, errors)
    elif kind == "LineString":
        if not isinstance(c, list) or len(c) < 2:
            errors.append(f"{where}: a LineString needs >= 2 positions")
        else:
            for i, p in enumerate(c):
                _position(p, f"{where}[{i}]", errors)
    elif kind == "Polygon":
        if not isinstance(c, list) or not c:
            errors.append(f"{where}: a Polygon needs rings")
        else:
            for i, r in enumerate(c):
                _ring(r, f"{where}[{i}]", i == 0, errors)
    else:
        errors.append(f"{where}: {kind} not expected in this export")


def rfc7946_errors(obj: Any) -> list[str]:
    """Every violation of the rules above in a FeatureCollection."""
    errors: list[str] = []
    try:
        json.dumps(obj, allow_nan=False)
    except (TypeError, ValueError) as e:
        return [f"not JSON: {e}"]
    _no_crs(obj, "$", errors)
    if not isinstance(obj, dict) or obj.get("type") != "FeatureCollection" \
            or not isinstance(obj.get("features"), list):
        return errors + ["$: not a FeatureCollection with a features array"]
    for i, f in enumerate(obj["features"]):
        where = f"features[{i}]"
        if not isinstance(f, dict) or f.get("type") != "Feature" or "geometry" not in f \
                or "properties" not in f or not isinstance(f["properties"], (dict, type(None))):
            errors.append(f"{where}: not a Feature with geometry and properties")
            continue
        _geometry(f["geometry"], f"{where}.geometry", errors)
    return errors
