"""The .pfrec format (round trip, a truncated last record, invalid files) and a real
record -> replay run that must give the services' outputs again."""

from __future__ import annotations

import io
from pathlib import Path

import msgpack
import numpy as np
import pytest
import zenoh

from common.bus.recording import Record, RecordingError, RecordReader, RecordWriter
from common.bus.transport import stamp
from common.cli import COMMANDS
from common.deploy.config import load
from common.deploy.deployment import ChildSpec, plan
from common.wire import protocol
from services.record.main import Writer
from tests.harness import ROOT, SCENARIOS, Deployment

TWO_TARGETS = str(SCENARIOS / "two_targets.toml")
SCANS = 120
PER_BASE = {"channel-plotter": "radar/fused/{}", "elementary-tracker": "radar/etracks/{}"}

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


def outputs(d: Deployment, keys: list[str]) -> dict[str, dict[float, dict]]:
    """Every output message of ``keys``, by key and message time (times are unique)."""
    out: dict[str, dict[float, dict]] = {}
    for k in keys:
        msgs = d.of(k)
        out[k] = {m["t"]: m for m in msgs}
        assert len(out[k]) == len(msgs), f"{k}: two messages with one time"
    return out


def start(d: Deployment, specs: list[ChildSpec], keys: list[str]) -> None:
    """Collect ``keys`` and sim/status, then start the services of ``specs``."""
    for k in [*keys, "sim/status"]:
        d.collect(k)
    for s in specs:
        d.start(s.name.replace("/", "-"), *s.argv)


def wait_last_scan(d: Deployment, keys: list[str]) -> None:
    d.wait_for(lambda: bool(d.of("sim/status")))
    last = d.of("sim/status")[0]["t"]
    d.wait_for(lambda: all(any(m["t"] == last for m in d.of(k)) for k in keys))


def replay(d: Deployment, recording: Path, specs: list[ChildSpec],
           keys: list[str]) -> dict[str, dict[float, dict]]:
    """Fresh ``specs`` fed by ``recording``: their outputs on ``keys``."""
    start(d, specs, keys)
    child = d.start("replay", "replay", str(recording), "--config", TWO_TARGETS,
                    "--wait-alive", "test/collector",
                    *[a for s in specs for a in ("--wait-alive", s.alive)])
    wait_last_scan(d, keys)
    assert child.wait(30) == 0
    return outputs(d, keys)


def same(a: object, b: object, where: str) -> None:
    """Equal messages: numbers (and arrays) to 1e-9, everything else exactly."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for k in a:
            same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{where}[{i}]")
    elif isinstance(a, (np.ndarray, float)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9, err_msg=where)
    else:
        assert a == b, where


def same_outputs(a: dict[str, dict[float, dict]], b: dict[str, dict[float, dict]]) -> None:
    for k in a:
        assert len(a[k]) == SCANS and a[k].keys() == b[k].keys(), k
        for t in a[k]:
            same(a[k][t], b[k][t], f"{k} t={t}")


def records(path: Path) -> list[Record]:
    with path.open("rb") as f:
        reader = RecordReader(f)
        recs = list(reader)
    assert reader.errors == 0 and reader.root == ROOT
    return recs


@pytest.mark.slow
def test_record_then_replay_gives_the_same_tracks(tmp_path: Path) -> None:
    """Plots recorded live and replayed into a fresh chain (plotters, elementary trackers,
    global fusion) give the same fused plots, elementary tracks and global tracks: same
    numbers, states equal to 1e-9."""
    specs = plan(load(TWO_TARGETS), TWO_TARGETS, COMMANDS)
    per_base = [s for s in specs if s.argv[0] in PER_BASE]
    keys = [PER_BASE[s.argv[0]].format(s.argv[-1]) for s in per_base] + ["radar/gtracks"]
    plots = tmp_path / "plots.pfrec"
    for sub in ("live", "replay"):
        (tmp_path / sub).mkdir()
    with Deployment(tmp_path / "live") as d:
        start(d, specs, keys + ["radar/plots/**"])
        recorder = d.start("record-plots", "record", "radar/plots/**", "sim/status", "--out",
                           str(plots), "--config", TWO_TARGETS)
        d.simulate(Path(TWO_TARGETS), wait_alive=[s.alive for s in specs] + ["record/plots"])
        wait_last_scan(d, keys)
        assert recorder.wait(30) == 0
        live = outputs(d, keys)
        live_plots = [(k, m) for k, m in d.messages if "/plots/" in k]
    assert records(plots)[-1].key == f"{ROOT}/sim/status"
    recorded = [r for r in records(plots) if "/plots/" in r.key]
    assert [r.key for r in recorded] == [k for k, _ in live_plots]
    assert len(recorded) == SCANS * 9
    for r, (_, m) in zip(recorded, live_plots):
        same(protocol.decode("plots", r.payload), m, r.key)
    assert any(tr["status"] == "confirmed" for m in live["radar/gtracks"].values()
               for tr in m["tracks"])
    with Deployment(tmp_path / "replay") as d:
        again = replay(d, plots, specs, keys)
    same_outputs(live, again)


def test_replay_then_record_again_gives_the_same_file_content(tmp_path: Path) -> None:
    """Two key expressions, a simulator run: a recording replayed as fast as possible and
    recorded again has the same records (key, payload) in the same order."""
    first, second = tmp_path / "first.pfrec", tmp_path / "second.pfrec"
    with Deployment(tmp_path) as d:
        rec = d.start("record-first", "record", "radar/plots/b1/*", "sim/**", "--out", str(first))
        d.simulate(Path(TWO_TARGETS), wait_alive=["record/first"])
        assert rec.wait(30) == 0
        rec = d.start("record-second", "record", "radar/plots/b1/*", "sim/**", "--out", str(second))
        replay = d.start("replay", "replay", str(first), "--wait-alive", "record/second")
        assert replay.wait(30) == 0 and rec.wait(30) == 0
    a, b = records(first), records(second)
    assert len(a) == SCANS * (3 + 1) + 1
    assert a[-1].key == f"{ROOT}/sim/status"
    assert [(r.key, r.payload) for r in a] == [(r.key, r.payload) for r in b]


def test_recorder_counts_the_samples_that_never_arrived() -> None:
    """pfusion record writes the wanted samples and counts, from their stamps, those
    that never arrived (per key); a bad stamp is logged and its sample still written."""
    f = io.BytesIO()
    w = Writer(RecordWriter(f, ROOT, 0.0), [zenoh.KeyExpr(f"{ROOT}/radar/plots/**")], t0=100.0)
    key, other = f"{ROOT}/radar/plots/b1/c1", f"{ROOT}/radar/fused/b1"
    for k, (n, t) in enumerate([(0, 100.1), (1, 100.2), (4, 100.3), (5, 100.4)]):
        w.take(t, key, bytes([k]), stamp("sensor", n))
    w.take(100.5, other, b"x", stamp("fuser", 9))  # not wanted: neither written nor checked
    w.take(100.6, key, b"y", b"\x93bad")
    assert dict(w.losses.missed) == {key: 2}
    _, recs = read_all(f.getvalue())
    assert [(k, p) for k, _, p in recs] == [(key, bytes([0])), (key, bytes([1])), (key, bytes([2])),
                                           (key, bytes([3])), (key, b"y")]
