"""``pfusion tma-input`` through the processes (issue 31 section 3): an operator's bounds
for one track change that track's TMA solution (CTMA used) and not another's, the command
gets the tma service's ack (exit 0) or its refusal (exit 1 with the reason), the input
survives a killed and restarted tma service ([sonar.tma] state_dir), and a new track
reusing the number does not inherit it.

(a) router + bearing tracker + tma + simulator on scenarios/sonar_tma.toml at 100x;
(b) router + tma fed btracks, own ship and history replies by the test, to delete and
reuse a number on cue (and a corrupt state file at its start). Measured: (a) about 8 s, (b) about 3 s of wall time.
"""

from __future__ import annotations

import json
import math
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import zenoh

from common.core.angles import TWO_PI
from common.wire import protocol
from common.wire.sonar_messages import history_message
from tests.harness import ROOT, SCENARIOS, Deployment

R_MIN, R_MAX = 30000.0, 90000.0  # the contacts of sonar_tma are at 5-12 km: CTMA at r_min


def scene(tmp_path: Path, extra: str = "") -> Path:
    """sonar_tma.toml with a state folder for the tma service."""
    cfg = tmp_path / "sonar_tma.toml"
    cfg.write_text((SCENARIOS / "sonar_tma.toml").read_text()
                   + f'\n[sonar.tma]\nstate_dir = "{tmp_path / "state"}"\n{extra}')
    return cfg


def tma_input(d: Deployment, name: str, *args: str, timeout: float = 60.0) -> tuple[int, str]:
    """Run ``pfusion tma-input ARGS`` to its end; its exit code and output."""
    child = d.start(name, "tma-input", *args)
    code = child.wait(timeout)
    return code, (d.logdir / f"{name}.log").read_text()


def solution(msg: dict[str, Any], track: int) -> dict[str, Any] | None:
    return next((s for s in msg["solutions"] if s["track"] == track), None)


def test_bounds_for_one_track_acked_kept_across_a_restart(tmp_path: Path) -> None:
    cfg = scene(tmp_path, "cycle_dt = 20.0\n")
    with Deployment(tmp_path) as d:
        for key in ("sonar/tma/a1", "sonar/tma/ack/a1"):
            d.collect(key)
        d.start("btracker", "bearing-tracker", "--config", str(cfg), "--array", "a1")
        tma = d.start("tma", "tma", "--config", str(cfg), "--array", "a1")
        d.wait_alive(["bearing_tracker/a1", "tma/a1"])
        d.announce()
        d.start("simulate", "simulate", "--config", str(cfg), "--scenario", str(cfg), "--seed", "1",
                "--speed", "100", "--wait-alive", "test/collector", "--wait-alive", "tma/a1")
        d.wait_for(lambda: any(m["t"] >= 300.0 and len(m["solutions"]) >= 2 for m in d.of("sonar/tma/a1")))
        first = d.of("sonar/tma/a1")[-1]
        a, b = (s["track"] for s in first["solutions"][:2])
        code, out = tma_input(d, "bounds", "bounds", "--config", str(cfg), "--array", "a1", "--track", str(a),
                              "--range-min", str(R_MIN), "--range-max", str(R_MAX))
        assert code == 0, out
        acks = d.of("sonar/tma/ack/a1")
        assert [(x["ok"], x["reason"], x["track"]) for x in acks] == [(True, "accepted", a)]
        birth = acks[0]["birth"]
        assert f"born at t={birth}" in out and "accepted by tma/a1" in out

        def constrained_a(since: int) -> dict[str, Any] | None:
            """The first tma message after ``since`` with track a's solution at the bounds."""
            return next((m for m in d.of("sonar/tma/a1")[since:]
                         if (s := solution(m, a)) and s["bounds"][0] == R_MIN), None)

        d.wait_for(lambda: constrained_a(0) is not None)
        m = constrained_a(0)
        sa, sb = solution(m, a), solution(m, b)
        assert sa["constrained"] and sa["range"] >= R_MIN - 1e-6
        # the other track keeps the array's bounds (it may be constrained by them, early on)
        assert sb is not None and sb["bounds"][0] == 100.0 and sb["range"] < R_MIN
        # a birth that is not the track's: refused with the reason, exit 1
        code, out = tma_input(d, "stale", "clear", "--config", str(cfg), "--array", "a1", "--track", str(a),
                              "--birth", str(birth + 1.0))
        assert code == 1 and "refused by tma/a1: stale_birth" in out, out
        state = json.loads((tmp_path / "state" / "tma-a1.json").read_text())
        assert [(e["track"], e["birth"], e["bounds"][0]) for e in state["inputs"]] == [(a, birth, R_MIN)]
        # a crash (SIGKILL) and a new tma process: the input is still there
        tma.proc.send_signal(signal.SIGKILL)
        tma.proc.wait(10)
        n = len(d.of("sonar/tma/a1"))
        d.start("tma2", "tma", "--config", str(cfg), "--array", "a1")
        d.wait_for(lambda: constrained_a(n) is not None)
        m = constrained_a(n)
        assert {"track": a, "birth": birth} in m["births"]
        sb = solution(m, b)
        assert sb is None or (sb["bounds"][0] == 100.0 and sb["range"] < R_MIN)


SIG = 0.01
TARGET = np.array([6000.0, 4000.0, -2.0, 1.5])


def own_at(t: float) -> tuple[float, float]:
    """Own ship: North at 3 m/s for 900 s, then East at 3 m/s."""
    return (0.0, 3.0 * t) if t <= 900.0 else (3.0 * (t - 900.0), 2700.0)


def brg(t: float) -> float:
    ox, oy = own_at(t)
    x, y = TARGET[:2] + TARGET[2:] * t
    return math.atan2(x - ox, y - oy) % TWO_PI


class Feed:
    """The bearing tracker's side for the tma service: own ship and btracks per cycle,
    and the register of track 1 (true bearings every 20 s) on history queries."""

    def __init__(self, d: Deployment) -> None:
        self.d, self.t = d, 1480.0
        self.q = d.session.declare_queryable(f"{ROOT}/sonar/history/a1/*", self.reply)

    def reply(self, query: zenoh.Query) -> None:
        times = np.arange(0.0, self.t + 1.0, 20.0)
        own = np.array([own_at(x) for x in times])
        reg = {"t": times, "brg": np.array([brg(x) for x in times]), "sbrg": np.full(times.size, SIG),
               "own_x": own[:, 0], "own_y": own[:, 1]}
        query.reply(query.key_expr, protocol.encode(history_message("a1", self.t, 1, ("confirmed", reg))))

    def cycle(self, status: str | None) -> None:
        """The next cycle (20 s later) with track 1 of that status (None: no track)."""
        self.t += 20.0
        t, (ox, oy) = self.t, own_at(self.t)
        self.d.session.put(f"{ROOT}/sonar/detections/a1", protocol.encode({
            "v": 1, "t": t, "seq": int(t), "array": "a1", "own": {"x": ox, "y": oy, "heading": 0.0, "speed": 3.0},
            "brg": [], "amp": []}))
        P = [0.0] * 16
        P[0] = SIG**2
        tracks = [] if status is None else [{"id": 1, "status": status, "x": [brg(t), 0.0, 20.0, 0.0], "P": P,
                                             "quality": 5.0, "ambiguous": False}]
        self.d.session.put(f"{ROOT}/sonar/btracks/a1", protocol.encode(
            {"v": 1, "t": t, "array": "a1", "tracks": tracks}))

    def until(self, what: Any, timeout: float = 60.0) -> None:
        """Cycles every 0.2 s (track 1 confirmed) until ``what()`` holds."""
        deadline = time.monotonic() + timeout
        while not what():
            assert time.monotonic() < deadline, "timed out"
            self.cycle("confirmed")
            time.sleep(0.2)
            self.d.drain()


def test_a_reused_number_does_not_inherit(tmp_path: Path) -> None:
    cfg = scene(tmp_path, "cycle_dt = 0.0\n")
    (tmp_path / "state").mkdir()
    (tmp_path / "state" / "tma-a1.json").write_text("{not json")  # counted, left aside, replaced
    with Deployment(tmp_path) as d:
        for key in ("sonar/tma/a1", "sonar/tma/ack/a1", "metrics/tma/a1"):
            d.collect(key)
        d.start("tma", "tma", "--config", str(cfg), "--array", "a1")
        d.wait_alive(["tma/a1"])
        feed = Feed(d)
        feed.until(lambda: any(solution(m, 1) for m in d.of("sonar/tma/a1")))
        child = d.start("bounds", "tma-input", "bounds", "--config", str(cfg), "--array", "a1", "--track", "1",
                        "--range-min", str(R_MIN), "--range-max", str(R_MAX))
        feed.until(lambda: not child.alive())
        assert child.proc.returncode == 0
        birth = d.of("sonar/tma/ack/a1")[0]["birth"]
        feed.until(lambda: (s := solution(d.of("sonar/tma/a1")[-1], 1)) is not None and s["constrained"])
        feed.cycle(None)  # track 1 deleted
        feed.cycle("tentative")  # its number reused by a new track
        reborn = feed.t
        n = len(d.of("sonar/tma/a1"))
        feed.until(lambda: any(solution(m, 1) for m in d.of("sonar/tma/a1")[n:]))
        m = next(m for m in d.of("sonar/tma/a1")[n:] if solution(m, 1))
        assert m["births"] == [{"track": 1, "birth": reborn}] and reborn != birth
        s = solution(m, 1)
        assert not s["constrained"] and s["bounds"][0] == 100.0
        # a support value for the new track: the birth taken from the next tma message
        child = d.start("support", "tma-input", "support", "--config", str(cfg), "--array", "a1", "--track", "1",
                        "--kind", "course", "--value", "127", "--sigma", "5")
        feed.until(lambda: not child.alive())
        out = (d.logdir / "support.log").read_text()
        assert child.proc.returncode == 0 and f"born at t={reborn}" in out, out
        code, out = tma_input(d, "clear", "clear", "--config", str(cfg), "--array", "a1", "--track", "1",
                              "--birth", str(birth))
        assert code == 1 and "stale_birth" in out, out
        state = json.loads((tmp_path / "state" / "tma-a1.json").read_text())
        assert state["births"] == [[1, reborn, True]]
        (e,) = state["inputs"]
        assert (e["track"], e["birth"], e["bounds"]) == (1, reborn, None)
        assert [(k, round(math.degrees(v)), round(math.degrees(sg))) for k, v, sg, *_ in e["support"]] == [
            ("course", 127, 5)]
        d.wait_for(lambda: any(m["rejected"] == {"bad_state": 1, "stale_birth": 1} for m in d.of("metrics/tma/a1")))
        feed.q.undeclare()
