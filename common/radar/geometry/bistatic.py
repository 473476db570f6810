"""Bistatic geometry of one passive radar base (seed 001 [1]-[3], the map g of [47]).

Frame: local East-North-Up Cartesian, metres, the receiver need not be at the origin.
Azimuth: clockwise from North (+y), in [0, 2pi), ``az = atan2(dx, dy)``.

Deviation from the seed: [3] and [47] write ``theta = atan((y - y_R) / (x - x_R))``,
i.e. counter-clockwise from the x axis (East) and defined modulo pi. The project
convention is the navigation azimuth above (full circle, clockwise from North), so
every ``theta`` here is ``atan2(dx, dy)`` wrapped to [0, 2pi). The bistatic range is
the full path ``R_T + R_R`` as in [1] (the baseline L is NOT subtracted), so
``r_b >= L`` for any real position.

Global states are ordered ``[x vx y vy z vz]`` as in 001 [47] / [51].
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from common.core.angles import TWO_PI, wrap_2pi

POS = np.array([0, 2, 4])
VEL = np.array([1, 3, 5])


class BaseGeometry(Protocol):
    """What the radar core needs of a bistatic base (the deployment's ``RadarBase``)."""

    @property
    def id(self) -> str: ...

    @property
    def tx(self) -> np.ndarray: ...

    @property
    def rx(self) -> np.ndarray: ...

    @property
    def azimuth(self) -> bool: ...


def norm3(d: np.ndarray) -> np.ndarray:
    """Euclidean norm over the last axis (of length 3): the value of np.linalg.norm(d,
    axis=-1), whose sum runs in the same order ((x^2 + y^2) + z^2), at a fifth of its
    cost on the small stacks of the fusion cycle."""
    sq = d * d
    return np.sqrt(sq[..., 0] + sq[..., 1] + sq[..., 2])


def _legs(pos: np.ndarray, tx: np.ndarray, rx: np.ndarray):
    """Vectors and lengths transmitter->target and receiver->target."""
    d_t = np.asarray(pos, dtype=float) - np.asarray(tx, dtype=float)
    d_r = np.asarray(pos, dtype=float) - np.asarray(rx, dtype=float)
    return d_t, norm3(d_t), d_r, norm3(d_r)


def bistatic_range(pos: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """r_b = ||X - X_Tx|| + ||X - X_Rx|| for positions (N, 3); 001 [1]."""
    _, r_t, _, r_r = _legs(pos, tx, rx)
    return r_t + r_r  # 001 [1]


def bistatic_range_rate(
    pos: np.ndarray, vel: np.ndarray, tx: np.ndarray, rx: np.ndarray
) -> np.ndarray:
    """v_b = d r_b / dt for positions and velocities (N, 3); 001 [2]."""
    d_t, r_t, d_r, r_r = _legs(pos, tx, rx)
    v = np.asarray(vel, dtype=float)
    return np.sum(d_t * v, axis=-1) / r_t + np.sum(d_r * v, axis=-1) / r_r  # 001 [2]


def azimuth(pos: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """Azimuth of positions (N, 3) seen from the receiver, clockwise from North; 001 [3]."""
    d = np.asarray(pos, dtype=float) - np.asarray(rx, dtype=float)
    return wrap_2pi(np.arctan2(d[..., 0], d[..., 1]))  # 001 [3], navigation convention


def project(state6: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """g of 001 [47]: states (N, 6) [x vx y vy z vz] -> (N, 3) [r_b, v_b, theta]."""
    s = np.atleast_2d(np.asarray(state6, dtype=float))
    pos, vel = s[:, POS], s[:, VEL]
    return np.stack(
        [bistatic_range(pos, tx, rx), bistatic_range_rate(pos, vel, tx, rx), azimuth(pos, rx)],
        axis=-1,
    )


def project_jacobian(state6: np.ndarray, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    """Jacobian dg/dx of 001 [47] at states (N, 6): (N, 3, 6), columns [x vx y vy z vz].

    d r_b/dp = u_T + u_R; d v_b/dv = u_T + u_R;
    d v_b/dp = (v - (u_T.v) u_T)/R_T + (v - (u_R.v) u_R)/R_R;
    d theta/dx = dy/rho^2, d theta/dy = -dx/rho^2 (rho: horizontal receiver distance).
    """
    s = np.atleast_2d(np.asarray(state6, dtype=float))
    pos, vel = s[:, POS], s[:, VEL]
    d_t, r_t, d_r, r_r = _legs(pos, tx, rx)
    u_t, u_r = d_t / r_t[:, None], d_r / r_r[:, None]
    vt = np.sum(u_t * vel, axis=1)[:, None]
    vr = np.sum(u_r * vel, axis=1)[:, None]
    rho2 = d_r[:, 0] ** 2 + d_r[:, 1] ** 2
    jac = np.zeros((s.shape[0], 3, 6))
    jac[:, 0, POS] = u_t + u_r
    jac[:, 1, POS] = (vel - vt * u_t) / r_t[:, None] + (vel - vr * u_r) / r_r[:, None]
    jac[:, 1, VEL] = u_t + u_r
    jac[:, 2, 0] = d_r[:, 1] / rho2
    jac[:, 2, 2] = -d_r[:, 0] / rho2
    return jac


def ellipsoid_point(
    rb: np.ndarray,
    az: np.ndarray,
    tx: np.ndarray,
    rx: np.ndarray,
    elevation: np.ndarray | float = 0.0,
) -> np.ndarray:
    """Point of the bistatic ellipsoid r_b seen from the receiver at (az, elevation).

    Receiver distance r_R = (r_b^2 - L^2) / (2 (r_b - u . (X_Tx - X_Rx))), u the unit
    line of sight; the receiver-centred form of 001 [34]-[35] for one base. NaN where
    r_b <= L (no such ellipsoid). Returns (N, 3) positions.
    """
    rb = np.asarray(rb, dtype=float)
    az = np.asarray(az, dtype=float)
    el = np.asarray(elevation, dtype=float)
    rb, az, el = np.broadcast_arrays(rb, az, el)
    u = np.stack([np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)], axis=-1)
    base = np.asarray(tx, dtype=float) - np.asarray(rx, dtype=float)
    big_l = np.linalg.norm(base)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_r = (rb**2 - big_l**2) / (2.0 * (rb - u @ base))
    r_r = np.where(rb > big_l, r_r, np.nan)
    return np.asarray(rx, dtype=float) + r_r[..., None] * u


def ellipse_points(rb: float, tx: np.ndarray, rx: np.ndarray, n: int = 181) -> np.ndarray:
    """n points (n, 3) of the iso-r_b curve in the receiver's horizontal plane (plotting)."""
    az = np.linspace(0.0, TWO_PI, n)
    return ellipsoid_point(np.full(n, rb), az, tx, rx)
