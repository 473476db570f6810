"""The .pfrec format: round trip, a truncated last record, invalid files."""

from __future__ import annotations

import io

import msgpack
import pytest

from common.recording import RecordReader, RecordWriter, RecordingError

RECORDS = [("pf/v1/radar/plots/b1/c1", 0.0, b"\x81\xa1v\x01"),
           ("pf/v1/radar/plots/b1/c2", 0.25, b""),
           ("pf/v1/sim/status", 0.25, bytes(range(256)) * 40)]


def written(records=RECORDS, root: str = "pf/v1") -> bytes:
    buf = io.BytesIO()
    w = RecordWriter(buf, root, 1.7e9)
    for key, t, payload in records:
        w.write(key, t, payload)
    assert w.count == len(records)
    return buf.getvalue()


def read_all(data: bytes) -> tuple[RecordReader, list[tuple[str, float, bytes]]]:
    reader = RecordReader(io.BytesIO(data))
    return reader, [(r.key, r.t, r.payload) for r in reader]


def test_round_trip() -> None:
    reader, recs = read_all(written())
    assert recs == RECORDS
    assert reader.header == {"format": "pfrec", "version": 1, "root": "pf/v1", "created": 1.7e9}
    assert reader.root == "pf/v1"
    assert (reader.count, reader.errors, reader.truncated_bytes) == (3, 0, 0)


def test_large_recording_spans_read_chunks() -> None:
    recs = [(f"pf/v1/k/{i % 7}", i * 0.001, bytes([i % 256]) * (i % 300)) for i in range(5000)]
    reader, got = read_all(written(recs))
    assert got == recs and reader.errors == 0


@pytest.mark.parametrize("cut", [1, 2, 10, 100])
def test_truncated_last_record_is_tolerated_and_counted(cut: int) -> None:
    data = written()
    reader, recs = read_all(data[:-cut])
    assert recs == RECORDS[:2]
    assert reader.errors == 1
    assert reader.truncated_bytes == len(data) - cut - len(written(RECORDS[:2]))


def test_empty_or_headerless_file_is_an_error() -> None:
    with pytest.raises(RecordingError, match="no header"):
        RecordReader(io.BytesIO(b""))
    with pytest.raises(RecordingError, match="no header"):
        RecordReader(io.BytesIO(written()[:5]))
    with pytest.raises(RecordingError, match="not a pfrec"):
        RecordReader(io.BytesIO(msgpack.packb(["pf/v1/x", 0.0, b""])))


def test_wrong_version_is_an_error() -> None:
    head = msgpack.packb({"format": "pfrec", "version": 2, "root": "pf/v1", "created": 0.0})
    with pytest.raises(RecordingError, match="version 2"):
        RecordReader(io.BytesIO(head))


@pytest.mark.parametrize("bad, match", [
    (["k", 1.0], "expected"),
    (["", 1.0, b""], "key"),
    (["k", "0", b""], "finite"),
    (["k", float("nan"), b""], "finite"),
    (["k", 1.0, "text"], "payload"),
    (["k", 0.1, b""], "goes back"),
])
def test_invalid_record_names_its_index(bad: list, match: str) -> None:
    data = written(RECORDS[:2]) + msgpack.packb(bad, use_bin_type=True)
    reader = RecordReader(io.BytesIO(data))
    with pytest.raises(RecordingError, match=f"record 2: .*{match}"):
        list(reader)


def test_writer_refuses_time_going_back() -> None:
    w = RecordWriter(io.BytesIO(), "pf/v1", 0.0)
    w.write("k", 1.0, b"")
    with pytest.raises(ValueError):
        w.write("k", 0.5, b"")
