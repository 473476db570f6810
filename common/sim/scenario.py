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

from dataclasses import dataclass
from typing import Any, ClassVar

from common.core.params import Params, Range, Rule, ascending_pair, non_negative, positive, unbounded
from common.deploy.config import Config, ConfigError
from common.deploy.positions import geo_origin
from common.radar.geometry.geodesy import LocalFrame
from common.sim.mover import Mover
from common.sim.parse import CLUTTER, DB, OWN_KEYS, PD, SEA_KEYS, checked, listed, mover, num, table, unique_ids, vec
from common.sim.radar_scenario import RadarChannelSim, RadarSim, radar_section

__all__ = ["MODES", "RadarChannelSim", "RadarSim", "Scenario", "SonarArraySim", "SonarSim", "load_scenario",
           "radar_scene"]

MODES = ("broadband", "narrowband")


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


_SAR_KEYS = {"mode", "pd", "clutter", "di_db", "nl_db", "snr_threshold_db", "sigma_amp_db",
             "clutter_snr_db", "endfire_deg", "sfreq_hz", "band_hz"}


def _sonar_array(t: dict[str, Any], key: str, base: SonarArraySim) -> SonarArraySim:
    mode = t.get("mode", base.mode)
    if mode not in MODES:
        raise ConfigError(f"{key}.mode", f"must be one of {MODES}")
    band = base.band_hz
    if "band_hz" in t:
        b = vec(t, "band_hz", key, (2,))
        band = (float(b[0]), float(b[1]))
    return checked(
        SonarArraySim, key,
        mode=mode,
        pd=num(t, "pd", key, base.pd),
        clutter=num(t, "clutter", key, base.clutter),
        di_db=num(t, "di_db", key, base.di_db),
        nl_db=num(t, "nl_db", key, base.nl_db),
        snr_threshold_db=num(t, "snr_threshold_db", key, base.snr_threshold_db),
        sigma_amp_db=num(t, "sigma_amp_db", key, base.sigma_amp_db),
        clutter_snr_db=num(t, "clutter_snr_db", key, base.clutter_snr_db),
        endfire_deg=num(t, "endfire_deg", key, base.endfire_deg),
        sfreq_hz=num(t, "sfreq_hz", key, base.sfreq_hz),
        band_hz=band,
    )


def _sonar(t: Any, period: float) -> SonarSim:
    key = "sim.sonar"
    top = {"scan_period", "own", "array", "target", "alpha_db_km", "sound_speed"}
    t = table(t, key, _SAR_KEYS | top)
    period = num(t, "scan_period", key, period, 0.0, lo_open=True)
    default = _sonar_array(t, key, SonarArraySim())
    arr_raw = table(t.get("array", {}), f"{key}.array", set(t.get("array", {})))
    arrays = {a: _sonar_array(table(v, f"{key}.array.{a}", _SAR_KEYS), f"{key}.array.{a}", default)
              for a, v in arr_raw.items()}
    if "own" not in t:
        raise ConfigError(f"{key}.own", "missing")
    own, _ = mover(t["own"], f"{key}.own", OWN_KEYS, (2,))
    targets = []
    for i, m in enumerate(listed(t, "target", key)):
        k = f"{key}.target[{i}]"
        mv, raw = mover(m, k, SEA_KEYS, (2,))
        lines = raw.get("lines_hz", [])
        if not isinstance(lines, list) or not all(
            isinstance(f, (int, float)) and not isinstance(f, bool) and f > 0 for f in lines
        ):
            raise ConfigError(f"{k}.lines_hz", "must be a list of positive frequencies in Hz")
        targets.append(Mover(mv.id, mv.pos, mv.course, mv.speed, 0.0, mv.legs, mv.t_on, mv.t_off,
                             num(raw, "sl_db", k, 140.0), tuple(float(f) for f in lines)))
    unique_ids(targets, f"{key}.target")
    return SonarSim(
        own, default, arrays, targets, period,
        alpha_db_km=num(t, "alpha_db_km", key, 0.1, 0.0),
        sound_speed=num(t, "sound_speed", key, 1500.0, 0.0, lo_open=True),
    )


def load_scenario(doc: dict[str, Any]) -> Scenario:
    """Validate the ``[sim]`` table of a parsed scenario file into a :class:`Scenario`."""
    if not isinstance(doc, dict) or "sim" not in doc:
        raise ConfigError("sim", "missing")
    key = "sim"
    s = table(doc["sim"], key, {"name", "scan_period", "n_scans", "duration", "radar", "sonar"})
    period = num(s, "scan_period", key, 1.0, 0.0, lo_open=True)
    if ("n_scans" in s) == ("duration" in s):
        raise ConfigError(f"{key}.n_scans", "give exactly one of n_scans or duration")
    if "n_scans" in s:
        n = s["n_scans"]
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise ConfigError(f"{key}.n_scans", "must be an integer >= 1")
        duration = n * period
    else:
        duration = num(s, "duration", key, lo=0.0, lo_open=True)
    name = s.get("name", "")
    if not isinstance(name, str):
        raise ConfigError(f"{key}.name", "expected a string")
    radar = radar_section(s["radar"], period) if "radar" in s else None
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
