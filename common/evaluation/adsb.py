"""ADS-B truth: tar1090 / readsb ``aircraft.json`` snapshots parsed, interpolated to the
track times in the deployment's ENU frame, and global tracks scored against them.

A snapshot is ``{now, aircraft: [{hex, lat, lon, seen_pos, alt_geom, alt_baro, mlat,
tisb, type, ...}]}``. A position's time is ``now - seen_pos``. Altitude rule: alt_geom
(feet above the WGS-84 ellipsoid) is the height; alt_baro (pressure altitude, feet) is
used only with a stated ``baro_offset`` (metres added to it) and "ground" never. MLAT
or TIS-B positions (type, or lat in the mlat / tisb lists) and non-ICAO ``~`` addresses
are kept but marked lower-quality. Anything else not usable is counted by reason in
``rejects``, never raised. Pure: the caller reads the files.

Scoring: a confirmed track farther than the cutoff from every aircraft ADS-B sees at
that time is *unverified* (an aircraft without ADS-B, or a false track: ADS-B cannot
tell) and left out of GOSPA, switches and RMSE; the others are scored as against
simulator truth.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from common.evaluation.pcrlb import Evaluation
from common.radar.geometry.geodesy import LocalFrame

FT = 0.3048  # m
HEX = re.compile(r"~?[0-9a-f]{6}")
NON_ICAO = 1 << 24  # aircraft_id of a '~' address: above every 24-bit ICAO address


def aircraft_id(hex_: str) -> int:
    """Integer id of an address: the ICAO number, + NON_ICAO for a '~' address."""
    return int(hex_.lstrip("~"), 16) + (NON_ICAO if hex_.startswith("~") else 0)


@dataclass(frozen=True)
class Fix:
    """One aircraft position: t (s), lat, lon (deg), h (m ellipsoidal); ``lower`` the
    reason it is lower-quality truth ("mlat", "tisb", "non-icao"), "" for ADS-B."""

    hex: str
    t: float
    lat: float
    lon: float
    h: float
    lower: str = ""


def _number(v: Any) -> float | None:
    """v as a finite float, None for anything else (bool, str, NaN, missing)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        return None
    return float(v)


def _lower(a: dict[str, Any], hex_: str) -> str:
    kind = a.get("type")
    kind = kind if isinstance(kind, str) else ""
    if kind == "mlat" or "lat" in (a.get("mlat") or []):
        return "mlat"
    if kind.startswith("tisb") or "lat" in (a.get("tisb") or []):
        return "tisb"
    return "non-icao" if hex_.startswith("~") else ""


def _height(a: dict[str, Any], baro_offset: float | None) -> float | str:
    """Ellipsoidal height (m) by the altitude rule, or the reject reason."""
    geom = _number(a.get("alt_geom"))
    if geom is not None:
        return geom * FT
    baro = a.get("alt_baro")
    if baro == "ground":
        return "ground"
    if _number(baro) is None:
        return "no_altitude"
    return "baro_only" if baro_offset is None else float(baro) * FT + baro_offset


def parse_snapshot(doc: Any, rejects: Counter[str], baro_offset: float | None = None,
                   max_age: float = 60.0) -> list[Fix]:
    """The fixes of one decoded aircraft.json; positions older than ``max_age`` s are
    rejected (``stale``). Every aircraft left out adds one to ``rejects[reason]``."""
    now = _number(doc.get("now")) if isinstance(doc, dict) else None
    if now is None or not isinstance(doc.get("aircraft"), list):
        rejects["bad_snapshot"] += 1
        return []
    out = []
    for a in doc["aircraft"]:
        reason, fix = _fix(a, now, baro_offset, max_age)
        if fix is None:
            rejects[reason] += 1
        else:
            out.append(fix)
    return out


def _fix(a: Any, now: float, baro_offset: float | None, max_age: float) -> tuple[str, Fix | None]:
    if not isinstance(a, dict):
        return "not_a_map", None
    hex_ = a.get("hex")
    if not isinstance(hex_, str) or not HEX.fullmatch(hex_.lower()):
        return "bad_hex", None
    hex_ = hex_.lower()
    if "lat" not in a or "lon" not in a:
        return "no_position", None
    lat, lon, seen = _number(a["lat"]), _number(a["lon"]), _number(a.get("seen_pos"))
    if lat is None or lon is None or not (abs(lat) <= 90 and abs(lon) <= 180):
        return "bad_position", None
    if seen is None or seen < 0:
        return "no_seen_pos", None
    if seen > max_age:
        return "stale", None
    h = _height(a, baro_offset)
    if isinstance(h, str):
        return h, None
    return "", Fix(hex_, now - seen, lat, lon, h, _lower(a, hex_))


@dataclass
class _Path:
    t: np.ndarray  # (k,) increasing
    p: np.ndarray  # (k, 3) ENU m


@dataclass
class AdsbTruth:
    """Per aircraft its fixes in the ENU frame, interpolated linearly (velocity: the
    segment's slope) between fixes at most ``max_gap`` s apart. The same position
    repeated by later snapshots (same hex and time) counts once."""

    frame: LocalFrame
    max_gap: float = 10.0
    paths: dict[int, _Path] = field(default_factory=dict)
    hexes: dict[int, str] = field(default_factory=dict)
    lower: dict[int, str] = field(default_factory=dict)

    def add(self, fixes: Iterable[Fix]) -> None:
        """Take the fixes of every snapshot (any order, repeats allowed), once."""
        by: dict[int, dict[float, Fix]] = {}
        for f in fixes:
            i = aircraft_id(f.hex)
            by.setdefault(i, {}).setdefault(round(f.t, 3), f)
            self.hexes[i] = f.hex
            if f.lower:
                self.lower[i] = f.lower
        for i, d in by.items():
            ts = sorted(d)
            geo = np.array([[d[t].lat, d[t].lon, d[t].h] for t in ts])
            self.paths[i] = _Path(np.array(ts), self.frame.to_enu(geo[:, 0], geo[:, 1], geo[:, 2]))

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(ids (n,), states (n, 6) [x vx y vy z vz]) of the aircraft seen at time t."""
        ids, states = [], []
        for i, path in self.paths.items():
            k = min(int(np.searchsorted(path.t, t, side="right")), path.t.size - 1)
            dt = path.t[k] - path.t[k - 1] if k > 0 else np.inf
            if not (path.t[k - 1] <= t <= path.t[k] and dt <= self.max_gap):
                continue
            v = (path.p[k] - path.p[k - 1]) / dt
            p = path.p[k - 1] + v * (t - path.t[k - 1])
            ids.append(i)
            states.append([p[0], v[0], p[1], v[1], p[2], v[2]])
        return np.array(ids, dtype=np.int64), np.array(states, dtype=float).reshape(-1, 6)


def verified(truth_x: np.ndarray, track_x: np.ndarray, cutoff: float) -> np.ndarray:
    """(m,) True for the tracks within ``cutoff`` m of some truth (states [x vx y vy z vz])."""
    if truth_x.shape[0] == 0:
        return np.zeros(track_x.shape[0], dtype=bool)
    d = np.linalg.norm(track_x[:, None, ::2] - truth_x[None, :, ::2], axis=2)
    return np.asarray(d.min(axis=1) < cutoff)


@dataclass
class AdsbScoring:
    """Global tracks scored step by step against ADS-B truth; ``unverified`` holds the
    ids of the tracks ever left out as unverified, ``unverified_steps`` their count over
    the steps."""

    truth: AdsbTruth
    ev: Evaluation
    unverified: set[int] = field(default_factory=set)
    unverified_steps: int = 0

    def add(self, t: float, ids: np.ndarray, x: np.ndarray, P: np.ndarray) -> None:
        """The confirmed tracks of time t: ids (m,), x (m, 6), P (m, 6, 6)."""
        truth_ids, truth_x = self.truth.at(t)
        ok = verified(truth_x, x, self.ev.c)
        self.unverified |= set(ids[~ok].tolist())
        self.unverified_steps += int((~ok).sum())
        self.ev.add(t, truth_ids, truth_x, ids[ok], x[ok], P[ok])
