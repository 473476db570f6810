"""Constrained TMA with detection and correction of wrong bounds (seed 003, ES 2 400 413).

Per processing cycle (003 Fig. 2 and 6, claims 1-3): the TMA solution of ``common.sonar.tma.bearings_only``
is compared with the bounds on range R, course K and speed V; inside them it is the
answer. Otherwise the constrained TMA (CTMA) runs; before the convergence instant of the
TMA (convergence detector 78) the CTMA solution is output with its bounds; after it the
error handling 14 runs: feasibility check 38 (residual check 42 with the residual factor
Q, edge checks 52 and 54) and correction module 40 (re-centre the violated intervals, at
most ``max_corrections`` times a cycle, then minimal bounds 75 when Q is high).

R, K, V and the bounds refer to the current time (latest bearing) of each cycle; the
bounds, the edge checks and the correction are in ``common.sonar.tma.bounds``, the
constrained solve in ``common.sonar.tma.constrained_solve``. With
target legs each leg has its own course and speed bounds (003 claim 9, paragraph 55);
the error handling checks and corrects those of the current leg.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Sequence

import numpy as np
from scipy.special import chdtri

from common.core.params import INF, PROB_OPEN, Params, Range, Rule, count, order, positive
from common.sonar.tma.bearings_only import Support, TmaSolution, detect_manoeuvre, solve_tma
from common.sonar.tma.bounds import (
    MINIMAL_BOUNDS,
    Bounds,
    edge_flags,
    effective_bounds,
    recentre,
    rkv,
    state_bounds,
)
from common.sonar.tma.constrained_solve import legs_inside, new_leg_bounds, solve_ctma


@dataclass(frozen=True)
class CtmaParams(Params):
    """Parameters of the TMA/CTMA cycle (``[sonar.tma.ctma]``).

    q1, q2, q3: residual-factor thresholds (q1 > q2 > q3) over 1, 2, 3 consecutive
        cycles (003 Fig. 4).
    q_minimal: Q above which minimal bounds replace the corrected ones (003 Fig. 5).
    edge_tol: fraction of an interval width within which a value is "on the edge".
    edge_cycles: consecutive cycles on the edge that make an edge error.
    max_corrections: bound corrections allowed per cycle (003 Fig. 5: 3).
    roc_window, roc_threshold: convergence detector: cycles in the window and relative
        spread of the estimated range below which the solution is "post" (003 Fig. 6).
    tma_tol, max_iter: Gauss-Newton stop rule of 002 claim 17 (||Delta p|| in m) and
        the iteration cap.
    detect_manoeuvres: run the residual-based manoeuvre detector after convergence; a
        new leg gets its own bounds (course free), the earlier one keeps its (003 claim 9).
    manoeuvre_p_false: false alarm probability of that detector (Bonferroni-corrected).
    """

    q1: float = 2.0
    q2: float = 1.5
    q3: float = 1.25
    q_minimal: float = 1.5
    edge_tol: float = 0.02
    edge_cycles: int = 2
    max_corrections: int = 3
    roc_window: int = 5
    roc_threshold: float = 0.05
    tma_tol: float = 1.0
    max_iter: int = 50
    detect_manoeuvres: bool = False
    manoeuvre_p_false: float = 1e-3

    RANGES: ClassVar[dict[str, Range]] = {
        "q1": Range("", 1.0, INF, "()"), "q2": Range("", 1.0, INF, "()"),
        "q3": Range("", 1.0, INF, "()"), "q_minimal": Range("", 1.0, INF, "()"),
        "edge_tol": Range("fraction", 0.0, 0.5, "[)"), "edge_cycles": count(1),
        "max_corrections": count(0), "roc_window": count(2),
        "roc_threshold": positive("fraction"), "tma_tol": positive("m"), "max_iter": count(1),
        "manoeuvre_p_false": PROB_OPEN,
    }
    RULES: ClassVar[tuple[Rule, ...]] = (order("q2", "q1"), order("q3", "q2"))


def residual_factor(ctma_res: np.ndarray, tma_res: np.ndarray, sbrg: np.ndarray | float) -> float:
    """Q = sum|CTMA residuals| / sum|TMA residuals|, residuals weighted by 1/sigma (003 Fig. 4, block 46)."""
    s = np.asarray(sbrg, float)
    return float(np.sum(np.abs(ctma_res) / s) / max(np.sum(np.abs(tma_res) / s), 1e-300))


def residual_alarm(q_history: Sequence[float], cfg: CtmaParams) -> bool:
    """Residual check 42/48: Q >= q1 once, >= q2 in 2 or >= q3 in 3 consecutive cycles."""
    q = np.asarray(q_history, float)
    return bool(
        (q.size >= 1 and q[-1] >= cfg.q1)
        or (q.size >= 2 and np.all(q[-2:] >= cfg.q2))
        or (q.size >= 3 and np.all(q[-3:] >= cfg.q3))
    )


class ConvergenceDetector:
    """Convergence phase detector 78 (003 Fig. 6).

    ROC = spread of the target range over the last ``window`` TMA solutions, each
    propagated to the current time and measured from the current own position, as
    std / mean. Deviation: relative rather than absolute spread, so that one threshold
    fits all ranges. "post" is latched once ROC <= threshold.
    """

    def __init__(self, window: int = 5, threshold: float = 0.05) -> None:
        self.window = window
        self.threshold = threshold
        self.states: list[tuple[float, np.ndarray]] = []
        self.roc = np.inf
        self.phase = "pre"

    def update(self, t: float, own_c: np.ndarray, state: np.ndarray | None) -> str:
        """Add the TMA state (x, y, vx, vy) at time ``t`` (None: TMA failed); return the phase."""
        self.states.append((t, None if state is None else np.asarray(state, float)))
        self.states = self.states[-self.window:]
        if len(self.states) < self.window or any(s is None for _, s in self.states):
            self.roc = np.inf
        else:
            r = np.array([np.hypot(s[0] + s[2] * (t - ts) - own_c[0], s[1] + s[3] * (t - ts) - own_c[1])
                          for ts, s in self.states])
            self.roc = float(np.std(r) / np.mean(r))
        if self.roc <= self.threshold:
            self.phase = "post"
        return self.phase


@dataclass(frozen=True)
class CycleOutput:
    """One processing cycle's target data at time ``t`` (current = latest bearing).

    ``residual_factor`` is 1.0 when the TMA solution was inside the bounds (CTMA = TMA).
    ``legs`` are the manoeuvre times in use. ``converged``: the solve of this solution met
    its stop rule (TMA: 002 claim 17 within ``max_iter``; CTMA: the solver's tolerance,
    not its evaluation cap). ``ctma_exhausted``: a CTMA solution whose error (003 Fig. 4-5)
    remained after ``max_corrections`` corrections and the minimal-bounds fall-back.
    ``range_observable``: :func:`range_observable`.
    """

    t: float
    x: float
    y: float
    vx: float
    vy: float
    P: np.ndarray
    range: float
    course: float
    speed: float
    constrained: bool
    bounds: Bounds | None
    bounds_modified: bool
    phase: str
    residual_factor: float
    legs: tuple[float, ...]
    roc: float
    converged: bool
    ctma_exhausted: bool
    range_observable: bool


RANGE_SIGMA_RATIO = 0.5


def range_observable(x: np.ndarray, P: np.ndarray, own_c: np.ndarray) -> bool:
    """Range observable from the bearings: sigma_R <= 0.5 R, with sigma_R^2 = g P g' the
    variance of the range R of x (x, y, vx, vy) from own_c under its covariance P
    ((H'WH)^-1 of 002 eq. 7-8), g = dR/dx. Bearings alone fix the range only after an
    own-ship manoeuvre (or with a range support value, 002 claims 3-10); without one
    sigma_R is orders of magnitude above R.
    """
    d = np.asarray(x[:2], float) - own_c
    r = float(np.hypot(d[0], d[1]))
    g = np.concatenate((d / max(r, 1e-300), (0.0, 0.0)))[None, :]
    sigma = float(np.sqrt((g @ P @ g.T)[0, 0]))
    return bool(sigma <= RANGE_SIGMA_RATIO * r)


class TmaTracker:
    """Per-track TMA/CTMA processor: one :meth:`update` per new bearing batch (003 claims 1-3).

    ``bounds`` are those of the current target leg; the error handling corrects them and
    a bounds message replaces them. When a leg is added at a manoeuvre time T_A (002
    claim 13), the earlier leg keeps in ``leg_bounds`` the bounds in force after the last
    cycle at or before T_A (the original ones: corrections made after T_A fitted one leg
    to a manoeuvring target) and the new leg gets :func:`new_leg_bounds` of the current
    ones (003 claim 9). Falling back to the minimal bounds replaces those of every leg.
    """

    def __init__(self, bounds: Bounds | None = None, config: CtmaParams = CtmaParams()) -> None:
        self.bounds = bounds
        self.cfg = config
        self.t = np.empty(0)
        self.brg = np.empty(0)
        self.sbrg = np.empty(0)
        self.own = np.empty((0, 2))
        self.support: list[Support] = []
        self.legs: tuple[float, ...] = ()
        self.leg_bounds: tuple[Bounds | None, ...] = ()
        self.bounds_hist: list[tuple[float, Bounds | None]] = []
        self.t0: float | None = None
        self.tma: TmaSolution | None = None
        self.detector = ConvergenceDetector(config.roc_window, config.roc_threshold)
        self.q_hist: list[float] = []
        self.edge_streak = np.zeros((2, 3), int)

    def _solve_tma(self) -> TmaSolution:
        args = (self.t, self.brg, self.sbrg, self.own, self.t0)
        kw = dict(support=self.support, legs=self.legs, tol=self.cfg.tma_tol, max_iter=self.cfg.max_iter)
        cold = solve_tma(*args, **kw)
        if self.tma is None or not self.tma.converged:
            return cold
        warm = solve_tma(*args, beta0=self.tma.beta, **kw)
        return warm if warm.converged and warm.cost <= cold.cost else cold

    def update(
        self, t: np.ndarray, brg: np.ndarray, sbrg: np.ndarray | float, own_xy: np.ndarray,
        support: Sequence[Support] = (),
    ) -> CycleOutput | None:
        """Add bearings (times, bearings, sigmas, own positions (N, 2)) and run one cycle.

        Returns None while fewer than 4 bearings are known.
        """
        t = np.atleast_1d(np.asarray(t, float))
        self.t = np.concatenate((self.t, t))
        self.brg = np.concatenate((self.brg, np.atleast_1d(brg)))
        self.sbrg = np.concatenate((self.sbrg, np.broadcast_to(np.asarray(sbrg, float), t.shape)))
        self.own = np.vstack((self.own, np.asarray(own_xy, float).reshape(-1, 2)))
        self.support.extend(support)
        if self.t0 is None:
            self.t0 = float(self.t.min())
        if self.t.size < 4:
            return None
        m = int(np.argmax(self.t))
        tc, oc = float(self.t[m]), self.own[m]
        tma = self._solve_tma()
        self.tma = tma
        phase = self.detector.update(tc, oc, tma.state_at(tc)[0] if tma.converged else None)
        if self.cfg.detect_manoeuvres and phase == "post":
            tma = self._manoeuvre(tma)
        out = self._constrain(tma, tc, oc, phase)
        if self.cfg.detect_manoeuvres:
            self.bounds_hist.append((tc, self.bounds))
        return out

    def _manoeuvre(self, tma: TmaSolution) -> TmaSolution:
        """Add a leg when the residuals reject the current legs (002 claim 13)."""
        dof = self.t.size - tma.beta.size
        if dof <= 0 or tma.cost <= chdtri(dof, 0.01):  # chi2 upper 1 % quantile
            return tma
        ta = detect_manoeuvre(self.t, self.brg, self.sbrg, self.own, self.t0, tma, self.support,
                              p_false=self.cfg.manoeuvre_p_false)
        if ta is None:
            return tma
        self.legs = self.legs + (ta,)
        k = max(0, sum(tb <= ta for tb, _ in self.bounds_hist) - 1)
        leg = self.bounds_hist[k][1] if self.bounds_hist else self.bounds
        self.leg_bounds = self.leg_bounds + (leg,)  # 003 claim 9
        self.bounds_hist = self.bounds_hist[k:]
        if self.bounds is not None:
            self.bounds = new_leg_bounds(self.bounds)
        self.tma = self._solve_tma()
        return self.tma

    def _output(self, sol: TmaSolution, tc: float, oc: np.ndarray, constrained: bool, modified: bool,
                phase: str, q: float, exhausted: bool = False) -> CycleOutput:
        x, P = sol.state_at(tc)
        r, k, v = rkv(x, oc)
        return CycleOutput(tc, *map(float, x), P, r, k, v, constrained, self.bounds, modified, phase, q,
                           self.legs, self.detector.roc, sol.converged, exhausted, range_observable(x, P, oc))

    def _inside(self, tma: TmaSolution, rkv_t: tuple[float, float, float]) -> bool:
        """The TMA solution lies in the bounds of every leg (003 claims 2b and 9)."""
        return self.bounds is None or (self.bounds.contains(*rkv_t) and legs_inside(tma.beta, self.leg_bounds))

    def _constrain(self, tma: TmaSolution, tc: float, oc: np.ndarray, phase: str) -> CycleOutput:
        """TMA inside bounds -> TMA; else CTMA, and after convergence the error handling 14."""
        cfg = self.cfg
        x_t, _ = tma.state_at(tc)
        rkv_t = rkv(x_t, oc)
        if self._inside(tma, rkv_t):
            self.q_hist.append(1.0)
            self.edge_streak[:] = 0
            return self._output(tma, tc, oc, False, False, phase, 1.0)
        modified = exhausted = False
        z = 0
        data = (self.t, self.brg, self.sbrg, self.own, self.t0)
        while True:
            ctma = solve_ctma(*data, self.bounds, tma, self.support, self.legs, self.leg_bounds)
            q = residual_factor(ctma.residuals, tma.residuals, self.sbrg)
            if phase == "pre":
                self.q_hist.append(q)
                return self._output(ctma, tc, oc, True, modified, phase, q)
            x_c, _ = ctma.state_at(tc)
            r, k, v = rkv(x_c, oc)
            brg_c = float(np.arctan2(x_c[0] - oc[0], x_c[1] - oc[1]))
            eff = effective_bounds(*state_bounds(self.bounds, oc, brg_c), oc)
            flags = np.stack((edge_flags(r, k, v, self.bounds, cfg.edge_tol), edge_flags(r, k, v, eff, cfg.edge_tol)))
            streak = np.where(flags, self.edge_streak + 1, 0)
            edge_err = np.any(streak >= cfg.edge_cycles, axis=0)
            res_err = residual_alarm(self.q_hist + [q], cfg)
            if not (res_err or edge_err.any()):
                break
            if z >= cfg.max_corrections:
                if q > cfg.q_minimal and self.bounds != MINIMAL_BOUNDS:
                    self.bounds, modified = MINIMAL_BOUNDS, True
                    self.leg_bounds = tuple(None if b is None else MINIMAL_BOUNDS for b in self.leg_bounds)
                    if self._inside(tma, rkv_t):
                        self.q_hist.append(1.0)
                        self.edge_streak[:] = 0
                        return self._output(tma, tc, oc, False, True, phase, 1.0)
                    continue
                exhausted = True
                break
            to_fix = flags.any(axis=0) if flags.any() else self.bounds.violations(*rkv_t)
            self.bounds = recentre(self.bounds, to_fix, r, k, v)
            modified = True
            z += 1
            if self._inside(tma, rkv_t):
                self.q_hist.append(1.0)
                self.edge_streak[:] = 0
                return self._output(tma, tc, oc, False, True, phase, 1.0)
        self.q_hist.append(q)
        self.edge_streak = streak
        return self._output(ctma, tc, oc, True, modified, phase, q, exhausted)
