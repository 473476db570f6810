"""The deployment's local ENU frame on WGS-84 (common.radar.geometry.geodesy): round trips
to < 1 mm over a 300 km region and heights -100 m..20 km, the Earth's fall below the
tangent plane, and the lifted tracks of the simulator."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from common.radar.geometry.geodesy import WGS84, LocalFrame

MM = 1e-3
DEG_M = 111_320.0  # metres per degree of latitude, an upper bound (for the mm scale)

origins = st.builds(LocalFrame, st.floats(-80, 80), st.floats(-180, 180), st.floats(-100, 3000))
offsets = st.floats(-150e3, 150e3)
heights = st.floats(-100, 20e3)


def _curvature_radius(lat0: float, az: float) -> float:
    """Radius of curvature of the ellipsoid at latitude lat0 (deg) in azimuth az (rad)."""
    e2 = WGS84.eccentricity**2
    w = np.sqrt(1 - e2 * np.sin(np.radians(lat0)) ** 2)
    n, m = WGS84.semimajor_axis / w, WGS84.semimajor_axis * (1 - e2) / w**3
    return float(1.0 / (np.cos(az) ** 2 / m + np.sin(az) ** 2 / n))


@settings(max_examples=200, deadline=None)
@given(origins, offsets, offsets, heights)
def test_geodetic_enu_geodetic_within_a_millimetre(f: LocalFrame, x: float, y: float, h: float) -> None:
    lat, lon, _ = f.to_geodetic(np.array([x, y, 0.0]))
    back = f.to_geodetic(f.to_enu(lat, lon, h))
    dlon = (back[1] - lon + 180.0) % 360.0 - 180.0
    assert abs(back[0] - lat) * DEG_M < MM
    assert abs(dlon) * DEG_M * np.cos(np.radians(lat)) < MM
    assert abs(back[2] - h) < MM


@settings(max_examples=200, deadline=None)
@given(origins, offsets, offsets, heights)
def test_enu_geodetic_enu_within_a_millimetre(f: LocalFrame, x: float, y: float, h: float) -> None:
    p = np.array([x, y, h - f.h0])
    assert np.max(np.abs(f.to_enu(*f.to_geodetic(p)) - p)) < MM


def test_vectorised_over_any_shape() -> None:
    f = LocalFrame(48.0, 2.0, 100.0)
    p = np.random.default_rng(0).uniform(-150e3, 150e3, (4, 5, 3))
    lat, lon, h = f.to_geodetic(p)
    assert lat.shape == lon.shape == h.shape == (4, 5)
    assert f.to_enu(lat, lon, h).shape == (4, 5, 3)
    np.testing.assert_allclose(f.to_enu(lat, lon, h), p, atol=MM)
    np.testing.assert_allclose(f.to_enu(48.0, 2.0, 100.0), [0.0, 0.0, 0.0], atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(origins, st.floats(0.0, 2 * np.pi))
def test_constant_height_falls_below_the_tangent_plane(f: LocalFrame, az: float) -> None:
    """A point at the origin's ellipsoidal height 150 km away: z ~ -d^2 / (2 R), R the
    radius of curvature in that direction (~1.76-1.77 km)."""
    p = f.lift(np.array([150e3 * np.sin(az), 150e3 * np.cos(az), f.h0]))
    d = float(np.hypot(p[0], p[1]))
    assert abs(d - 150e3) < 100.0
    assert -1780.0 < p[2] < -1750.0
    assert abs(p[2] + d * d / (2 * _curvature_radius(f.lat0, az))) < 1.0


def test_known_fall_at_150_km_north() -> None:
    p = LocalFrame(45.0, 5.0, 0.0).lift(np.array([0.0, 150e3, 0.0]))
    assert round(float(-p[2])) == 1766


@settings(max_examples=100, deadline=None)
@given(origins, offsets, offsets, heights)
def test_lift_keeps_the_ellipsoidal_height(f: LocalFrame, x: float, y: float, h: float) -> None:
    p = f.lift(np.array([x, y, h]))
    lat, lon, hh = f.to_geodetic(p)
    assert abs(hh - h) < MM
    foot = f.to_geodetic(np.array([x, y, 0.0]))
    assert abs(lat - foot[0]) * DEG_M < MM  # on the vertical of the tangent-plane point
    assert abs((lon - foot[1] + 180.0) % 360.0 - 180.0) * DEG_M < MM


def test_lift_motion_velocity_is_the_derivative_of_the_path() -> None:
    f = LocalFrame(50.0, 10.0, 300.0)
    track = np.array([[120e3, -60e3, 9000.0], [0.0, 0.0, 300.0]])
    rate = np.array([[180.0, 150.0, 3.0], [250.0, 0.0, 0.0]])
    pos, vel = f.lift_motion(track, rate)
    np.testing.assert_allclose(pos, f.lift(track))
    dt = 1e-3
    numeric = (f.lift(track + dt * rate) - f.lift(track - dt * rate)) / (2 * dt)
    np.testing.assert_allclose(vel, numeric, atol=1e-4)
    # at the origin, constant height: the velocity is the tangent-plane one
    np.testing.assert_allclose(vel[1], [250.0, 0.0, 0.0], atol=1e-3)
    # flying away from the origin at constant height, the point sinks: dz/dt ~ -v.d / R
    assert vel[0, 2] < rate[0, 2] - 0.5 * (180.0 * 120e3 - 150.0 * 60e3) / 6.4e6
