"""The history queryable "as of" a btracks time through the real bearing-tracker process
(docs/protocol.md, common.sonar.history_as_of): the issue 31 close approach
(scenarios/sonar_cpa_coarse.toml) in the multiple-hypothesis mode, the simulator as fast
as it goes. Once the tracker has taken every scan, a query with ``as_of`` = the time of
an earlier cycle gets the reply that a tracker in this process, fed the same detection
lists, gives right after that cycle (its retrodiction has since rewritten those rows:
the test checks that the register of now differs); a query without ``as_of`` gets the
register of now, as before the parameter. About 5 s (router, one service, 30 scans).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from common.core.crossing import CrossingParams
from common.deploy.config import load, section
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.trackers import bearing_tracker
from common.wire import protocol
from tests.harness import ROOT, SCENARIOS, Deployment

KEPT = 16  # [sonar.tracker] history_as_of_cycles, the default


def _reply(d: Deployment, tid: int, as_of: float | None) -> dict:
    sel = f"{ROOT}/sonar/history/a1/{tid}" + ("" if as_of is None else f"?as_of={as_of!r}")
    replies = [r for r in d.session.get(sel, timeout=5) if r.ok is not None]
    assert len(replies) == 1, (tid, as_of)
    return protocol.decode("history", replies[0].ok.payload.to_bytes())


def _same(msg: dict, found: tuple) -> bool:
    status, cols = found
    cols = {("t_hist" if k == "t" else k): v for k, v in cols.items()}
    return msg["status"] == status and all(np.array_equal(np.asarray(msg[k]), v) for k, v in cols.items())


def test_history_as_of_an_earlier_cycle_through_the_tracker_process(tmp_path: Path) -> None:
    scene = tmp_path / "cpa_mht.toml"
    scene.write_text((SCENARIOS / "sonar_cpa_coarse.toml").read_text()
                     + '\n[sonar.tracker]\nmode_association = "mht"\n'
                     + f"\n[sonar.tracker.mht]\nrho_f = {1.0 / (2 * math.pi * 10.0)!r}\n")
    cfg = load(scene)
    arr = cfg.arrays[0]
    with Deployment(tmp_path) as d:
        d.collect("sonar/detections/a1")
        d.collect("sonar/btracks/a1")
        d.start("btracker", "bearing-tracker", "--config", str(scene), "--array", "a1")
        d.wait_alive(["bearing_tracker/a1"])
        d.simulate(scene, seed=1, wait_alive=["bearing_tracker/a1"])
        d.wait_for(lambda: len(d.of("sonar/btracks/a1")) == 30)
        dets = sorted(d.of("sonar/detections/a1"), key=lambda m: m["t"])
        # the same chain in this process: the reply of every confirmed track after every cycle
        core = bearing_tracker(section(cfg, "sonar.tracker", SonarTrackerParams),
                               section(cfg, "sonar.tracker.mht", MhtParams), arr.kind, arr.sigma0,
                               section(cfg, "sonar.crossing", CrossingParams))
        then: dict[float, dict[int, tuple]] = {}
        for m in dets:
            amp = np.asarray(m["amp"])
            good = amp > 0
            o = m["own"]
            c = core.step(m["t"], np.asarray(m["brg"])[good], amp[good], o["heading"], o["x"], o["y"],
                          None, np.asarray(m["sbrg"])[good])
            then[m["t"]] = {int(i): core.history_of(int(i)) for i in c.ids[c.confirmed]}
        times = sorted(then)[-KEPT:-1]
        asked = revised = 0
        for t in times:
            for tid, found in then[t].items():
                assert found is not None
                msg = _reply(d, tid, t)
                assert _same(msg, found), (t, tid)
                assert msg["t"] == t
                asked += 1
                now = core.history_of(tid)
                cut = {k: v[now[1]["t_retro" if k.endswith("_retro") else "t"] <= t] for k, v in now[1].items()}
                revised += not _same(msg, (now[0], cut))
        tid = next(iter(then[max(then)]))
        assert _same(_reply(d, tid, None), core.history_of(tid))  # no as_of: the register of now
    assert asked >= 10 and revised > 0, (asked, revised)
