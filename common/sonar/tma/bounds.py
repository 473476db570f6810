"""Bounds on range R, course K and speed V of seed 003 (ES 2 400 413) and the checks and
corrections made on them: containment (control unit 30, claim 2b), edge checks 52 and
54 (the bounds converted to state bounds and back), correction module 40 (re-centre
the violated intervals) and the minimal bounds 75. R, K, V refer to the current time
(latest bearing); the course interval runs clockwise from ``k_min`` to ``k_max``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from common.core.angles import TWO_PI, wrap_2pi


@dataclass(frozen=True)
class Bounds:
    """Bounds on range (m), course (rad, clockwise interval k_min -> k_max) and speed (m/s).

    ``k_min == k_max`` (mod 2 pi) means no course bound.
    """

    r_min: float
    r_max: float
    k_min: float
    k_max: float
    v_min: float
    v_max: float

    @property
    def course_width(self) -> float:
        """Width of the course interval in (0, 2 pi]."""
        w = wrap_2pi(self.k_max - self.k_min)
        return TWO_PI if w == 0.0 else w

    def violations(self, r: float, k: float, v: float) -> np.ndarray:
        """Flags (R, K, V) outside their interval (control unit 30, 003 claim 2b)."""
        return np.array([
            not self.r_min <= r <= self.r_max,
            wrap_2pi(k - self.k_min) > self.course_width,
            not self.v_min <= v <= self.v_max,
        ])

    def contains(self, r: float, k: float, v: float) -> bool:
        """True when (R, K, V) lies inside the solution space of the bounds."""
        return not self.violations(r, k, v).any()


# 003 Fig. 5 "valores límites mínimos 75": 0.1-100 km, 0.1-15 m/s, all courses
# (the seed prints 0-350 deg; the full circle is used).
MINIMAL_BOUNDS = Bounds(100.0, 100e3, 0.0, TWO_PI, 0.1, 15.0)


def rkv(x: np.ndarray, own_c: np.ndarray) -> tuple[float, float, float]:
    """Range, course (rad in [0, 2 pi)) and speed of the state (x, y, vx, vy)."""
    return (
        float(np.hypot(x[0] - own_c[0], x[1] - own_c[1])),
        wrap_2pi(np.arctan2(x[2], x[3])),
        float(np.hypot(x[2], x[3])),
    )


def edge_flags(r: float, k: float, v: float, b: Bounds, tol: float) -> np.ndarray:
    """First edge check 52: (R, K, V) on the edge (within tol * width) or outside of the bounds."""
    fr = r <= b.r_min + tol * (b.r_max - b.r_min) or r >= b.r_max - tol * (b.r_max - b.r_min)
    fv = v <= b.v_min + tol * (b.v_max - b.v_min) or v >= b.v_max - tol * (b.v_max - b.v_min)
    w = b.course_width
    fk = False
    if w < TWO_PI:
        d = wrap_2pi(k - b.k_min)
        fk = d <= tol * w or d >= (1.0 - tol) * w
    return np.array([fr, fk, fv])


def _arc(angles: np.ndarray) -> tuple[float, float]:
    """Smallest clockwise arc (start, end) containing all angles."""
    a = np.sort(wrap_2pi(angles))
    gaps = np.diff(np.concatenate((a, [a[0] + TWO_PI])))
    i = int(np.argmax(gaps))
    return float(a[(i + 1) % a.size]), float(a[i])


def state_bounds(b: Bounds, own_c: np.ndarray, brg_c: float) -> tuple[np.ndarray, np.ndarray]:
    """State bounds on p = (x, y, vx, vy) at the current time derived from (R, K, V) bounds (003 edge check 54).

    Position: the segment R in [r_min, r_max] on the current bearing; velocity: the
    annular sector V in [v_min, v_max], K in the course interval. Deviation: the seed
    bounds (X0, Y0) at track start; the current time is used because R refers to it.
    """
    u = np.array([np.sin(brg_c), np.cos(brg_c)])
    pos = own_c + np.outer([b.r_min, b.r_max], u)
    w = b.course_width
    k0 = wrap_2pi(b.k_min)
    ks = np.array([k0, k0 + w] + [c for c in np.arange(0.0, 2.0 * TWO_PI, np.pi / 2) if k0 <= c <= k0 + w])
    vel = np.concatenate([np.stack((v * np.sin(ks), v * np.cos(ks)), 1) for v in (b.v_min, b.v_max)])
    lo = np.concatenate((pos.min(0), vel.min(0)))
    hi = np.concatenate((pos.max(0), vel.max(0)))
    return lo, hi


def effective_bounds(lo: np.ndarray, hi: np.ndarray, own_c: np.ndarray) -> Bounds:
    """Effective (weaker) R, K, V bounds re-converted from state bounds (003 edge check 54)."""
    pc = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]]) - own_c
    near = np.clip(own_c, lo[:2], hi[:2]) - own_c
    vc = np.array([[lo[2], lo[3]], [lo[2], hi[3]], [hi[2], lo[3]], [hi[2], hi[3]]])
    tol = 1e-9 * np.max(np.abs(vc))
    vnear = np.clip(np.zeros(2), lo[2:], hi[2:])
    if np.all(np.abs(vnear) <= tol):
        vnear = np.zeros(2)
        k_min, k_max = 0.0, TWO_PI
    else:
        k_min, k_max = _arc(np.arctan2(vc[:, 0], vc[:, 1]))
    return Bounds(
        float(np.hypot(*near)), float(np.max(np.hypot(pc[:, 0], pc[:, 1]))),
        k_min, k_max,
        float(np.hypot(*vnear)), float(np.max(np.hypot(vc[:, 0], vc[:, 1]))),
    )


def recentre(b: Bounds, flags: np.ndarray, r: float, k: float, v: float, minimal: Bounds = MINIMAL_BOUNDS) -> Bounds:
    """Correction module 40 / unit 72: shift each flagged interval so the estimate is at its centre.

    Widths are kept; range and speed intervals are shifted back inside ``minimal``.
    """

    def shift(lo: float, hi: float, x: float, mlo: float, mhi: float) -> tuple[float, float]:
        w = min(hi - lo, mhi - mlo)
        lo = min(max(x - 0.5 * w, mlo), mhi - w)
        return lo, lo + w

    out = b
    if flags[0]:
        out = replace(out, **dict(zip(("r_min", "r_max"), shift(b.r_min, b.r_max, r, minimal.r_min, minimal.r_max))))
    if flags[1] and b.course_width < TWO_PI:
        w = b.course_width
        out = replace(out, k_min=wrap_2pi(k - 0.5 * w), k_max=wrap_2pi(k + 0.5 * w))
    if flags[2]:
        out = replace(out, **dict(zip(("v_min", "v_max"), shift(b.v_min, b.v_max, v, minimal.v_min, minimal.v_max))))
    return out
