"""Wire protocol v1: msgpack maps with ``v`` = 1 and ``t``, columnar plot lists.

Every message type has a schema (a dict of field name -> :class:`Field`); :func:`decode`
checks a payload against it strictly (types, equal column lengths, finite values,
sigmas > 0, angles in [0, 2pi]) and raises :class:`DecodeError` naming the field.
Decoded float columns are numpy float64 arrays, int columns int64 arrays. Fields a schema
does not name are ignored, so a v1 reader accepts additive changes. docs/protocol.md is
the human-readable version of the schemas below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np

from common.core.angles import TWO_PI
from common.core.rejection import Rejected

VERSION = 1
MAX_PAYLOAD = 16 * 1024 * 1024


class DecodeError(Rejected):
    """A payload that does not match its schema; ``field`` names the culprit. Counted as
    ``decode:<field>``."""

    def __init__(self, field: str, why: str) -> None:
        super().__init__(f"decode:{field}", f"{field}: {why}", message=f"{field}: {why}")
        self.field = field


@dataclass(frozen=True)
class Field:
    """Schema of one field.

    kind: float | int | str | bool | floats | ints | strs | map | maps | pairs.
    ``column`` groups list fields that must have equal lengths; ``length`` fixes the
    length of a list; ``sub`` is the schema of a nested map (map / maps); ``interval``
    bounds numbers (closed); optional fields of one ``together`` group come all or none.
    """

    kind: str
    optional: bool = False
    positive: bool = False
    nonneg: bool = False
    angle: bool = False
    column: str | None = None
    length: int | None = None
    choices: tuple[str, ...] | None = None
    sub: dict[str, "Field"] | None = None
    interval: tuple[float, float] | None = None
    together: str | None = None


def _col(kind: str = "floats", **kw: Any) -> Field:
    return Field(kind, column="n", **kw)


V = Field("int")
T = Field("float", nonneg=True)
SEQ = Field("int", nonneg=True)
ID = Field("str")
TRACK_STATUS = ("tentative", "confirmed", "coasting")

OWN_SHIP = {
    "x": Field("float"),
    "y": Field("float"),
    "heading": Field("float", angle=True),
    "speed": Field("float", nonneg=True),
}

# az and saz: both or neither (a range-Doppler base's plots have neither), see TOGETHER
PLOTS = {
    "v": V, "t": T, "seq": SEQ, "base": ID, "channel": ID,
    "rb": _col(nonneg=True), "vb": _col(), "az": _col(optional=True, angle=True),
    "srb": _col(positive=True), "svb": _col(positive=True), "saz": _col(optional=True, positive=True),
    "snr": _col(optional=True),
}
FUSED = {
    "v": V, "t": T, "base": ID,
    "rb": _col(nonneg=True), "vb": _col(), "az": _col(optional=True, angle=True),
    "srb": _col(positive=True), "svb": _col(positive=True), "saz": _col(optional=True, positive=True),
    "n_ch": _col("ints", positive=True),
}
# x: 5 floats, or 3 in a message with azimuth = false (range-Doppler base); P its square
ETRACK = {
    "id": Field("int", nonneg=True), "status": Field("str", choices=TRACK_STATUS),
    "x": Field("floats"), "P": Field("floats"),
    "score": Field("float"), "n_ch": Field("int", nonneg=True),
    "updated": Field("bool"), "ambiguous": Field("bool"),
}
ETRACKS = {"v": V, "t": T, "base": ID, "azimuth": Field("bool", optional=True),
           "tracks": Field("maps", sub=ETRACK)}
GTRACK = {
    "id": Field("int", nonneg=True), "status": Field("str", choices=TRACK_STATUS),
    "x": Field("floats", length=6), "P": Field("floats", length=36),
    "score": Field("float"), "etracks": Field("pairs"), "ambiguous": Field("bool"),
    # geodetic deployments only: WGS-84 position of x (deg, deg, m ellipsoidal height)
    "lat": Field("float", optional=True, interval=(-90.0, 90.0), together="geo"),
    "lon": Field("float", optional=True, interval=(-180.0, 180.0), together="geo"),
    "alt": Field("float", optional=True, together="geo"),
}
GTRACKS = {"v": V, "t": T, "tracks": Field("maps", sub=GTRACK)}
# a network track handed over between partitions of global fusion (docs/networks.md)
HANDED = {"id": Field("int", nonneg=True), "status": Field("str", choices=TRACK_STATUS),
          "x": Field("floats", length=6), "P": Field("floats", length=36), "t_update": T,
          "born": T, "hits": Field("int", nonneg=True), "etracks": Field("pairs")}
HANDOVER = {"v": V, "t": T, "from": ID, "to": ID, "track": Field("map", sub=HANDED)}
HANDOVER_ACK = {"v": V, "t": T, "from": ID, "to": ID, "id": Field("int", nonneg=True)}
DETECTIONS = {
    "v": V, "t": T, "seq": SEQ, "array": ID, "own": Field("map", sub=OWN_SHIP),
    "brg": _col(angle=True), "amp": _col(), "sbrg": _col(optional=True, positive=True),
    "freq": _col(optional=True, positive=True),
}
TRUTH_RADAR = {
    "v": V, "t": T, "id": _col("ints", nonneg=True),
    "x": _col(), "y": _col(), "z": _col(), "vx": _col(), "vy": _col(), "vz": _col(),
}
TRUTH_SONAR = {
    "v": V, "t": T, "array": ID, "own": Field("map", sub=OWN_SHIP),
    "id": _col("ints", nonneg=True), "x": _col(), "y": _col(), "vx": _col(), "vy": _col(),
    "brg": _col(angle=True),
}
BTRACK_STATUS = ("tentative", "confirmed")
BTRACK = {
    "id": Field("int", nonneg=True), "status": Field("str", choices=BTRACK_STATUS),
    "x": Field("floats"), "P": Field("floats"), "quality": Field("float"),
    "ambiguous": Field("bool"), "ml": Field("int", optional=True, nonneg=True),
}
MLTRACK = {
    "id": Field("int", nonneg=True), "lines": Field("ints"),
    "brg": Field("float", angle=True), "brg_rate": Field("float"),
}
BTRACKS = {
    "v": V, "t": T, "array": ID, "tracks": Field("maps", sub=BTRACK),
    "multiline": Field("maps", optional=True, sub=MLTRACK),
}
HISTORY = {
    "v": V, "t": T, "array": ID, "id": Field("int", nonneg=True),
    "status": Field("str", choices=("confirmed", "deleted")),
    "t_hist": _col(nonneg=True), "brg": _col(angle=True), "sbrg": _col(positive=True),
    "own_x": _col(), "own_y": _col(),
    # multiple-hypothesis mode only: the retrodicted bearings at every cycle (000)
    "t_retro": Field("floats", optional=True, nonneg=True, column="retro"),
    "brg_retro": Field("floats", optional=True, angle=True, column="retro"),
    "sbrg_retro": Field("floats", optional=True, positive=True, column="retro"),
}
TMA_SOLUTION = {
    "track": Field("int", nonneg=True), "t": T,
    "x": Field("float"), "y": Field("float"), "vx": Field("float"), "vy": Field("float"),
    "P": Field("floats", length=16), "range": Field("float", nonneg=True),
    "course": Field("float", angle=True), "speed": Field("float", nonneg=True),
    "constrained": Field("bool"), "bounds": Field("floats", length=6), "bounds_modified": Field("bool"),
    "phase": Field("str", choices=("pre", "post")), "residual_factor": Field("float", nonneg=True),
    "legs": Field("floats"),
    # added in v1: absent from older publishers and recordings (docs/protocol.md)
    "converged": Field("bool", optional=True), "ctma_exhausted": Field("bool", optional=True),
    "range_observable": Field("bool", optional=True),
}
TMA_BIRTH = {"track": Field("int", nonneg=True), "birth": T}
TMA = {"v": V, "t": T, "array": ID, "solutions": Field("maps", sub=TMA_SOLUTION),
       # added in v1 (issue 31): the birth of every track of the cycle
       "births": Field("maps", optional=True, sub=TMA_BIRTH)}
# operator inputs (issue 31): req (request id) asks for an ack, birth names the track
REQ = Field("str", optional=True)
BIRTH = Field("float", optional=True, nonneg=True)
TMA_BOUNDS = {
    "v": V, "t": T, "track": Field("int", optional=True, nonneg=True), "birth": BIRTH, "req": REQ,
    "r_min": Field("float", nonneg=True), "r_max": Field("float", positive=True),
    "course_min": Field("float", angle=True), "course_max": Field("float", angle=True),
    "speed_min": Field("float", nonneg=True), "speed_max": Field("float", positive=True),
}
TMA_SUPPORT = {
    "v": V, "t": T, "track": Field("int", nonneg=True), "birth": BIRTH, "req": REQ,
    "kind": Field("str", choices=("range", "course", "speed")), "value": Field("float"),
    "sigma": Field("float", positive=True),
    "obs_x": Field("float", optional=True), "obs_y": Field("float", optional=True),
}
TMA_CLEAR = {
    "v": V, "t": T, "track": Field("int", nonneg=True), "birth": BIRTH, "req": REQ,
    "what": Field("str", choices=("bounds", "support", "all")),
}
TMA_ACK = {
    "v": V, "t": T, "req": ID, "ok": Field("bool"), "reason": ID,
    "track": Field("int", optional=True, nonneg=True), "birth": BIRTH,
}
SIM_STATUS = {"v": V, "t": T, "state": Field("str", choices=("running", "done")),
              "scans": Field("int", nonneg=True), "published": Field("int", nonneg=True)}

SCHEMAS: dict[str, dict[str, Field]] = {
    "plots": PLOTS, "fused": FUSED, "etracks": ETRACKS, "gtracks": GTRACKS,
    "detections": DETECTIONS, "truth_radar": TRUTH_RADAR, "truth_sonar": TRUTH_SONAR,
    "sim_status": SIM_STATUS, "btracks": BTRACKS, "history": HISTORY,
    "tma": TMA, "tma_bounds": TMA_BOUNDS, "tma_support": TMA_SUPPORT,
    "tma_clear": TMA_CLEAR, "tma_ack": TMA_ACK, "handover": HANDOVER,
    "handover_ack": HANDOVER_ACK,
}

# Key layout under the root -> message kind ("*" = one chunk: a base, channel, array, id).
KEY_KINDS: tuple[tuple[tuple[str, ...], str], ...] = (
    (("radar", "plots", "*", "*"), "plots"),
    (("radar", "fused", "*"), "fused"),
    (("radar", "etracks", "*"), "etracks"),
    (("radar", "gtracks"), "gtracks"),
    (("radar", "gtracks", "*"), "gtracks"),
    (("radar", "handover", "*"), "handover"),
    (("radar", "handover_ack", "*"), "handover_ack"),
    (("sonar", "detections", "*"), "detections"),
    (("sonar", "btracks", "*"), "btracks"),
    (("sonar", "history", "*", "*"), "history"),
    (("sonar", "tma", "*"), "tma"),
    (("sonar", "tma", "bounds", "*"), "tma_bounds"),
    (("sonar", "tma", "support", "*"), "tma_support"),
    (("sonar", "tma", "clear", "*"), "tma_clear"),
    (("sonar", "tma", "ack", "*"), "tma_ack"),
    (("sim", "truth", "radar"), "truth_radar"),
    (("sim", "truth", "sonar"), "truth_sonar"),
    (("sim", "status"), "sim_status"),
)


def kind_of(key: str, root: str) -> str | None:
    """The message kind of a full key under ``root`` (None: not a v1 data key)."""
    if not key.startswith(root + "/"):
        return None
    parts = tuple(key[len(root) + 1:].split("/"))
    for pattern, kind in KEY_KINDS:
        if len(pattern) == len(parts) and all(p in ("*", c) for p, c in zip(pattern, parts)):
            return kind
    return None


def _np_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"cannot encode {type(obj).__name__}")


def encode(msg: dict[str, Any]) -> bytes:
    """msgpack-encode a message map (numpy arrays and scalars become lists / numbers)."""
    return msgpack.packb(msg, default=_np_default, use_bin_type=True)


def unpack(payload: bytes) -> dict[str, Any]:
    """msgpack-decode ``payload`` into a map with string keys, or raise DecodeError."""
    if not isinstance(payload, (bytes, bytearray, memoryview)):
        raise DecodeError("<payload>", f"expected bytes, got {type(payload).__name__}")
    if len(payload) > MAX_PAYLOAD:
        raise DecodeError("<payload>", f"{len(payload)} bytes exceeds {MAX_PAYLOAD}")
    try:
        obj = msgpack.unpackb(bytes(payload), raw=False, strict_map_key=False)
    except Exception as e:  # msgpack raises many types on hostile input
        raise DecodeError("<payload>", f"not msgpack ({type(e).__name__}: {e})") from None
    if not isinstance(obj, dict):
        raise DecodeError("<payload>", f"expected a map, got {type(obj).__name__}")
    return obj


# Optional fields present together or not at all, per message kind.
TOGETHER: dict[str, tuple[str, str]] = {"plots": ("az", "saz"), "fused": ("az", "saz")}
ETRACK_SIZES = {True: 5, False: 3}  # len(x) of etracks by the message's azimuth (absent: true)


def decode(kind: str, payload: bytes) -> dict[str, Any]:
    """Unpack and validate a payload of message type ``kind`` (a key of SCHEMAS)."""
    msg = validate(SCHEMAS[kind], unpack(payload), "")
    if msg["v"] != VERSION:
        raise DecodeError("v", f"unsupported protocol version {msg['v']}")
    if kind in TOGETHER:
        a, b = TOGETHER[kind]
        if (a in msg) != (b in msg):
            raise DecodeError(b if a in msg else a, f"missing: {a} and {b} come together")
    if kind == "etracks":
        _etrack_sizes(msg["tracks"], ETRACK_SIZES[msg.get("azimuth", True)])
    return msg


def _etrack_sizes(tracks: list[dict[str, Any]], n: int) -> None:
    """Every x of n elements and every P of n^2."""
    for i, e in enumerate(tracks):
        for name, size in (("x", n), ("P", n * n)):
            if len(e[name]) != size:
                raise DecodeError(f"tracks[{i}].{name}", f"expected {size} elements, got {len(e[name])}")


def validate(schema: dict[str, Field], obj: Any, path: str) -> dict[str, Any]:
    """Check map ``obj`` against ``schema``; return it with lists as numpy arrays."""
    if not isinstance(obj, dict):
        raise DecodeError(path or "<payload>", f"expected a map, got {type(obj).__name__}")
    out: dict[str, Any] = {}
    lengths: dict[str, tuple[str, int]] = {}
    for name, f in schema.items():
        where = f"{path}.{name}" if path else name
        if name not in obj:
            if f.optional:
                continue
            raise DecodeError(where, "missing")
        value = _check(f, obj[name], where)
        if f.column is not None:
            n = len(value)
            if f.column in lengths and lengths[f.column][1] != n:
                other, m = lengths[f.column]
                raise DecodeError(where, f"length {n} differs from {other} length {m}")
            lengths.setdefault(f.column, (where, n))
        out[name] = value
    for name, f in schema.items():
        if f.together is not None and name not in out:
            given = [n for n, g in schema.items() if g.together == f.together and n in out]
            if given:
                raise DecodeError(f"{path}.{name}" if path else name, f"missing (given: {given[0]})")
    return out


def _number(v: Any, where: str, integer: bool) -> float | int:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise DecodeError(where, f"expected a number, got {type(v).__name__}")
    if integer and not isinstance(v, int):
        raise DecodeError(where, "expected an integer")
    if not integer and not math.isfinite(v):
        raise DecodeError(where, f"not finite ({v})")
    return v


def _range(f: Field, a: np.ndarray, where: str) -> None:
    if f.positive and np.any(a <= 0):
        raise DecodeError(where, "must be > 0")
    if f.nonneg and np.any(a < 0):
        raise DecodeError(where, "must be >= 0")
    if f.angle and np.any((a < 0) | (a > TWO_PI)):
        raise DecodeError(where, "angle must be in [0, 2pi] radians")
    if f.interval is not None and np.any((a < f.interval[0]) | (a > f.interval[1])):
        raise DecodeError(where, f"must be in [{f.interval[0]}, {f.interval[1]}]")


def _check(f: Field, v: Any, where: str) -> Any:
    k = f.kind
    if k in ("float", "int"):
        x = _number(v, where, k == "int")
        if k == "int" and abs(x) > 2**62:
            raise DecodeError(where, "integer out of range")
        _range(f, np.asarray([x], dtype=float), where)
        return float(x) if k == "float" else int(x)
    if k == "bool":
        if not isinstance(v, bool):
            raise DecodeError(where, f"expected a bool, got {type(v).__name__}")
        return v
    if k == "str":
        if not isinstance(v, str) or not v:
            raise DecodeError(where, "expected a non-empty string")
        if f.choices is not None and v not in f.choices:
            raise DecodeError(where, f"'{v}' is not one of {f.choices}")
        return v
    if k == "map":
        return validate(f.sub or {}, v, where)
    if not isinstance(v, (list, tuple)):
        raise DecodeError(where, f"expected a list, got {type(v).__name__}")
    if f.length is not None and len(v) != f.length:
        raise DecodeError(where, f"expected {f.length} elements, got {len(v)}")
    if k == "maps":
        return [validate(f.sub or {}, item, f"{where}[{i}]") for i, item in enumerate(v)]
    if k == "pairs":
        return [_pair(item, f"{where}[{i}]") for i, item in enumerate(v)]
    if k == "strs":
        for i, s in enumerate(v):
            _check(Field("str"), s, f"{where}[{i}]")
        return list(v)
    integer = k == "ints"
    for i, x in enumerate(v):
        _number(x, f"{where}[{i}]", integer)
    if integer and any(abs(x) > 2**62 for x in v):
        raise DecodeError(where, "integer out of range")
    a = np.asarray(v, dtype=np.int64 if integer else np.float64)
    _range(f, a, where)
    return a


def _pair(item: Any, where: str) -> tuple[str, int]:
    """A (base id, elementary track id) reference of a global track."""
    if not isinstance(item, (list, tuple)) or len(item) != 2:
        raise DecodeError(where, "expected [base, id]")
    base = _check(Field("str"), item[0], where + "[0]")
    tid = _check(Field("int", nonneg=True), item[1], where + "[1]")
    return base, tid
