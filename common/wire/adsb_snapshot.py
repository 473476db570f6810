"""The simulator's radar truth as readsb ``aircraft.json`` snapshots, so that
``pfusion evaluate --truth-adsb`` can be checked against the simulator truth path.

One snapshot per ``sim/truth/radar`` message: now = t, seen_pos = 0, hex = the truth id
in 6 hex digits, lat / lon rounded to 6 decimals and alt_geom to whole feet as readsb
writes them; gs (kt), track (deg from North) and geom_rate (ft/min) from the ENU
velocity at the origin. Needs a geodetic deployment ([radar.origin])."""

from __future__ import annotations

from typing import Any

import numpy as np

from common.core.angles import wrap_360
from common.radar.geometry.geodesy import LocalFrame

FT = 0.3048  # m
KT = 1852.0 / 3600.0  # m/s


def aircraft_json(truth: dict[str, Any], origin: LocalFrame) -> dict[str, Any]:
    """The aircraft.json of one sim/truth/radar message (decoded or as built)."""
    ids = np.asarray(truth["id"], dtype=np.int64)
    if ids.size and (ids.min() < 0 or ids.max() >= 1 << 24):
        raise ValueError("truth ids must fit 24-bit ICAO addresses")
    pos = np.column_stack([truth["x"], truth["y"], truth["z"]]).reshape(-1, 3)
    vel = np.column_stack([truth["vx"], truth["vy"], truth["vz"]]).reshape(-1, 3)
    lat, lon, h = origin.to_geodetic(pos)
    track = wrap_360(np.degrees(np.arctan2(vel[:, 0], vel[:, 1])))
    aircraft = [
        {"hex": f"{i:06x}", "type": "adsb_icao", "lat": round(la, 6), "lon": round(lo, 6),
         "alt_geom": int(round(a / FT)), "gs": round(float(np.hypot(v[0], v[1])) / KT, 1),
         "track": round(tr, 2), "geom_rate": int(round(v[2] / FT * 60.0)), "seen_pos": 0.0,
         "seen": 0.0, "mlat": [], "tisb": []}
        for i, la, lo, a, v, tr in zip(ids.tolist(), np.atleast_1d(lat).tolist(),
                                        np.atleast_1d(lon).tolist(), np.atleast_1d(h).tolist(),
                                        vel, np.atleast_1d(track).tolist())]
    return {"now": float(truth["t"]), "messages": 0, "aircraft": aircraft}
