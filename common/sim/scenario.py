"""Scenario description for the simulator: the ``[sim]`` tables of a scenario file.

:func:`load_scenario` validates the parsed TOML and returns a :class:`Scenario`;
any bad value raises :class:`~common.deploy.config.ConfigError` (a ``ValueError``) naming the
key. Units: metres, seconds, m/s; angles in the file are degrees (keys ending in
``_deg``), everywhere else radians, clockwise from North. docs/scenarios.md lists
every key.

Motion of the targets and own ship: common.sim.mover. In a geodetic deployment (one
with [radar.origin]) a radar target's z is its WGS-84 ellipsoidal height and its
(x, y) track runs in the tangent plane (common.sim.simulator lifts it to that height).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

import numpy as np

from common.core.params import ParamError, Params, Range, Rule, ascending_pair, non_negative, positive, unbounded
from common.deploy.config import Config, ConfigError
from common.deploy.positions import geo_origin
from common.radar.geometry.geodesy import LocalFrame
from common.sim.mover import Leg, Mover

MODES = ("broadband", "narrowband")
PD = Range("probability", 0.0, 1.0)
CLUTTER = Range("mean count per scan", 0.0, 1e4)
DB = "any level in dB"
P = TypeVar("P", bound=Params)


@dataclass(frozen=True)
class RadarChannelSim(Params):
    """Per-channel radar sensor model: pd, clutter mean, sigmas, reference SNR."""

    pd: float = 0.9
    clutter: float = 1.0
    srb: float = 150.0
    svb: float = 2.0
    saz: float = math.radians(1.5)
    snr_db: float = 15.0

    RANGES: ClassVar[dict[str, Range]] = {
        "pd": PD, "clutter": CLUTTER, "srb": positive("m"), "svb": positive("m/s"),
        "saz": Range("rad", 0.0, math.pi, "(]"), "snr_db": unbounded("dB", DB),
    }


@dataclass(frozen=True)
class RadarSim:
    """Radar part of a scenario."""

    default: RadarChannelSim
    channels: dict[str, RadarChannelSim]
    targets: list[Mover]
    scan_period: float
    rb_max: float = 200e3
    vb_max: float = 600.0
    snr_threshold_db: float = 10.0
    snr_sigma_db: float = 1.0
    snr_ref_range: float = 50e3
    clutter_snr_db: float = 2.0
    timing: dict[str, tuple[float, float]] = field(default_factory=dict)  # base: period, phase

    def channel(self, cid: str) -> RadarChannelSim:
        return self.channels.get(cid, self.default)

    def base_times(self, base: str, duration: float) -> np.ndarray:
        """Scan times of a base: phase + k period in [0, duration) ([sim.radar.base.<id>]),
        else the common k scan_period."""
        period, phase = self.timing.get(base, (self.scan_period, 0.0))
        return phase + np.arange(int(np.ceil((duration - phase) / period - 1e-9))) * period


@dataclass(frozen=True)
class SonarArraySim(Params):
    """Per-array sonar sensor model (array kind and sigma0 come from the deployment)."""

    mode: str = "broadband"
    pd: float = 0.9
    clutter: float = 1.0
    di_db: float = 15.0
    nl_db: float = 65.0
    snr_threshold_db: float = 3.0
    sigma_amp_db: float = 2.0
    clutter_snr_db: float = 2.0
    endfire_deg: float = 10.0
    sfreq_hz: float = 0.05
    band_hz: tuple[float, float] = (10.0, 1000.0)

    RANGES: ClassVar[dict[str, Range]] = {
        "pd": PD, "clutter": CLUTTER, "di_db": unbounded("dB", DB), "nl_db": unbounded("dB", DB),
        "snr_threshold_db": unbounded("dB", DB), "sigma_amp_db": non_negative("dB"),
        "clutter_snr_db": positive("dB"), "endfire_deg": Range("deg", 0.0, 90.0, "(]"),
        "sfreq_hz": positive("Hz"), "band_hz": positive("Hz"),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (ascending_pair("band_hz"),)


@dataclass(frozen=True)
class SonarSim:
    """Sonar part of a scenario: own ship, targets, per-array models."""

    own: Mover
    default: SonarArraySim
    arrays: dict[str, SonarArraySim]
    targets: list[Mover]
    scan_period: float
    alpha_db_km: float = 0.1
    sound_speed: float = 1500.0

    def array(self, aid: str) -> SonarArraySim:
        return self.arrays.get(aid, self.default)


@dataclass(frozen=True)
class Scenario:
    """A parsed ``[sim]`` section: horizon, and optional radar and sonar parts; origin
    is the file's [radar.origin] (None: a flat deployment)."""

    duration: float
    radar: RadarSim | None = None
    sonar: SonarSim | None = None
    name: str = ""
    origin: LocalFrame | None = None


# ---------------------------------------------------------------- parsing helpers


def _table(v: Any, key: str, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise ConfigError(key, "expected a table")
    unknown = set(v) - allowed
    if unknown:
        known = ", ".join(sorted(allowed))
        raise ConfigError(f"{key}.{sorted(unknown)[0]}", f"unknown key (known: {known})")
    return v


def _num(t: dict[str, Any], k: str, key: str, default: float | None = None, lo: float = -math.inf,
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


def _vec(t: dict[str, Any], k: str, key: str, dims: tuple[int, ...]) -> np.ndarray:
    v = t.get(k)
    ok = isinstance(v, list) and len(v) in dims and all(
        isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in v
    )
    if not ok:
        raise ConfigError(f"{key}.{k}", f"expected a list of {' or '.join(map(str, dims))} numbers")
    return np.concatenate([np.asarray(v, dtype=float), np.zeros(3 - len(v))])


def _course_speed(vel: np.ndarray) -> tuple[float, float]:
    return float(np.arctan2(vel[0], vel[1])), float(np.hypot(vel[0], vel[1]))


_LEG_KEYS = {"t", "vel", "course_deg", "speed", "vz", "turn_rate_deg"}


def _leg(t: Any, key: str, t_min: float) -> Leg:
    t = _table(t, key, _LEG_KEYS)
    tt = _num(t, "t", key, lo=t_min)
    if "vel" in t:
        if set(t) & {"course_deg", "speed", "turn_rate_deg"}:
            raise ConfigError(f"{key}.vel", "give either vel or course_deg/speed/turn_rate_deg")
        vel = _vec(t, "vel", key, (2, 3))
        c, s = _course_speed(vel)
        return Leg(tt, c, s, float(vel[2]) if len(t["vel"]) == 3 else _num(t, "vz", key, 0.0))
    if not set(t) - {"t"}:
        raise ConfigError(f"{key}.t", "a leg needs vel, course_deg, speed, vz or turn_rate_deg")
    course = math.radians(_num(t, "course_deg", key)) if "course_deg" in t else None
    rate = _num(t, "turn_rate_deg", key, lo=-30.0, hi=30.0) if "turn_rate_deg" in t else None
    if rate == 0.0:
        raise ConfigError(f"{key}.turn_rate_deg", "must be non-zero")
    return Leg(
        tt,
        course,
        _num(t, "speed", key, lo=0.0) if "speed" in t else None,
        _num(t, "vz", key) if "vz" in t else None,
        math.radians(rate) if rate is not None else None,
    )


_AIR_KEYS = {"id", "pos", "vel", "course_deg", "speed", "vz", "t_on", "t_off", "leg"}
_SEA_KEYS = _AIR_KEYS - {"vz"} | {"sl_db", "lines_hz"}
_OWN_KEYS = _AIR_KEYS - {"vz", "id", "t_on", "t_off"}


def _mover(t: Any, key: str, allowed: set[str], dims: tuple[int, ...]) -> tuple[Mover, dict[str, Any]]:
    """A mover from its table; 2-D movers (dims (2,)) stay at z = 0."""
    t = _table(t, key, allowed)
    mid = 0
    if "id" in allowed:
        mid = t.get("id")
        if not isinstance(mid, int) or isinstance(mid, bool) or mid < 0:
            raise ConfigError(f"{key}.id", "must be an integer >= 0")
    pos = _vec(t, "pos", key, dims)
    if "vel" in t:
        if "course_deg" in t or "speed" in t:
            raise ConfigError(f"{key}.vel", "give either vel or course_deg + speed")
        vel = _vec(t, "vel", key, dims)
        course, speed = _course_speed(vel)
        vz = float(vel[2])
    else:
        course = math.radians(_num(t, "course_deg", key))
        speed = _num(t, "speed", key, lo=0.0)
        vz = _num(t, "vz", key, 0.0)
    t_on = _num(t, "t_on", key, 0.0, lo=0.0)
    t_off = _num(t, "t_off", key, math.inf, lo=t_on, lo_open=True)
    raw_legs = t.get("leg", [])
    if not isinstance(raw_legs, list):
        raise ConfigError(f"{key}.leg", "expected an array of tables [[...leg]]")
    legs, t_prev = [], t_on
    for i, lg in enumerate(raw_legs):
        leg = _leg(lg, f"{key}.leg[{i}]", t_prev)
        legs.append(leg)
        t_prev = leg.t
    return Mover(mid, pos, course, speed, vz, tuple(legs), t_on, t_off), t


_RCH_KEYS = {"pd", "clutter", "srb", "svb", "saz_deg", "snr_db"}


def _checked(cls: type[P], key: str, **values: Any) -> P:
    """``cls(**values)``, a ParamError as a ConfigError naming the file's key."""
    try:
        return cls(**values)
    except ParamError as e:
        name = "saz_deg" if e.keys[0] == "saz" else e.keys[0]
        raise ConfigError(f"{key}.{name}", f"[{key}] {e.detail}") from None


def _radar_channel(t: dict[str, Any], key: str, base: RadarChannelSim) -> RadarChannelSim:
    return _checked(
        RadarChannelSim, key,
        pd=_num(t, "pd", key, base.pd),
        clutter=_num(t, "clutter", key, base.clutter),
        srb=_num(t, "srb", key, base.srb),
        svb=_num(t, "svb", key, base.svb),
        saz=math.radians(_num(t, "saz_deg", key, math.degrees(base.saz))),
        snr_db=_num(t, "snr_db", key, base.snr_db),
    )


def _unique_ids(movers: list[Mover], key: str) -> None:
    ids = [m.id for m in movers]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{key}.id", "target ids must be unique")


def _radar(t: Any, period: float) -> RadarSim:
    key = "sim.radar"
    win = {"rb_max", "vb_max", "snr_threshold_db", "snr_sigma_db", "snr_ref_range",
           "clutter_snr_db", "channel", "target", "base"}
    t = _table(t, key, _RCH_KEYS | win)
    default = _radar_channel(t, key, RadarChannelSim())
    chans_raw = _table(t.get("channel", {}), f"{key}.channel", set(t.get("channel", {})))
    chans = {
        c: _radar_channel(_table(v, f"{key}.channel.{c}", _RCH_KEYS), f"{key}.channel.{c}", default)
        for c, v in chans_raw.items()
    }
    targets = [
        _mover(m, f"{key}.target[{i}]", _AIR_KEYS, (3,))[0]
        for i, m in enumerate(_list(t, "target", key))
    ]
    _unique_ids(targets, f"{key}.target")
    timing = {}
    for b, v in _table(t.get("base", {}), f"{key}.base", set(t.get("base", {}))).items():
        k = f"{key}.base.{b}"
        v = _table(v, k, {"period", "phase"})
        bp = _num(v, "period", k, period, 0.0, lo_open=True)
        timing[b] = (bp, _num(v, "phase", k, 0.0, 0.0, bp))
        if timing[b][1] == bp:
            raise ConfigError(f"{k}.phase", f"must be below the period {bp}")
    return RadarSim(
        default, chans, targets, period, timing=timing,
        rb_max=_num(t, "rb_max", key, 200e3, 0.0, lo_open=True),
        vb_max=_num(t, "vb_max", key, 600.0, 0.0, lo_open=True),
        snr_threshold_db=_num(t, "snr_threshold_db", key, 10.0),
        snr_sigma_db=_num(t, "snr_sigma_db", key, 1.0, 0.0),
        snr_ref_range=_num(t, "snr_ref_range", key, 50e3, 0.0, lo_open=True),
        clutter_snr_db=_num(t, "clutter_snr_db", key, 2.0, 0.0, lo_open=True),
    )


def _list(t: dict[str, Any], k: str, key: str) -> list[Any]:
    v = t.get(k, [])
    if not isinstance(v, list):
        raise ConfigError(f"{key}.{k}", "expected an array of tables")
    return v


_SAR_KEYS = {"mode", "pd", "clutter", "di_db", "nl_db", "snr_threshold_db", "sigma_amp_db",
             "clutter_snr_db", "endfire_deg", "sfreq_hz", "band_hz"}


def _sonar_array(t: dict[str, Any], key: str, base: SonarArraySim) -> SonarArraySim:
    mode = t.get("mode", base.mode)
    if mode not in MODES:
        raise ConfigError(f"{key}.mode", f"must be one of {MODES}")
    band = base.band_hz
    if "band_hz" in t:
        b = _vec(t, "band_hz", key, (2,))
        band = (float(b[0]), float(b[1]))
    return _checked(
        SonarArraySim, key,
        mode=mode,
        pd=_num(t, "pd", key, base.pd),
        clutter=_num(t, "clutter", key, base.clutter),
        di_db=_num(t, "di_db", key, base.di_db),
        nl_db=_num(t, "nl_db", key, base.nl_db),
        snr_threshold_db=_num(t, "snr_threshold_db", key, base.snr_threshold_db),
        sigma_amp_db=_num(t, "sigma_amp_db", key, base.sigma_amp_db),
        clutter_snr_db=_num(t, "clutter_snr_db", key, base.clutter_snr_db),
        endfire_deg=_num(t, "endfire_deg", key, base.endfire_deg),
        sfreq_hz=_num(t, "sfreq_hz", key, base.sfreq_hz),
        band_hz=band,
    )


def _sonar(t: Any, period: float) -> SonarSim:
    key = "sim.sonar"
    top = {"scan_period", "own", "array", "target", "alpha_db_km", "sound_speed"}
    t = _table(t, key, _SAR_KEYS | top)
    period = _num(t, "scan_period", key, period, 0.0, lo_open=True)
    default = _sonar_array(t, key, SonarArraySim())
    arr_raw = _table(t.get("array", {}), f"{key}.array", set(t.get("array", {})))
    arrays = {a: _sonar_array(_table(v, f"{key}.array.{a}", _SAR_KEYS), f"{key}.array.{a}", default)
              for a, v in arr_raw.items()}
    if "own" not in t:
        raise ConfigError(f"{key}.own", "missing")
    own, _ = _mover(t["own"], f"{key}.own", _OWN_KEYS, (2,))
    targets = []
    for i, m in enumerate(_list(t, "target", key)):
        k = f"{key}.target[{i}]"
        mv, raw = _mover(m, k, _SEA_KEYS, (2,))
        lines = raw.get("lines_hz", [])
        if not isinstance(lines, list) or not all(
            isinstance(f, (int, float)) and not isinstance(f, bool) and f > 0 for f in lines
        ):
            raise ConfigError(f"{k}.lines_hz", "must be a list of positive frequencies in Hz")
        targets.append(Mover(mv.id, mv.pos, mv.course, mv.speed, 0.0, mv.legs, mv.t_on, mv.t_off,
                             _num(raw, "sl_db", k, 140.0), tuple(float(f) for f in lines)))
    _unique_ids(targets, f"{key}.target")
    return SonarSim(
        own, default, arrays, targets, period,
        alpha_db_km=_num(t, "alpha_db_km", key, 0.1, 0.0),
        sound_speed=_num(t, "sound_speed", key, 1500.0, 0.0, lo_open=True),
    )


def load_scenario(doc: dict[str, Any]) -> Scenario:
    """Validate the ``[sim]`` table of a parsed scenario file into a :class:`Scenario`."""
    if not isinstance(doc, dict) or "sim" not in doc:
        raise ConfigError("sim", "missing")
    key = "sim"
    s = _table(doc["sim"], key, {"name", "scan_period", "n_scans", "duration", "radar", "sonar"})
    period = _num(s, "scan_period", key, 1.0, 0.0, lo_open=True)
    if ("n_scans" in s) == ("duration" in s):
        raise ConfigError(f"{key}.n_scans", "give exactly one of n_scans or duration")
    if "n_scans" in s:
        n = s["n_scans"]
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise ConfigError(f"{key}.n_scans", "must be an integer >= 1")
        duration = n * period
    else:
        duration = _num(s, "duration", key, lo=0.0, lo_open=True)
    name = s.get("name", "")
    if not isinstance(name, str):
        raise ConfigError(f"{key}.name", "expected a string")
    radar = _radar(s["radar"], period) if "radar" in s else None
    sonar = _sonar(s["sonar"], period) if "sonar" in s else None
    if radar is None and sonar is None:
        raise ConfigError(key, "needs [sim.radar] and/or [sim.sonar]")
    radar_doc = doc.get("radar")
    origin = geo_origin(radar_doc.get("origin") if isinstance(radar_doc, dict) else None)
    return Scenario(duration, radar, sonar, name, origin)


def radar_scene(cfg: Config) -> RadarSim | None:
    """The [sim.radar] part of a deployment file that is also a scenario (None without it):
    the channels' accuracies and detection probabilities the PCRLB needs."""
    return load_scenario(cfg.doc).radar if "sim" in cfg.doc else None
