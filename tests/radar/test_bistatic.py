"""Tests of common.radar.geometry.bistatic: 001 [1]-[3], g of [47] and its Jacobian."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from common.radar.geometry.bistatic import (
    azimuth,
    bistatic_range,
    bistatic_range_rate,
    ellipse_points,
    ellipsoid_point,
    norm3,
    project,
    project_jacobian,
)

TX = np.array([30000.0, 0.0, 0.0])
RX = np.array([0.0, 0.0, 0.0])

coord = st.floats(-80e3, 80e3, allow_nan=False)
speed = st.floats(-300.0, 300.0, allow_nan=False)
alt = st.floats(0.0, 12e3, allow_nan=False)


def test_hand_values_3_4_5_triangle() -> None:
    # target due North of the receiver at 40 km; transmitter 30 km East
    pos = np.array([[0.0, 40000.0, 0.0]])
    vel = np.array([[0.0, -200.0, 0.0]])
    assert bistatic_range(pos, TX, RX)[0] == pytest.approx(50000.0 + 40000.0)  # [1]
    # (-30000*0 + 40000*-200)/50000 + (40000*-200)/40000 = -160 - 200
    assert bistatic_range_rate(pos, vel, TX, RX)[0] == pytest.approx(-360.0)  # [2]
    assert azimuth(pos, RX)[0] == pytest.approx(0.0)  # [3]
    y = project(np.array([[0.0, 0.0, 40000.0, -200.0, 0.0, 0.0]]), TX, RX)
    np.testing.assert_allclose(y, [[90000.0, -360.0, 0.0]], atol=1e-9)


def test_azimuth_convention_clockwise_from_north() -> None:
    rx = np.array([1000.0, -2000.0, 50.0])
    pts = rx + np.array([[0, 5e3, 0], [5e3, 0, 0], [0, -5e3, 0], [-5e3, 0, 0], [1e3, 1e3, 7]])
    np.testing.assert_allclose(
        azimuth(pts, rx), [0.0, np.pi / 2, np.pi, 3 * np.pi / 2, np.pi / 4], atol=1e-12
    )


def test_range_includes_baseline_and_rate_zero_on_tangent() -> None:
    # on the baseline extension the bistatic range is L + 2 d; a velocity tangent to the
    # ellipse (here: perpendicular to the baseline at its midpoint) gives v_b = 0
    assert bistatic_range(np.array([[-1000.0, 0, 0]]), TX, RX)[0] == pytest.approx(32000.0)
    mid = np.array([[15000.0, 20000.0, 0.0]])
    assert bistatic_range_rate(mid, np.array([[250.0, 0, 0]]), TX, RX)[0] == pytest.approx(0.0)


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(coord, speed, coord, speed, alt, st.floats(-20, 20)),
    st.tuples(coord, coord, st.floats(0, 500)),
    st.tuples(coord, coord, st.floats(0, 500)),
)
def test_jacobian_matches_finite_differences(state, tx, rx) -> None:
    x = np.array(state)
    tx, rx = np.array(tx), np.array(rx)
    pos = x[[0, 2, 4]]
    # stay away from the singularities (target on a site, or above the receiver)
    assume(min(np.linalg.norm(pos - tx), np.linalg.norm(pos - rx)) > 2000.0)
    assume(np.hypot(*(pos - rx)[:2]) > 2000.0)
    jac = project_jacobian(x[None], tx, rx)[0]
    num = np.empty((3, 6))
    for j in range(6):
        h = 0.5 if j in (0, 2, 4) else 1e-2
        e = np.zeros(6)
        e[j] = h
        d = project((x + e)[None], tx, rx)[0] - project((x - e)[None], tx, rx)[0]
        d[2] = (d[2] + np.pi) % (2 * np.pi) - np.pi
        num[:, j] = d / (2 * h)
    np.testing.assert_allclose(jac, num, rtol=1e-5, atol=1e-9)


def test_jacobian_vectorised_shape_and_rows() -> None:
    x = np.array([[0.0, 0.0, 40000.0, -200.0, 0.0, 0.0], [40000.0, 10.0, 0.0, 0.0, 1e3, 0.0]])
    jac = project_jacobian(x, TX, RX)
    assert jac.shape == (2, 3, 6)
    # first state: u_T = (-0.6, 0.8, 0), u_R = (0, 1, 0) -> d r_b / d(x, y) = (-0.6, 1.8)
    np.testing.assert_allclose(jac[0, 0], [-0.6, 0, 1.8, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(jac[0, 2], [1 / 40000.0, 0, 0, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(jac[1], project_jacobian(x[1:], TX, RX)[0])


@settings(max_examples=80, deadline=None)
@given(
    st.floats(0.0, 2 * np.pi, exclude_max=True),
    st.floats(1000.0, 100e3),
    st.floats(-0.3, 0.3),
    st.tuples(coord, coord, st.floats(0, 500)),
)
def test_ellipsoid_point_inverts_range_and_azimuth(az, excess, el, tx) -> None:
    tx = np.array(tx)
    rx = np.array([500.0, -300.0, 20.0])
    rb = np.linalg.norm(tx - rx) + excess
    p = ellipsoid_point(np.array([rb]), np.array([az]), tx, rx, el)
    assert bistatic_range(p, tx, rx)[0] == pytest.approx(rb, rel=1e-9)
    got = azimuth(p, rx)[0]
    assert abs((got - az + np.pi) % (2 * np.pi) - np.pi) < 1e-9


def test_ellipse_points_nan_inside_baseline_and_on_curve() -> None:
    assert np.all(np.isnan(ellipse_points(20000.0, TX, RX, 8)))
    pts = ellipse_points(90000.0, TX, RX, 16)
    assert pts.shape == (16, 3)
    np.testing.assert_allclose(bistatic_range(pts, TX, RX), 90000.0, rtol=1e-12)


def test_norm3_is_numpy_norm_bit_for_bit() -> None:
    """norm3 gives exactly np.linalg.norm(axis=-1) (same order of the sum) on stacks of
    the fusion's shapes, magnitudes from 1e-3 to 1e6 m, contiguous or not."""
    rng = np.random.default_rng(5)
    for shape in [(7, 3), (5000, 3), (194, 6, 4, 3), (300, 8, 3)]:
        d = rng.standard_normal(shape) * np.exp(rng.uniform(-7.0, 14.0, shape))
        np.testing.assert_array_equal(norm3(d), np.linalg.norm(d, axis=-1))
        strided = np.swapaxes(np.swapaxes(d, 0, -1).copy(), 0, -1)
        np.testing.assert_array_equal(norm3(strided), np.linalg.norm(strided, axis=-1))
