"""The ``.pfrec`` recording format: a msgpack stream of one header map
``{format: "pfrec", version: 1, root, created}`` followed by records
``[key, t, payload]`` (full Zenoh key, seconds since the recording started, the payload
bytes as received).

A record cut short at the end of the file (a recorder that was killed) is tolerated: the
reader stops there and reports ``truncated_bytes``. Anything else that does not match is
a :class:`RecordingError` naming the record.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import IO, Any

import msgpack

FORMAT = "pfrec"
VERSION = 1
CHUNK = 1 << 16


class RecordingError(ValueError):
    """A file that is not a valid recording."""


@dataclass(frozen=True)
class Record:
    """One received sample."""

    key: str
    t: float
    payload: bytes


class RecordWriter:
    """Appends records to a binary stream after writing the header."""

    def __init__(self, stream: IO[bytes], root: str, created: float) -> None:
        self._stream = stream
        self._last_t = 0.0
        self.count = 0
        stream.write(msgpack.packb(
            {"format": FORMAT, "version": VERSION, "root": root, "created": float(created)}))

    def write(self, key: str, t: float, payload: bytes) -> None:
        """Append a record; ``t`` must not go backwards."""
        if not math.isfinite(t) or t < self._last_t:
            raise ValueError(f"record time {t} is before the previous one ({self._last_t})")
        self._stream.write(msgpack.packb([key, float(t), bytes(payload)], use_bin_type=True))
        self._last_t = t
        self.count += 1


class RecordReader:
    """Iterates the records of a stream; the header is read and checked at construction.

    After the iteration, ``truncated_bytes`` > 0 means the last record was cut short
    (``errors`` is then 1).
    """

    def __init__(self, stream: IO[bytes]) -> None:
        self._stream = stream
        self._unpacker = msgpack.Unpacker(raw=False, strict_map_key=False)
        self._fed = 0
        self._consumed = 0
        self.truncated_bytes = 0
        self.count = 0
        first = self._next()
        if first is None:
            raise RecordingError("no header: empty or truncated file")
        self.header = check_header(first)
        self.root: str = self.header["root"]

    @property
    def errors(self) -> int:
        return 1 if self.truncated_bytes else 0

    def _next(self) -> Any | None:
        """The next msgpack object, or None at the end of the data."""
        while True:
            try:
                obj = self._unpacker.unpack()
                self._consumed = self._unpacker.tell()
                return obj
            except msgpack.OutOfData:
                chunk = self._stream.read(CHUNK)
                if not chunk:
                    self.truncated_bytes = self._fed - self._consumed
                    return None
                self._fed += len(chunk)
                self._unpacker.feed(chunk)
            except Exception as e:  # msgpack raises several types on corrupt data
                raise RecordingError(f"record {self.count}: not msgpack ({e})") from None

    def __iter__(self) -> Iterator[Record]:
        last_t = 0.0
        while (obj := self._next()) is not None:
            rec = check_record(obj, self.count, last_t)
            last_t = rec.t
            self.count += 1
            yield rec


def check_header(obj: Any) -> dict[str, Any]:
    """The header map, or RecordingError."""
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        raise RecordingError("not a pfrec recording (no pfrec header)")
    if obj.get("version") != VERSION:
        raise RecordingError(f"unsupported pfrec version {obj.get('version')!r}")
    if not isinstance(obj.get("root"), str) or not obj["root"]:
        raise RecordingError("header: root must be a non-empty string")
    created = obj.get("created")
    if isinstance(created, bool) or not isinstance(created, (int, float)):
        raise RecordingError("header: created must be a number (UNIX time)")
    return obj


def check_record(obj: Any, index: int, last_t: float) -> Record:
    """Record number ``index``, or RecordingError."""
    if not isinstance(obj, list) or len(obj) != 3:
        raise RecordingError(f"record {index}: expected [key, t, payload]")
    key, t, payload = obj
    if not isinstance(key, str) or not key:
        raise RecordingError(f"record {index}: key must be a non-empty string")
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
        raise RecordingError(f"record {index}: t must be a finite number")
    if t < last_t:
        raise RecordingError(f"record {index}: t={t} goes back from {last_t}")
    if not isinstance(payload, bytes):
        raise RecordingError(f"record {index}: payload must be bytes")
    return Record(key, float(t), payload)
