"""Angles: the one TWO_PI and the one wrap of each range ([-pi, pi) and [0, 2pi) in
radians, [0, 360) in degrees), for scalars and numpy arrays. Every module wraps with
these."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

TWO_PI = 2.0 * np.pi


def wrap_pi(a: ArrayLike) -> np.ndarray | float:
    """Wrap angles to [-pi, pi); a scalar in gives a float out."""
    a = np.asarray(a, dtype=float)
    # a - 2pi floor((a + pi) / 2pi), in place: several times faster than np.mod on large
    # arrays; the two corrections catch results that rounding leaves on or past a bound.
    w = np.add(a, np.pi, out=np.empty_like(a))
    w /= TWO_PI
    np.floor(w, out=w)
    w *= -TWO_PI
    w += a
    w[w >= np.pi] -= TWO_PI
    w[w < -np.pi] += TWO_PI
    return float(w) if w.ndim == 0 else w


def wrap_2pi(a: ArrayLike) -> np.ndarray | float:
    """Wrap angles to [0, 2pi); a scalar in gives a float out."""
    w = np.mod(np.asarray(a, dtype=float), TWO_PI)
    # np.mod can round a tiny negative input up to exactly 2pi.
    w = np.where(w >= TWO_PI, 0.0, w)
    return float(w) if w.ndim == 0 else w


def wrap_360(a: ArrayLike) -> np.ndarray | float:
    """Wrap angles in degrees to [0, 360); a scalar in gives a float out."""
    w = np.mod(np.asarray(a, dtype=float), 360.0)
    w = np.where(w >= 360.0, 0.0, w)  # as wrap_2pi
    return float(w) if w.ndim == 0 else w
