"""The constrained TMA solve of seed 003 (ES 2 400 413): bearing least squares with box
bounds on range, course and speed, per target leg (claims 1 and 9), and the bounds of a
new leg (paragraph 55). Used by the TMA/CTMA cycle of ``common.sonar.tma.constrained``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
from scipy.optimize import least_squares

from common.core.angles import TWO_PI, wrap_2pi
from common.sonar.tma.bearings_only import Support, TmaSolution, covariance, leg_times, weighted_system
from common.sonar.tma.bounds import Bounds


def _course_into(k: float, b: Bounds) -> float:
    """Course unwrapped into [k_min, k_min + width], clipped to the nearer edge if outside."""
    w = b.course_width
    d = wrap_2pi(k - b.k_min)
    if d > w:
        d = w if d - w < TWO_PI - d else 0.0
    return b.k_min + d


def new_leg_bounds(b: Bounds) -> Bounds:
    """Bounds of a new target leg (003 paragraph 55, claim 9): the course is freed, range
    and speed intervals are kept.

    Paragraph 55 sets "new bounds" for the position after a manoeuvre so that changes of
    course and/or speed are taken into account, without saying how. Rule chosen: a
    manoeuvre is a change of course, so the old course interval cannot hold; the speed
    interval (the target's class) and the range interval (it refers to the current
    time) are kept. A speed outside it is found and corrected by the error handling of
    the new leg (claims 5-8), and an operator's bounds message replaces these bounds.
    Deviation: the seed's range bounds for the start of the new leg derived from the
    estimated end position of the original one are not formed: the joint solve starts
    the new leg at that end position by construction (002 eq. 16).
    """
    return replace(b, k_min=0.0, k_max=TWO_PI)


def legs_inside(beta: np.ndarray, leg_bounds: Sequence[Bounds | None]) -> bool:
    """True when course and speed of every earlier leg j of ``beta`` lie in ``leg_bounds[j]`` (003 claim 9)."""
    for j, b in enumerate(leg_bounds):
        if b is not None:
            vx, vy = beta[2 + 2 * j:4 + 2 * j]
            if not b.contains(b.r_min, wrap_2pi(np.arctan2(vx, vy)), float(np.hypot(vx, vy))):
                return False
    return True


def solve_ctma(
    t: np.ndarray,
    brg: np.ndarray,
    sbrg: np.ndarray | float,
    own_xy: np.ndarray,
    t0: float,
    bounds: Bounds,
    start: TmaSolution,
    support: Sequence[Support] = (),
    legs: Sequence[float] = (),
    leg_bounds: Sequence[Bounds | None] = (),
) -> TmaSolution:
    """Constrained TMA: bearing least squares with R, K, V bounded, per target leg (003 claims 1, 9).

    ``bounds`` hold for the current (last) leg: R at the latest bearing time, its K and
    V. ``leg_bounds[j]`` bounds course and speed of the earlier leg j (its range
    interval is not used: R refers to the current time); missing or None: free.
    Parameterisation p = (B, R, K_0, V_0, ..., K_L-1, V_L-1): the target sits at range
    R on bearing B from the own position at the latest bearing time, leg j moves with
    speed V_j on course K_j; box bounds go to scipy's trust-region reflective least
    squares. Starts: the TMA solution clipped into the bounds and the centre of the
    bounds; the lower cost wins. P is the unconstrained (H'WH)^-1 at the solution.
    """
    t = np.asarray(t, float)
    brg = np.asarray(brg, float)
    own_xy = np.asarray(own_xy, float)
    sb = np.broadcast_to(np.asarray(sbrg, float), t.shape)
    legs = tuple(legs)
    m = int(np.argmax(t))
    oc = own_xy[m]
    Tc = leg_times(np.array([t[m]]), t0, legs)[0]
    L = Tc.size
    per_leg = (list(leg_bounds) + [None] * L)[:L - 1] + [bounds]  # 003 claim 9: own bounds per leg
    i = np.arange(L)

    def to_beta(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        b, r = p[:2]
        k, v = p[2::2], p[3::2]
        s, c = np.sin(k), np.cos(k)
        vel = np.ravel(np.column_stack((v * s, v * c)))
        beta = np.concatenate(([oc[0] + r * np.sin(b) - vel[0::2] @ Tc, oc[1] + r * np.cos(b) - vel[1::2] @ Tc], vel))
        D = np.zeros((beta.size, p.size))
        D[0, :2] = r * np.cos(b), np.sin(b)
        D[1, :2] = -r * np.sin(b), np.cos(b)
        D[2 + 2 * i, 2 + 2 * i] = v * c
        D[2 + 2 * i, 3 + 2 * i] = s
        D[3 + 2 * i, 2 + 2 * i] = -v * s
        D[3 + 2 * i, 3 + 2 * i] = c
        D[0] -= Tc @ D[2::2]
        D[1] -= Tc @ D[3::2]
        return beta, D

    def fun(p: np.ndarray) -> np.ndarray:
        return -weighted_system(to_beta(p)[0], t, brg, sb, own_xy, t0, support, legs)[0]

    def jac(p: np.ndarray) -> np.ndarray:
        beta, D = to_beta(p)
        return weighted_system(beta, t, brg, sb, own_xy, t0, support, legs)[1] @ D

    lb = np.full(2 + 2 * L, -np.inf)
    ub = np.full(2 + 2 * L, np.inf)
    lb[1], ub[1] = bounds.r_min, bounds.r_max
    lb[3::2] = 0.0
    x_s, _ = start.state_at(t[m])
    r_s = float(np.hypot(x_s[0] - oc[0], x_s[1] - oc[1]))
    k_s = np.arctan2(start.beta[2::2], start.beta[3::2])
    v_s = np.hypot(start.beta[2::2], start.beta[3::2])
    k_c, v_c = k_s.copy(), v_s.copy()
    for j, b in enumerate(per_leg):
        if b is None:
            continue
        lb[3 + 2 * j], ub[3 + 2 * j] = b.v_min, b.v_max
        v_c[j] = 0.5 * (b.v_min + b.v_max)
        if b.course_width < TWO_PI:
            lb[2 + 2 * j], ub[2 + 2 * j] = b.k_min, b.k_min + b.course_width
            k_s[j] = _course_into(k_s[j], b)
            k_c[j] = b.k_min + 0.5 * b.course_width
    kv_s = np.ravel(np.column_stack((k_s, v_s)))
    kv_c = np.ravel(np.column_stack((k_c, v_c)))
    starts = [
        np.concatenate(([np.arctan2(x_s[0] - oc[0], x_s[1] - oc[1]), r_s], kv_s)),
        np.concatenate(([brg[m], np.sqrt(bounds.r_min * bounds.r_max)], kv_c)),
    ]
    fin_lb, fin_ub = np.isfinite(lb), np.isfinite(ub)
    span = np.where(fin_lb & fin_ub, ub - lb, 0.0)
    best = None
    for x0 in starts:
        x0 = np.where(fin_lb, np.maximum(x0, lb + 1e-6 * span + 1e-9), x0)
        x0 = np.where(fin_ub, np.minimum(x0, ub - 1e-6 * span - 1e-9), x0)
        res = least_squares(fun, x0, jac=jac, bounds=(lb, ub), method="trf", x_scale="jac", max_nfev=200)
        if best is None or res.cost < best.cost:
            best = res
    beta, _ = to_beta(best.x)
    d, Hw, r = weighted_system(beta, t, brg, sb, own_xy, t0, support, legs)
    return TmaSolution(beta, covariance(Hw), float(t0), legs, r, float(d @ d), int(best.nfev), bool(best.status > 0),
                       float(t[m]))
