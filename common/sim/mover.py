"""Motion of the simulator's targets and own ship (a ``Mover`` of a scenario file, parsed by
common.sim.scenario): an initial state at ``t_on`` followed by legs; between legs a
mover flies straight at constant velocity or turns horizontally at a constant rate at
constant speed (coordinated turn), climbing at a constant ``vz``. Angles in radians,
clockwise from North.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_2pi


@dataclass(frozen=True)
class Segment:
    """A piece of motion from time t0: course (rad), speed (m/s), vz, turn rate (rad/s)."""

    t0: float
    pos: np.ndarray
    course: float
    speed: float
    vz: float
    omega: float


@dataclass(frozen=True)
class Leg:
    """A manoeuvre at time t; unset fields keep the current value."""

    t: float
    course: float | None = None
    speed: float | None = None
    vz: float | None = None
    turn_rate: float | None = None


@dataclass(frozen=True)
class Mover:
    """A target or own ship: state at ``t_on``, legs, present for t_on <= t < t_off."""

    id: int
    pos: np.ndarray
    course: float
    speed: float
    vz: float = 0.0
    legs: tuple[Leg, ...] = ()
    t_on: float = 0.0
    t_off: float = math.inf
    sl_db: float = 0.0
    lines_hz: tuple[float, ...] = ()

    def segments(self) -> list[Segment]:
        """Piecewise motion; a leg with course and turn rate turns, then flies straight."""
        segs = [Segment(self.t_on, self.pos, self.course, self.speed, self.vz, 0.0)]
        for leg in self.legs:
            pos, vel, _ = _eval(segs, np.array([leg.t]))
            course = float(np.arctan2(vel[0, 0], vel[0, 1])) if np.any(vel[0, :2]) else self.course
            speed = leg.speed if leg.speed is not None else float(np.hypot(vel[0, 0], vel[0, 1]))
            vz = leg.vz if leg.vz is not None else float(vel[0, 2])
            segs = [s for s in segs if s.t0 < leg.t]
            if leg.turn_rate is None:
                new = leg.course if leg.course is not None else course
                segs.append(Segment(leg.t, pos[0], new, speed, vz, 0.0))
            elif leg.course is None:
                segs.append(Segment(leg.t, pos[0], course, speed, vz, leg.turn_rate))
            else:
                turn = math.copysign(1.0, leg.turn_rate)
                dur = wrap_2pi((leg.course - course) * turn) / abs(leg.turn_rate)
                segs.append(Segment(leg.t, pos[0], course, speed, vz, leg.turn_rate))
                end_pos, _, _ = _eval(segs, np.array([leg.t + dur]))
                segs.append(Segment(leg.t + dur, end_pos[0], leg.course, speed, vz, 0.0))
        return segs

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (T, 3), velocities (T, 3) and presence mask (T,) at times t."""
        t = np.asarray(t, dtype=float)
        pos, vel, _ = _eval(self.segments(), t)
        return pos, vel, (t >= self.t_on) & (t < self.t_off)

    def headings(self, t: np.ndarray) -> np.ndarray:
        """Course over ground (rad, clockwise from North, [0, 2pi)) at times t."""
        return wrap_2pi(_eval(self.segments(), np.asarray(t, dtype=float))[2])


def _eval(segs: list[Segment], t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions, velocities and courses of piecewise straight / turning motion at t."""
    t0 = np.array([s.t0 for s in segs])
    i = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, None)
    p0 = np.array([s.pos for s in segs])[i]
    c0 = np.array([s.course for s in segs])[i]
    sp = np.array([s.speed for s in segs])[i]
    vz = np.array([s.vz for s in segs])[i]
    om = np.array([s.omega for s in segs])[i]
    dt = t - t0[i]
    c = c0 + om * dt
    turning = np.abs(om) > 1e-12
    safe = np.where(turning, om, 1.0)
    dx = np.where(turning, sp / safe * (np.cos(c0) - np.cos(c)), sp * np.sin(c0) * dt)
    dy = np.where(turning, sp / safe * (np.sin(c) - np.sin(c0)), sp * np.cos(c0) * dt)
    pos = p0 + np.stack([dx, dy, vz * dt], axis=-1)
    vel = np.stack([sp * np.sin(c), sp * np.cos(c), vz], axis=-1)
    return pos, vel, c
