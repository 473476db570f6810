"""The deployment's local frame on the Earth (issue 29), on pymap3d.

Datum: WGS-84. Latitudes and longitudes are geodetic, in degrees (longitudes in
[-180, 180]); heights are ellipsoidal (above the WGS-84 ellipsoid, not above mean sea
level), in metres. The local frame is East-North-Up at the origin (lat0, lon0, h0):
x East, y North, z along the ellipsoid normal at the origin, metres, the frame of every
core. It is a tangent plane: a point at constant height falls below it with distance
(z ~ -d^2 / (2 R), 1.77 km at 150 km).

Vectorised: every function takes arrays (or scalars) and broadcasts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d

WGS84 = pymap3d.Ellipsoid.from_name("wgs84")
# half step (s) of the central difference that maps a mover's velocity onto its lifted
# track: the lifted path's third derivative is ~ v^3 / R^2, so the error is ~ 1e-7 m/s
_DT = 0.5


@dataclass(frozen=True)
class LocalFrame:
    """The ENU frame at an origin: lat0, lon0 (deg, WGS-84), h0 (m, ellipsoidal)."""

    lat0: float
    lon0: float
    h0: float

    def to_enu(self, lat: np.ndarray, lon: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Geodetic (deg, deg, m) -> ENU positions (..., 3) in metres."""
        e, n, u = pymap3d.geodetic2enu(lat, lon, h, self.lat0, self.lon0, self.h0, ell=WGS84)
        return np.stack(np.broadcast_arrays(e, n, u), axis=-1).astype(float)

    def to_geodetic(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ENU positions (..., 3) in metres -> (lat deg, lon deg, ellipsoidal height m)."""
        p = np.asarray(p, dtype=float)
        lat, lon, h = pymap3d.enu2geodetic(p[..., 0], p[..., 1], p[..., 2],
                                           self.lat0, self.lon0, self.h0, ell=WGS84)
        return np.asarray(lat, float), np.asarray(lon, float), np.asarray(h, float)

    def lift(self, track: np.ndarray) -> np.ndarray:
        """ENU positions (..., 3) of horizontal tracks at ellipsoidal heights.

        ``track`` (..., 3) is [x, y, h]: (x, y) a point of the tangent plane z = 0, h an
        ellipsoidal height. The result is the point at height h on the ellipsoid normal
        through the foot of (x, y, 0): the mover runs in the tangent plane and each of
        its positions is re-projected along the vertical to its geodetic altitude."""
        track = np.asarray(track, dtype=float)
        lat, lon, _ = self.to_geodetic(np.concatenate([track[..., :2], np.zeros_like(track[..., 2:])], axis=-1))
        return self.to_enu(lat, lon, track[..., 2])

    def lift_motion(self, track: np.ndarray, rate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """ENU positions and velocities (..., 3) of :meth:`lift` for tangent-plane tracks
        [x, y, h] moving at ``rate`` [vx, vy, dh/dt]: the velocity is the derivative of
        the lifted path (a central difference along ``rate``, so exact at leg changes)."""
        track, rate = np.asarray(track, dtype=float), np.asarray(rate, dtype=float)
        ahead, behind = self.lift(track + _DT * rate), self.lift(track - _DT * rate)
        return self.lift(track), (ahead - behind) / (2.0 * _DT)
