"""Deployment configuration: one TOML file describes the sensors, the Zenoh wiring and
the tracker parameters of a whole deployment (see docs/configuration.md).

Parameter tables (``[radar.tracker]``, ``[sonar.tma]`` ...) are turned into the
parameter dataclasses that the core modules define, by :func:`section`; an unknown key
or a value of the wrong type is a :class:`ConfigError` that names the key.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

KEY_CHUNK = re.compile(r"^[a-z0-9_-]{1,32}$")
ARRAY_KINDS = ("cylindrical", "linear")

T = TypeVar("T")


class ConfigError(ValueError):
    """An invalid configuration; the message names the offending key."""

    def __init__(self, key: str, reason: str) -> None:
        super().__init__(f"config key '{key}': {reason}")
        self.key = key


@dataclass(frozen=True)
class ZenohConfig:
    """Where a process connects / listens; ``root`` prefixes every data key."""

    connect: list[str] = field(default_factory=lambda: ["tcp/127.0.0.1:7447"])
    listen: list[str] = field(default_factory=list)
    root: str = "pf/v1"


@dataclass(frozen=True)
class RadarBase:
    """One bistatic base: the receiver and one transmitter of opportunity (001)."""

    id: str
    tx: np.ndarray
    rx: np.ndarray
    channels: list[str]
    p: int = 1


@dataclass(frozen=True)
class SonarArray:
    """One hydrophone array: cylindrical (constant sigma) or linear (000 sigma law)."""

    id: str
    kind: str
    sigma0: float


@dataclass(frozen=True)
class Config:
    """A parsed deployment file; ``doc`` keeps the raw tables for :func:`section`."""

    zenoh: ZenohConfig
    bases: list[RadarBase]
    arrays: list[SonarArray]
    doc: dict[str, Any]
    path: Path | None = None

    def base(self, base_id: str) -> RadarBase:
        for b in self.bases:
            if b.id == base_id:
                return b
        raise ConfigError("radar.base", f"no base with id '{base_id}'")

    def array(self, array_id: str) -> SonarArray:
        for a in self.arrays:
            if a.id == array_id:
                return a
        raise ConfigError("sonar.array", f"no array with id '{array_id}'")


def load(path: str | Path) -> Config:
    """Read and validate a deployment TOML file."""
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text())
    except FileNotFoundError:
        raise ConfigError("<file>", f"{p} does not exist") from None
    except tomllib.TOMLDecodeError as e:
        raise ConfigError("<file>", f"{p} is not valid TOML: {e}") from None
    return parse(doc, p)


def parse(doc: dict[str, Any], path: Path | None = None) -> Config:
    """Validate the deployment part of a parsed TOML document."""
    z = doc.get("zenoh", {})
    _check_table(z, "zenoh")
    zc = _build(ZenohConfig, z, "zenoh")
    for k in ("connect", "listen"):
        for ep in getattr(zc, k):
            _endpoint(ep, f"zenoh.{k}")
    radar = doc.get("radar", {})
    _check_table(radar, "radar")
    bases = [_radar_base(b, i) for i, b in enumerate(radar.get("base", []))]
    _unique([b.id for b in bases], "radar.base.id")
    sonar = doc.get("sonar", {})
    _check_table(sonar, "sonar")
    arrays = [_sonar_array(a, i) for i, a in enumerate(sonar.get("array", []))]
    _unique([a.id for a in arrays], "sonar.array.id")
    return Config(zc, bases, arrays, doc, path)


def section(cfg: Config, dotted: str, cls: type[T]) -> T:
    """Build parameter dataclass ``cls`` from table ``dotted`` (defaults where absent).

    Nested tables are sections of their own (common.deploy.sections checks their names)."""
    table: Any = cfg.doc
    for part in dotted.split("."):
        table = table.get(part, {}) if isinstance(table, dict) else None
        if table is None:
            raise ConfigError(dotted, "expected a table")
    _check_table(table, dotted)
    return _build(cls, {k: v for k, v in table.items() if not isinstance(v, dict)}, dotted)


def _endpoint(ep: Any, key: str) -> str:
    if not isinstance(ep, str) or not re.match(r"^(tcp|udp|tls|quic|ws|unixsock-stream)/.+", ep):
        raise ConfigError(key, f"'{ep}' is not a Zenoh endpoint like tcp/127.0.0.1:7447")
    return ep


def _check_table(t: Any, key: str) -> None:
    if not isinstance(t, dict):
        raise ConfigError(key, "expected a table")


def _unique(ids: list[str], key: str) -> None:
    dup = {i for i in ids if ids.count(i) > 1}
    if dup:
        raise ConfigError(key, f"duplicate ids {sorted(dup)}")


def _chunk(v: Any, key: str) -> str:
    if not isinstance(v, str) or not KEY_CHUNK.match(v):
        raise ConfigError(key, f"{v!r} must be a string of [a-z0-9_-], 1-32 characters")
    return v


def _point(v: Any, key: str) -> np.ndarray:
    ok = isinstance(v, list) and len(v) == 3 and all(
        isinstance(c, (int, float)) and not isinstance(c, bool) for c in v
    )
    if not ok or not np.all(np.isfinite(v)):
        raise ConfigError(key, f"{v!r} must be [x, y, z] in metres")
    return np.asarray(v, dtype=float)


def _radar_base(b: Any, i: int) -> RadarBase:
    key = f"radar.base[{i}]"
    _check_table(b, key)
    unknown = set(b) - {"id", "tx", "rx", "channels", "p"}
    if unknown:
        raise ConfigError(f"{key}.{sorted(unknown)[0]}", "unknown key")
    for k in ("id", "tx", "rx", "channels"):
        if k not in b:
            raise ConfigError(f"{key}.{k}", "missing")
    chans = b["channels"]
    if not isinstance(chans, list) or not chans:
        raise ConfigError(f"{key}.channels", "must be a non-empty list of channel ids")
    chans = [_chunk(c, f"{key}.channels") for c in chans]
    _unique(chans, f"{key}.channels")
    p = b.get("p", 1)
    if not isinstance(p, int) or isinstance(p, bool) or p < 0:
        raise ConfigError(f"{key}.p", "must be an integer >= 0")
    tx, rx = _point(b["tx"], f"{key}.tx"), _point(b["rx"], f"{key}.rx")
    if np.linalg.norm(tx - rx) <= 0:
        raise ConfigError(f"{key}.tx", "transmitter and receiver must differ")
    return RadarBase(_chunk(b["id"], f"{key}.id"), tx, rx, chans, p)


def _sonar_array(a: Any, i: int) -> SonarArray:
    key = f"sonar.array[{i}]"
    _check_table(a, key)
    unknown = set(a) - {"id", "kind", "sigma0"}
    if unknown:
        raise ConfigError(f"{key}.{sorted(unknown)[0]}", "unknown key")
    kind = a.get("kind", "cylindrical")
    if kind not in ARRAY_KINDS:
        raise ConfigError(f"{key}.kind", f"must be one of {ARRAY_KINDS}")
    s = a.get("sigma0")
    if not isinstance(s, (int, float)) or isinstance(s, bool) or not (0 < s < np.pi):
        raise ConfigError(f"{key}.sigma0", "must be a bearing sigma in radians, 0 < sigma0 < pi")
    return SonarArray(_chunk(a.get("id"), f"{key}.id"), kind, float(s))


def _build(cls: type[T], table: dict[str, Any], key: str) -> T:
    """Instantiate dataclass ``cls`` from ``table``, checking names and simple types."""
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    hints = typing.get_type_hints(cls)
    kwargs: dict[str, Any] = {}
    for name, value in table.items():
        if name not in fields:
            raise ConfigError(f"{key}.{name}", f"unknown key (known: {', '.join(sorted(fields))})")
        kwargs[name] = _coerce(value, hints[name], f"{key}.{name}")
    return cls(**kwargs)


def _coerce(value: Any, hint: Any, key: str) -> Any:
    origin = typing.get_origin(hint)
    if origin is typing.Literal:
        if value not in typing.get_args(hint):
            raise ConfigError(key, f"{value!r} is not one of {typing.get_args(hint)}")
        return value
    if origin in (typing.Union, types.UnionType):
        for arm in typing.get_args(hint):
            if arm is type(None) and value is None:
                return None
            try:
                return _coerce(value, arm, key)
            except ConfigError:
                continue
        raise ConfigError(key, f"{value!r} does not fit {hint}")
    if origin in (list, tuple):
        if not isinstance(value, list):
            raise ConfigError(key, "expected a list")
        args = typing.get_args(hint)
        inner = args[0] if args else Any
        out = [_coerce(v, inner, key) for v in value]
        return out if origin is list else tuple(out)
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(key, f"expected a number, got {value!r}")
        if not np.isfinite(value):
            raise ConfigError(key, "must be finite")
        return float(value)
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(key, f"expected an integer, got {value!r}")
        return value
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(key, f"expected true or false, got {value!r}")
        return value
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(key, f"expected a string, got {value!r}")
        return value
    return value
