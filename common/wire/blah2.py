"""A blah2 node's HTTP answers, parsed and checked (pure): `/api/detection` (the latest
frame), `/stash/detection` (the last minutes of frames, one row per detection) and
`/api/config` (sites, carrier, sample rate); docs/networks.md.

A frame is {"timestamp", "delay": [km], "doppler": [Hz], "snr": [dB]}; `snr` is
optional (the stash has none). The timestamp is integer milliseconds since the UNIX
epoch in current blah2, integer seconds in older versions: a stamp >= 1e11 is taken as
milliseconds (1e11 s is in the year 5138, 1e11 ms in 1973), a smaller one as seconds.
A frame is rejected whole, with the reason as its counter: `json` (not JSON),
`fields` (a field missing or not numbers), `lengths` (columns of different lengths),
`nan` (a value not finite), `negative_delay`, `timestamp` (not > 0).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from common.core.rejection import Rejected
from common.deploy.config import RadarBase
from common.radar.geometry.geodesy import LocalFrame

MS_FROM = 1e11  # a stamp at least this large counts milliseconds
SITE_TOL_M = 10.0
FREQ_TOL_HZ = 1e3


@dataclass(frozen=True)
class Frame:
    """One frame of detections: t (UNIX s), delay (km), doppler (Hz), snr (dB or None)."""

    t: float
    delay: np.ndarray
    doppler: np.ndarray
    snr: np.ndarray | None

    def __len__(self) -> int:
        return int(self.delay.shape[0])


def unix_seconds(stamp: Any) -> float:
    """A blah2 timestamp (ms or s, see the module docstring) in UNIX seconds."""
    if isinstance(stamp, bool) or not isinstance(stamp, (int, float)):
        raise Rejected("fields", f"timestamp {stamp!r} is not a number")
    if not math.isfinite(stamp):
        raise Rejected("nan", f"timestamp {stamp!r}")
    if stamp <= 0:
        raise Rejected("timestamp", f"timestamp {stamp!r} is not > 0")
    return float(stamp) / 1000.0 if stamp >= MS_FROM else float(stamp)


def _load(body: bytes | str) -> Any:
    try:
        return json.loads(body)
    except (ValueError, RecursionError) as e:  # UnicodeDecodeError is a ValueError
        raise Rejected("json", f"not JSON: {e}") from None


def _column(doc: dict[str, Any], name: str, required: bool = True) -> np.ndarray | None:
    v = doc.get(name)
    if v is None and not required:
        return None
    if not isinstance(v, list) or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
        raise Rejected("fields", f"'{name}' is not a list of numbers")
    a = np.asarray(v, dtype=float).reshape(-1)
    if not np.all(np.isfinite(a)):
        raise Rejected("nan", f"'{name}' holds a value that is not finite")
    return a


def _columns(doc: Any, names: tuple[str, ...]) -> list[np.ndarray | None]:
    """The checked columns `names` (the last, snr, optional) of a JSON object."""
    if not isinstance(doc, dict):
        raise Rejected("fields", "not a JSON object")
    cols = [_column(doc, n, n != "snr") for n in names]
    lengths = {n: len(c) for n, c in zip(names, cols) if c is not None}
    if len(set(lengths.values())) > 1:
        raise Rejected("lengths", f"columns of different lengths {lengths}")
    delay = cols[names.index("delay")]
    if delay is not None and np.any(delay < 0):
        raise Rejected("negative_delay", f"delay {float(delay.min())} km < 0")
    return cols


def frame_of(doc: Any) -> Frame:
    """The Frame of one decoded /api/detection object (raises Rejected)."""
    if not isinstance(doc, dict) or "timestamp" not in doc:
        raise Rejected("fields", "not a JSON object with a timestamp")
    t = unix_seconds(doc["timestamp"])
    delay, doppler, snr = _columns(doc, ("delay", "doppler", "snr"))
    assert delay is not None and doppler is not None
    return Frame(t, delay, doppler, snr)


def parse_frame(body: bytes | str) -> Frame:
    """The Frame of an /api/detection answer (raises Rejected)."""
    return frame_of(_load(body))


def parse_stash(body: bytes | str) -> list[Frame]:
    """The frames of a /stash/detection answer ({"timestamp", "delay", "doppler"}, one
    entry per detection; `snr` optional), in time order (raises Rejected for the whole)."""
    doc = _load(body)
    stamps, delay, doppler, snr = _columns(doc, ("timestamp", "delay", "doppler", "snr"))
    assert stamps is not None and delay is not None and doppler is not None
    frames = []
    for s in np.unique(stamps):
        k = stamps == s
        frames.append(Frame(unix_seconds(s.item()), delay[k], doppler[k], None if snr is None else snr[k]))
    return frames


def parse_saved(text: str) -> list[Any]:
    """The decoded frames of a node's saved detections: a JSON array of frames, or one
    frame per line (each line then parsed alone: a bad line is one bad frame)."""
    if text.lstrip().startswith("["):
        doc = _load(text)
        return list(doc)
    out: list[Any] = []
    for line in text.splitlines():
        if line.strip():
            try:
                out.append(json.loads(line))
            except ValueError:
                out.append(line)  # frame_of rejects it as `fields`
    return out


@dataclass(frozen=True)
class NodeConfig:
    """What /api/config tells: rx, tx as [lat, lon, alt] (deg, m), fc, fs (Hz), cpi (s
    or None)."""

    rx: tuple[float, float, float]
    tx: tuple[float, float, float]
    fc: float
    fs: float
    cpi: float | None


def _number(doc: Any, path: str) -> float:
    v = doc
    for k in path.split("."):
        if not isinstance(v, dict) or k not in v:
            raise Rejected("config", f"/api/config has no {path}")
        v = v[k]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise Rejected("config", f"/api/config {path} = {v!r} is not a number")
    return float(v)


def parse_config(body: bytes | str) -> NodeConfig:
    """The NodeConfig of an /api/config answer (raises Rejected `config`)."""
    doc = _load(body)

    def site(k: str) -> tuple[float, float, float]:
        return (_number(doc, f"location.{k}.latitude"), _number(doc, f"location.{k}.longitude"),
                _number(doc, f"location.{k}.altitude"))

    cpi = _number(doc, "process.data.cpi") if isinstance(doc.get("process"), dict) else None
    return NodeConfig(site("rx"), site("tx"), _number(doc, "capture.fc"), _number(doc, "capture.fs"), cpi)


def _geo(p: Iterable[float]) -> str:
    lat, lon, alt = p
    return f"[{lat:.6f}, {lon:.6f}, {alt:.1f}]"


def mismatches(node: NodeConfig, base: RadarBase, origin: LocalFrame, fc: float, fs: float) -> list[str]:
    """Every disagreement of a node's config with its base in the deployment (sites
    within SITE_TOL_M, fc and fs within FREQ_TOL_HZ when the deployment gives them), each
    naming both values."""
    out = []
    for k, here in (("rx", base.rx), ("tx", base.tx)):
        there = origin.to_enu(*getattr(node, k))
        d = float(np.linalg.norm(there - here))
        if d > SITE_TOL_M:
            site = [float(v) for v in origin.to_geodetic(here)]
            out.append(f"{k}: node {_geo(getattr(node, k))}, deployment {_geo(site)} "
                       f"({d:.0f} m apart, tolerance {SITE_TOL_M:g} m)")
    for k, mine in (("fc", fc), ("fs", fs)):
        theirs = getattr(node, k)
        if mine > 0 and abs(theirs - mine) > FREQ_TOL_HZ:
            out.append(f"{k}: node {theirs:g} Hz, deployment {mine:g} Hz (tolerance {FREQ_TOL_HZ:g} Hz)")
    return out
