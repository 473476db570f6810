"""``pfusion replay`` into services that already processed later times (issue 32): it
refuses, exit code 3, naming them; with ``--reset`` it restarts them through their
control queryable (common.bus.control) and they process the whole recording. Through
the processes: a real router, a real elementary tracker, the replay command."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from common.bus import control
from common.bus.recording import RecordWriter
from common.radar.plots.channel_fusion import Plots
from common.wire import protocol
from common.wire.radar_messages import fused_message
from tests.harness import ROOT, SCENARIOS, Deployment

TWO_TARGETS = str(SCENARIOS / "two_targets.toml")
TRACKER = ("elementary_tracker", "b1")


def fused(t: float) -> bytes:
    """An empty radar/fused/b1 scan at time t (the tracker steps, publishes, moves on)."""
    empty = np.zeros(0)
    msg = fused_message("b1", t, Plots(empty, empty, empty, empty, empty, empty, np.zeros(0, dtype=np.int64)))
    return protocol.encode(msg)


def recording(path: Path, times: list[float]) -> Path:
    with path.open("wb") as f:
        w = RecordWriter(f, ROOT, 1.7e9)
        for i, t in enumerate(times):
            w.write(f"{ROOT}/radar/fused/b1", 0.01 * i, fused(t))
    return path


@pytest.mark.timeout(180)
def test_replay_refuses_services_ahead_and_resets_them(tmp_path: Path) -> None:
    """The tracker has run to t = 50; a recording of t = 1..5 is refused (exit 3, the
    tracker named with its time); with --reset the same process restarts fresh and
    tracks t = 1..5. About 6 s."""
    rec = recording(tmp_path / "early.pfrec", [1.0, 2.0, 3.0, 4.0, 5.0])
    with Deployment(tmp_path) as d:
        d.collect("radar/etracks/b1")
        names = d.start_services(Path(TWO_TARGETS), ("elementary-tracker",))
        d.wait_alive(names)
        tracker = next(c for c in d.children if c.name == "elementary-tracker-b1")
        for t in (40.0, 50.0):
            d.session.put(f"{ROOT}/radar/fused/b1", fused(t))
        d.wait_for(lambda: [m["t"] for m in d.of("radar/etracks/b1")] == [40.0, 50.0])
        assert control.ahead(control.states(d.session, ROOT), 1.0) == {TRACKER: 50.0}
        assert control.ahead(control.states(d.session, ROOT), 60.0) == {}

        refused = d.start("replay", "replay", str(rec), "--config", TWO_TARGETS)
        assert refused.wait(60) == 3
        err = (tmp_path / "replay.log").read_text()
        assert "services ahead of the recording (it starts at t=1): elementary_tracker/b1 (t=50)" in err
        assert "--reset" in err
        d.drain()
        assert len(d.of("radar/etracks/b1")) == 2  # nothing was replayed

        reset = d.start("replay-reset", "replay", str(rec), "--config", TWO_TARGETS, "--reset")
        assert reset.wait(60) == 0
        d.wait_for(lambda: [m["t"] for m in d.of("radar/etracks/b1")][2:] == [1.0, 2.0, 3.0, 4.0, 5.0])
        assert tracker.alive()  # restarted inside its own process: the supervisor saw no crash
        log = (tmp_path / "elementary-tracker-b1.log").read_text()
        assert "reset by a control query: restarting with a fresh state" in log
        assert "rejected" not in log  # no replayed scan was late
        state = control.states(d.session, ROOT)[TRACKER]
        assert state["t"] == 5.0 and state["in"] == 5
