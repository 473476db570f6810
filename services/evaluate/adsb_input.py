"""The inputs of ``pfusion evaluate --truth-adsb``: aircraft.json snapshots from files
(a file, or every ``*.json`` / ``*.json.gz`` under a directory, in name order) and the
radar/gtracks messages of a ``.pfrec`` recording."""

from __future__ import annotations

import gzip
import json
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from common.bus.recording import RecordReader
from common.evaluation.adsb import Fix, parse_snapshot
from common.wire import protocol


def snapshot_files(path: Path) -> list[Path]:
    """The snapshot files of a file or directory."""
    if path.is_file():
        return [path]
    return sorted(p for p in path.rglob("*") if p.name.endswith((".json", ".json.gz")))


def read_fixes(path: Path, rejects: Counter[str], baro_offset: float | None) -> list[Fix]:
    """Every fix of the snapshots of ``path``; an unreadable file counts as ``bad_file``."""
    out: list[Fix] = []
    for p in snapshot_files(path):
        try:
            raw = gzip.decompress(p.read_bytes()) if p.name.endswith(".gz") else p.read_bytes()
            doc = json.loads(raw)
        except (OSError, ValueError):  # gzip.BadGzipFile and JSONDecodeError are ValueErrors
            rejects["bad_file"] += 1
            continue
        out += parse_snapshot(doc, rejects, baro_offset)
    return out


def recorded_gtracks(path: Path, rejects: Counter[str]) -> Iterator[dict[str, Any]]:
    """The decoded radar/gtracks messages of a recording, in order; undecodable ones
    count as ``bad_gtracks``."""
    with path.open("rb") as f:
        reader = RecordReader(f)
        for rec in reader:
            if protocol.kind_of(rec.key, reader.root) != "gtracks":
                continue
            try:
                yield protocol.decode("gtracks", rec.payload)
            except protocol.DecodeError:
                rejects["bad_gtracks"] += 1
