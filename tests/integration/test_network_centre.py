"""The fusion centre alone through its process (benchmarks/network_centre.py, issue 29
section 3) on a small goal scene (20 aircraft, 15 s, 21 range-Doppler bases): the
recorded elementary tracks, replayed by `pfusion replay` as fast as possible into the
real global-fusion service pinned to one core, all reach it (its counters: every report
in, none missed or rejected; every radar/gtracks stamp received, the last at the end of
the scene), and its tracks are those of the same core fed the same recording in this
process. About 12 s."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks import network_centre
from common.bus.recording import RecordReader
from common.deploy.config import load
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import etracks_of, gtracks_message

AIRCRAFT, DURATION = 20, 15.0


def in_process(scene: Path, rec: Path) -> list[dict]:
    """The gtracks messages of the recording through the core in this process."""
    cfg = load(scene)
    core = RadarChain(cfg).fusion
    out = []
    with rec.open("rb") as f:
        for r in RecordReader(f):
            base, tracks = etracks_of(r.payload)
            out += core.push(base, tracks, 0.0)
    out += core.flush()
    return [gtracks_message(g, cfg.origin) for g in out]


def test_centre_replay_loses_nothing(tmp_path: Path) -> None:
    scene, rec, reports, t_last = network_centre.cached(AIRCRAFT, 1, DURATION, tmp_path / "cache")
    assert reports > 20 * DURATION  # 21 bases, one report every 0.5-1 s
    args = argparse.Namespace(speed=0.0, core=None)
    row, msgs = network_centre.run_centre(AIRCRAFT, scene, rec, reports, t_last, DURATION, args,
                                          tmp_path)
    assert row.lost == [], row.lost
    assert row.gtracks >= DURATION - 2 and row.cpu_s > 0
    want = {m["t"]: m for m in in_process(scene, rec)}
    got = {m["t"]: m for m in msgs}
    assert sorted(got) == sorted(want)
    for t, m in want.items():
        assert [tr["id"] for tr in got[t]["tracks"]] == [tr["id"] for tr in m["tracks"]]
        np.testing.assert_allclose([tr["x"] for tr in got[t]["tracks"]],
                                   [tr["x"] for tr in m["tracks"]], rtol=0, atol=1e-9)
