"""Positions of a deployment's sites: local metres (x East, y North, z up) or WGS-84
latitude, longitude and ellipsoidal height through the deployment's origin
([radar.origin], common.radar.geometry.geodesy)."""

from __future__ import annotations

from typing import Any

import numpy as np

from common.deploy.errors import ConfigError
from common.deploy.structure import ORIGIN
from common.radar.geometry.geodesy import LocalFrame


def point(v: Any, key: str, geo: bool = False) -> np.ndarray:
    ok = isinstance(v, list) and len(v) == 3 and all(
        isinstance(c, (int, float)) and not isinstance(c, bool) for c in v
    )
    if not ok or not np.all(np.isfinite(v)) or (geo and not (abs(v[0]) <= 90 and abs(v[1]) <= 180)):
        raise ConfigError(key, f"{v!r} must be " + ("[lat_deg, lon_deg, alt_m] (WGS-84, |lat| <= 90, "
                                                    "|lon| <= 180, ellipsoidal height)" if geo else
                                                    "[x, y, z] in metres"))
    return np.asarray(v, dtype=float)


def geo_origin(o: Any) -> LocalFrame | None:
    """Table [radar.origin] (lat, lon deg, alt m ellipsoidal) as a frame; None: flat."""
    if o is not None and (not isinstance(o, dict) or set(o) != ORIGIN.names()):
        raise ConfigError("radar.origin", "must be a table of exactly lat, lon (deg), alt (m, ellipsoidal)")
    return None if o is None else LocalFrame(*point([o["lat"], o["lon"], o["alt"]], "radar.origin", True).tolist())


def site_position(b: dict[str, Any], k: str, key: str, origin: LocalFrame | None) -> np.ndarray:
    """Site ``k`` (tx / rx) in local metres: ``k`` as given, or ``k_geo`` through origin."""
    if (k in b) == (f"{k}_geo" in b):
        raise ConfigError(f"{key}.{k}", f"give exactly one of {k} (local m) or {k}_geo ([lat, lon, alt])")
    if k in b:
        return point(b[k], f"{key}.{k}")
    if origin is None:
        raise ConfigError(f"{key}.{k}_geo", "needs [radar.origin]")
    return origin.to_enu(*point(b[f"{k}_geo"], f"{key}.{k}_geo", True))
