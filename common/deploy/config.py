"""Deployment configuration: one TOML file describes the sensors, the Zenoh wiring (and
its security: [zenoh.auth], [zenoh.tls], [[site]]), and the tracker parameters of a whole
deployment (see docs/configuration.md and docs/security.md).

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

from common.core.params import ParamError
from common.deploy.errors import ConfigError
from common.deploy.positions import geo_origin, site_position
from common.deploy.structure import ARRAY, BASE
from common.radar.geometry.geodesy import LocalFrame

# A Zenoh key chunk: non-empty, none of / * $ ? #, not verbatim (@...); we also refuse
# whitespace and control characters (ids go into command lines and credential files).
KEY_CHUNK = re.compile(r"^(?!@)[^/*$?#\s\x00-\x1f\x7f]+$")
ARRAY_KINDS = ("cylindrical", "linear")

T = TypeVar("T")


@dataclass(frozen=True)
class AuthConfig:
    """Zenoh user/password authentication of every process (docs/security.md).

    credentials: file of `user:password` lines, the identities of this host; a process
        logs in with the line of its identity.
    dictionary: routers only: file of `user:password` lines of every identity that may
        connect (Zenoh's `dictionary_file`).
    access_control: routers apply the access control generated from the deployment
        (`pfusion acl`): deny by default."""

    credentials: str = ""
    dictionary: str = ""
    access_control: bool = True


@dataclass(frozen=True)
class TlsConfig:
    """TLS on every link (endpoints `tls/host:port`), optionally mutual (docs/security.md).

    root_ca: CA certificate (PEM) that the other side's certificate must chain to.
    cert, key: this host's certificate and private key (PEM): what its clients present
        under mutual TLS, and its router's when router_cert is not set.
    router_cert, router_key: a router's certificate and key (listening, and towards an
        upstream router); common name = the router's identity (`router-fusion`,
        `router-<site>`); readable by the router only.
    mtls: mutual TLS: every client and router presents a certificate of the CA.
    hosts: [zenoh.tls.hosts], needs mtls: the common name of each host's `cert` -> the
        identities that run on that host; the access control accepts an identity only
        with one of its hosts' certificates (a router's only with its own)."""

    root_ca: str = ""
    cert: str = ""
    key: str = ""
    router_cert: str = ""
    router_key: str = ""
    mtls: bool = False
    hosts: dict[str, list[str]] = field(default_factory=dict)


@dataclass(frozen=True)
class ZenohConfig:
    """Where a process connects / listens; ``root`` prefixes every data key. ``auth`` and
    ``tls`` are the optional security tables; ``identity`` is the Zenoh username of this
    process (set from the command line, docs/security.md), not a file key."""

    connect: list[str] = field(default_factory=lambda: ["tcp/127.0.0.1:7447"])
    listen: list[str] = field(default_factory=list)
    root: str = "pf/v1"
    auth: AuthConfig | None = None
    tls: TlsConfig | None = None
    identity: str | None = None


@dataclass(frozen=True)
class RadarBase:
    """One bistatic base: the receiver and one transmitter of opportunity (001).

    azimuth: the receiver measures theta (001 [3]); false for a range-Doppler base
    (omnidirectional antenna: plots [r_b, v_b], elementary state [r_b, v_b, gamma_b])."""

    id: str
    tx: np.ndarray
    rx: np.ndarray
    channels: list[str]
    p: int = 1
    azimuth: bool = True


@dataclass(frozen=True)
class SonarArray:
    """One hydrophone array: cylindrical (constant sigma) or linear (000 sigma law)."""

    id: str
    kind: str
    sigma0: float


@dataclass(frozen=True)
class Site:
    """A receiver site, whose identity `site-<id>` publishes its sensors' feed.

    id: the site's id (a Zenoh key chunk); its identity is `site-<id>`.
    bases: ids of the [[radar.base]] whose channel plots the site publishes.
    arrays: ids of the [[sonar.array]] whose detections the site publishes."""

    id: str
    bases: list[str] = field(default_factory=list)
    arrays: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Config:
    """A parsed deployment file; ``doc`` keeps the raw tables for :func:`section`.
    ``sites`` is [[site]], or one site per base and per array when the file has none.
    ``origin``: [radar.origin], the WGS-84 origin of the local ENU frame (None: flat)."""

    zenoh: ZenohConfig
    bases: list[RadarBase]
    arrays: list[SonarArray]
    doc: dict[str, Any]
    path: Path | None = None
    sites: list[Site] = field(default_factory=list)
    origin: LocalFrame | None = None

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
    zc = _build(ZenohConfig, {k: v for k, v in z.items() if k not in ("auth", "tls")}, "zenoh")
    for k in ("connect", "listen"):
        for ep in getattr(zc, k):
            _endpoint(ep, f"zenoh.{k}")
    zc = dataclasses.replace(zc, auth=_files(AuthConfig, z, "auth", path),
                             tls=_files(TlsConfig, z, "tls", path))
    if zc.tls is not None and not zc.tls.root_ca:
        raise ConfigError("zenoh.tls.root_ca", "missing (the CA that certificates chain to)")
    radar = doc.get("radar", {})
    _check_table(radar, "radar")
    origin = geo_origin(radar.get("origin"))
    bases = [_radar_base(b, i, origin) for i, b in enumerate(radar.get("base", []))]
    _unique([b.id for b in bases], "radar.base.id")
    sonar = doc.get("sonar", {})
    _check_table(sonar, "sonar")
    arrays = [_sonar_array(a, i) for i, a in enumerate(sonar.get("array", []))]
    _unique([a.id for a in arrays], "sonar.array.id")
    sites = _sites(doc.get("site"), [b.id for b in bases], [a.id for a in arrays])
    return Config(zc, bases, arrays, doc, path, sites, origin)


def tables(doc: dict[str, Any], prefix: str = "") -> dict[str, dict[str, Any]]:
    """Every table of ``doc`` at every depth by dotted name (the one walker of the
    nested tables of a deployment file)."""
    out: dict[str, dict[str, Any]] = {}
    for k, v in doc.items():
        if isinstance(v, dict):
            out[prefix + k] = v
            out.update(tables(v, f"{prefix}{k}."))
    return out


def table(doc: dict[str, Any], dotted: str) -> dict[str, Any]:
    """Table ``dotted`` of ``doc``, {} when absent; ConfigError when a part of the path
    is a value, not a table."""
    found = tables(doc)
    parts = dotted.split(".")
    for i in range(1, len(parts) + 1):
        name, parent = ".".join(parts[:i]), ".".join(parts[:i - 1])
        if name not in found:
            if parts[i - 1] in (found[parent] if parent else doc):
                raise ConfigError(dotted, "expected a table")
            return {}
    return found[dotted]


def section(cfg: Config, dotted: str, cls: type[T], given: dict[str, Any] | None = None) -> T:
    """Build parameter dataclass ``cls`` from table ``dotted`` (defaults where absent), or
    from the keys ``given`` for it.

    Nested tables are sections of their own (common.deploy.sections checks their names).
    A value outside its range or a broken rule between keys (the class's RANGES and
    RULES, common.core.params) is a ConfigError naming the keys and the table."""
    if given is None:
        given = {k: v for k, v in table(cfg.doc, dotted).items() if not isinstance(v, dict)}
    try:
        return _build(cls, given, dotted)
    except ParamError as e:
        raise ConfigError(f"{dotted}.{e.keys[0]}", f"[{dotted}] {e.detail}") from None


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
        raise ConfigError(key, f"{v!r} must be a non-empty Zenoh key chunk: no / * $ ? #, "
                               "no whitespace, not starting with @")
    return v


def _files(cls: type[T], z: dict[str, Any], name: str, path: Path | None) -> T | None:
    """Table [zenoh.<name>] as ``cls``, its file paths made relative to the deployment
    file's directory (None when the table is absent)."""
    if name not in z:
        return None
    _check_table(z[name], f"zenoh.{name}")
    t = _build(cls, z[name], f"zenoh.{name}")
    base = path.parent if path is not None else Path(".")
    return dataclasses.replace(t, **{  # type: ignore[type-var]
        k: str(base / v) for k, v in dataclasses.asdict(t).items() if isinstance(v, str) and v})


def _sites(entries: Any, bases: list[str], arrays: list[str]) -> list[Site]:
    """[[site]] (each base and array in at most one site), or one site per base and per
    array (an array named like a base joins that base's site)."""
    if entries is None:
        out = {b: Site(b, [b], []) for b in bases}
        for a in arrays:
            out.setdefault(a, Site(a, [], [])).arrays.append(a)
        return list(out.values())
    if not isinstance(entries, list):
        raise ConfigError("site", "expected [[site]] tables")
    sites = []
    for i, e in enumerate(entries):
        key = f"site[{i}]"
        _check_table(e, key)
        unknown = set(e) - {f.name for f in dataclasses.fields(Site)}
        if unknown:
            raise ConfigError(f"{key}.{sorted(unknown)[0]}", "unknown key")
        lists = {}
        for k, known, kind in (("bases", bases, "radar.base"), ("arrays", arrays, "sonar.array")):
            v = e.get(k, [])
            if not isinstance(v, list):
                raise ConfigError(f"{key}.{k}", f"must be a list of [[{kind}]] ids")
            for x in v:
                if x not in known:
                    raise ConfigError(f"{key}.{k}", f"no [[{kind}]] with id {x!r}")
            lists[k] = list(v)
        sites.append(Site(_chunk(e.get("id"), f"{key}.id"), lists["bases"], lists["arrays"]))
    _unique([s.id for s in sites], "site.id")
    _unique([b for s in sites for b in s.bases], "site.bases")
    _unique([a for s in sites for a in s.arrays], "site.arrays")
    return sites


def _radar_base(b: Any, i: int, origin: LocalFrame | None) -> RadarBase:
    key = f"radar.base[{i}]"
    _check_table(b, key)
    unknown = set(b) - BASE.names()
    if unknown:
        raise ConfigError(f"{key}.{sorted(unknown)[0]}", "unknown key")
    for k in ("id", "channels"):
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
    azimuth = b.get("azimuth", True)
    if not isinstance(azimuth, bool):
        raise ConfigError(f"{key}.azimuth", "must be true or false")
    tx, rx = site_position(b, "tx", key, origin), site_position(b, "rx", key, origin)
    if np.linalg.norm(tx - rx) <= 0:
        raise ConfigError(f"{key}.tx", "transmitter and receiver must differ")
    return RadarBase(_chunk(b["id"], f"{key}.id"), tx, rx, chans, p, azimuth)


def _sonar_array(a: Any, i: int) -> SonarArray:
    key = f"sonar.array[{i}]"
    _check_table(a, key)
    unknown = set(a) - ARRAY.names()
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
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(key, "expected a table")
        k_hint, v_hint = typing.get_args(hint)
        return {_coerce(k, k_hint, key): _coerce(v, v_hint, f"{key}.{k}") for k, v in value.items()}
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
