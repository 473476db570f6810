"""Validation helpers of the scenario parsers (common.sim.scenario,
common.sim.radar_scenario): typed reads of TOML tables that raise
:class:`~common.deploy.config.ConfigError` naming the key, and the movers' tables."""

from __future__ import annotations

import math
from typing import Any, TypeVar

import numpy as np

from common.core.params import ParamError, Params, Range
from common.deploy.config import ConfigError
from common.sim.mover import Leg, Mover

PD = Range("probability", 0.0, 1.0)
CLUTTER = Range("mean count per scan", 0.0, 1e4)
DB = "any level in dB"
P = TypeVar("P", bound=Params)


def table(v: Any, key: str, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise ConfigError(key, "expected a table")
    unknown = set(v) - allowed
    if unknown:
        known = ", ".join(sorted(allowed))
        raise ConfigError(f"{key}.{sorted(unknown)[0]}", f"unknown key (known: {known})")
    return v


def num(t: dict[str, Any], k: str, key: str, default: float | None = None, lo: float = -math.inf,
         hi: float = math.inf, lo_open: bool = False) -> float:
    if k not in t:
        if default is None:
            raise ConfigError(f"{key}.{k}", "missing")
        return default
    v = t[k]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ConfigError(f"{key}.{k}", f"expected a finite number, got {v!r}")
    if v < lo or v > hi or (lo_open and v == lo):
        raise ConfigError(f"{key}.{k}", f"{v} out of range {'(' if lo_open else '['}{lo}, {hi}]")
    return float(v)


def vec(t: dict[str, Any], k: str, key: str, dims: tuple[int, ...]) -> np.ndarray:
    v = t.get(k)
    ok = isinstance(v, list) and len(v) in dims and all(
        isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in v
    )
    if not ok:
        raise ConfigError(f"{key}.{k}", f"expected a list of {' or '.join(map(str, dims))} numbers")
    return np.concatenate([np.asarray(v, dtype=float), np.zeros(3 - len(v))])


def course_speed(vel: np.ndarray) -> tuple[float, float]:
    return float(np.arctan2(vel[0], vel[1])), float(np.hypot(vel[0], vel[1]))


LEG_KEYS = {"t", "vel", "course_deg", "speed", "vz", "turn_rate_deg"}


def read_leg(t: Any, key: str, t_min: float) -> Leg:
    t = table(t, key, LEG_KEYS)
    tt = num(t, "t", key, lo=t_min)
    if "vel" in t:
        if set(t) & {"course_deg", "speed", "turn_rate_deg"}:
            raise ConfigError(f"{key}.vel", "give either vel or course_deg/speed/turn_rate_deg")
        vel = vec(t, "vel", key, (2, 3))
        c, s = course_speed(vel)
        return Leg(tt, c, s, float(vel[2]) if len(t["vel"]) == 3 else num(t, "vz", key, 0.0))
    if not set(t) - {"t"}:
        raise ConfigError(f"{key}.t", "a leg needs vel, course_deg, speed, vz or turn_rate_deg")
    course = math.radians(num(t, "course_deg", key)) if "course_deg" in t else None
    rate = num(t, "turn_rate_deg", key, lo=-30.0, hi=30.0) if "turn_rate_deg" in t else None
    if rate == 0.0:
        raise ConfigError(f"{key}.turn_rate_deg", "must be non-zero")
    return Leg(
        tt,
        course,
        num(t, "speed", key, lo=0.0) if "speed" in t else None,
        num(t, "vz", key) if "vz" in t else None,
        math.radians(rate) if rate is not None else None,
    )


AIR_KEYS = {"id", "pos", "vel", "course_deg", "speed", "vz", "t_on", "t_off", "leg"}
SEA_KEYS = AIR_KEYS - {"vz"} | {"sl_db", "lines_hz"}
OWN_KEYS = AIR_KEYS - {"vz", "id", "t_on", "t_off"}


def mover(t: Any, key: str, allowed: set[str], dims: tuple[int, ...]) -> tuple[Mover, dict[str, Any]]:
    """A mover from its table; 2-D movers (dims (2,)) stay at z = 0."""
    t = table(t, key, allowed)
    mid = 0
    if "id" in allowed:
        mid = t.get("id")
        if not isinstance(mid, int) or isinstance(mid, bool) or mid < 0:
            raise ConfigError(f"{key}.id", "must be an integer >= 0")
    pos = vec(t, "pos", key, dims)
    if "vel" in t:
        if "course_deg" in t or "speed" in t:
            raise ConfigError(f"{key}.vel", "give either vel or course_deg + speed")
        vel = vec(t, "vel", key, dims)
        course, speed = course_speed(vel)
        vz = float(vel[2])
    else:
        course = math.radians(num(t, "course_deg", key))
        speed = num(t, "speed", key, lo=0.0)
        vz = num(t, "vz", key, 0.0)
    t_on = num(t, "t_on", key, 0.0, lo=0.0)
    t_off = num(t, "t_off", key, math.inf, lo=t_on, lo_open=True)
    raw_legs = t.get("leg", [])
    if not isinstance(raw_legs, list):
        raise ConfigError(f"{key}.leg", "expected an array of tables [[...leg]]")
    legs, t_prev = [], t_on
    for i, lg in enumerate(raw_legs):
        leg = read_leg(lg, f"{key}.leg[{i}]", t_prev)
        legs.append(leg)
        t_prev = leg.t
    return Mover(mid, pos, course, speed, vz, tuple(legs), t_on, t_off), t


def checked(cls: type[P], key: str, **values: Any) -> P:
    """``cls(**values)``, a ParamError as a ConfigError naming the file's key."""
    try:
        return cls(**values)
    except ParamError as e:
        name = "saz_deg" if e.keys[0] == "saz" else e.keys[0]
        raise ConfigError(f"{key}.{name}", f"[{key}] {e.detail}") from None


def unique_ids(movers: list[Mover], key: str) -> None:
    ids = [m.id for m in movers]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{key}.id", "target ids must be unique")


def listed(t: dict[str, Any], k: str, key: str) -> list[Any]:
    v = t.get(k, [])
    if not isinstance(v, list):
        raise ConfigError(f"{key}.{k}", "expected an array of tables")
    return v
