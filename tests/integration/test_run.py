"""``pfusion run``: the plan of a deployment, the back-off, and real runs (a router of its
own on a loopback port, the services that exist, the simulator, a killed child)."""

from __future__ import annotations

import os
import re
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from common.bus import local_run
from common.bus.procs import pfusion_argv
from common.bus.transport import free_port, open_session, wait_port
from common.cli import COMMANDS
from common.deploy.config import ConfigError, ZenohConfig, load, parse
from common.deploy.deployment import Backoff, loopback_port, plan, restartable, router_endpoint, simulator_spec
from tests.harness import Terminal

REPO = Path(__file__).resolve().parents[2]
TWO_TARGETS = str(REPO / "scenarios" / "two_targets.toml")
SONAR = str(REPO / "scenarios" / "sonar_tma.toml")
ROOT = "pf/v1"
ALL = {"channel-plotter", "elementary-tracker", "global-fusion", "bearing-tracker", "tma"}


def test_plan_of_three_bases() -> None:
    specs = plan(load(TWO_TARGETS), "d.toml", ALL, ["tcp/127.0.0.1:1"])
    assert [s.name for s in specs] == [
        "channel-plotter/b1", "elementary-tracker/b1", "channel-plotter/b2",
        "elementary-tracker/b2", "channel-plotter/b3", "elementary-tracker/b3", "global-fusion"]
    assert specs[0].argv == ("channel-plotter", "--config", "d.toml",
                             "--connect", "tcp/127.0.0.1:1", "--base", "b1")
    assert specs[1].alive == "elementary_tracker/b1"
    assert specs[-1].argv == ("global-fusion", "--config", "d.toml", "--connect", "tcp/127.0.0.1:1")


def test_plan_of_an_array_and_of_one_base() -> None:
    specs = plan(load(SONAR), "s.toml", ALL)
    assert [(s.name, s.argv[-2:], s.alive) for s in specs] == [
        ("bearing-tracker/a1", ("--array", "a1"), "bearing_tracker/a1"),
        ("tma/a1", ("--array", "a1"), "tma/a1")]
    one = parse({"radar": {"base": [{"id": "b9", "tx": [1.0, 0, 0], "rx": [0, 0, 0], "channels": ["c"]}]}})
    assert [s.name for s in plan(one, "f", ALL)] == ["channel-plotter/b9", "elementary-tracker/b9"]


def test_plan_keeps_only_existing_commands() -> None:
    assert [s.name for s in plan(load(TWO_TARGETS), "f", {"elementary-tracker"})] == [
        "elementary-tracker/b1", "elementary-tracker/b2", "elementary-tracker/b3"]


def test_simulator_spec_waits_for_the_services() -> None:
    s = simulator_spec("d.toml", "s.toml", 3, 2.0, ["a/b", "c/*"], ["tcp/127.0.0.1:5"])
    argv = list(s.argv)
    assert argv[:7] == ["simulate", "--config", "d.toml", "--scenario", "s.toml", "--seed", "3"]
    assert argv[argv.index("--speed") + 1] == "2.0"
    assert [argv[i + 1] for i, a in enumerate(argv) if a == "--wait-alive"] == ["a/b", "c/*"]
    assert argv[argv.index("--connect") + 1] == "tcp/127.0.0.1:5"


def test_backoff_doubles_to_ten_seconds_and_resets_after_thirty() -> None:
    b = Backoff()
    assert [b.next_delay(1.0) for _ in range(7)] == [0.5, 1.0, 2.0, 4.0, 8.0, 10.0, 10.0]
    assert b.next_delay(29.9) == 10.0
    assert b.next_delay(30.0) == 0.5
    assert b.next_delay(0.1) == 1.0


def test_router_endpoint_choice() -> None:
    scenario = load(TWO_TARGETS)
    assert "connect" not in scenario.doc["zenoh"]
    assert router_endpoint(scenario, None) == "tcp/127.0.0.1:7447"  # where watch/status look
    assert router_endpoint(scenario, ["tcp/127.0.0.1:9"]) == "tcp/127.0.0.1:9"
    explicit = parse({"zenoh": {"connect": ["tcp/127.0.0.1:7999"]}})
    assert router_endpoint(explicit, None) == "tcp/127.0.0.1:7999"
    with pytest.raises(ConfigError, match="zenoh.connect"):
        router_endpoint(parse({"zenoh": {"connect": [], "listen": ["tcp/127.0.0.1:7998"]}}), None)
    assert loopback_port("tcp/127.0.0.1:7999") == 7999
    assert loopback_port("tcp/router:7447") is None


class Run(Terminal):
    """``pfusion run`` as a subprocess; its stderr lines are kept (and the started pids)."""

    def __init__(self, *args: str) -> None:
        super().__init__(pfusion_argv("run", *args))
        self.lines = self.err

    def pids(self, name: str) -> list[int]:
        pat = re.compile(rf"^\[run\] started {re.escape(name)} pid=(\d+)$")
        return [int(m.group(1)) for line in list(self.lines) if (m := pat.match(line))]

    def log(self) -> str:
        return "\n".join(self.lines[-60:])

    def stop(self, timeout: float = 20.0) -> int:
        return self.ctrl_c(timeout)


class Collector(local_run.Collector):
    """The shared collector on the run's router (its own session), subscribed to keys."""

    def __init__(self, endpoint: str, keys: list[str]) -> None:
        port = loopback_port(endpoint)
        assert port is not None
        wait_port(port, 30)
        super().__init__(open_session(ZenohConfig([endpoint], [], ROOT)))
        for k in keys:
            self.subscribe(k)

    def close(self) -> None:
        super().close()
        self.session.close()


def output_keys() -> list[str]:
    """Keys whose messages the existing radar services of two_targets publish."""
    keys = []
    for base in ("b1", "b2", "b3"):
        if "channel-plotter" in COMMANDS:
            keys.append(f"radar/fused/{base}")
        if "elementary-tracker" in COMMANDS:
            keys.append(f"radar/etracks/{base}")
    if "global-fusion" in COMMANDS:
        keys.append("radar/gtracks")
    return keys


def gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@pytest.mark.slow
def test_run_with_router_and_simulator_delivers_every_service_output() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    run = Run("--config", TWO_TARGETS, "--connect", endpoint, "--with-router",
              "--with-simulator", TWO_TARGETS, "--wait-alive", "test/collector",
              "--exit-after-sim", "1")
    keys = output_keys()
    col = Collector(endpoint, ["radar/**", "sim/status"])
    try:
        run.wait_for("sim/status done", lambda: col.of("sim/status"))
        last_t = col.of("sim/status")[0]["t"]
        run.wait_for("every output of the last scan",
                     lambda: all(any(m["t"] == last_t for m in col.of(k)) for k in keys))
        assert run.proc.wait(30) == 0, run.log()
    finally:
        col.close()
        run.stop()
    missing = {k: sorted(set(np.arange(120.0)) - {m["t"] for m in col.of(k)})
               for k in (*keys, "radar/plots/b2/c3")}
    assert all(len(col.of(k)) == 120 for k in missing), \
        (f"scan times missing per key: {missing}\n{run.log()}")
    names = ["router", "simulate", *(s.name for s in plan(load(TWO_TARGETS), "", COMMANDS))]
    started = [line for line in run.lines if line.startswith("[run] started ")]
    assert len(started) == len(names)
    for name in names:
        assert any(line.startswith(f"[{name}] ") for line in run.lines), name
        assert all(gone(pid) for pid in run.pids(name)), name
    assert "[run] simulator done" in run.lines and run.lines[-1] == "[run] stopped"


def test_run_restarts_a_killed_service_and_its_output_resumes() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    run = Run("--config", TWO_TARGETS, "--connect", endpoint, "--with-router",
              "--with-simulator", TWO_TARGETS, "--speed", "5", "--wait-alive", "test/collector")
    col = Collector(endpoint, ["radar/etracks/b1", "sim/status"])
    try:
        run.wait_for("etracks of b1", lambda: len(col.of("radar/etracks/b1")) >= 10)
        [pid] = run.pids("elementary-tracker/b1")
        os.kill(pid, signal.SIGKILL)
        killed_at = col.of("radar/etracks/b1")[-1]["t"]
        run.wait_for("the restart", lambda: len(run.pids("elementary-tracker/b1")) == 2)
        assert any(re.match(r"\[run\] elementary-tracker/b1 exited with code -9 after .*"
                            r"restarting in 0.5 s", line) for line in run.lines), run.log()
        run.wait_for("etracks of b1 after the restart",
                     lambda: col.of("radar/etracks/b1")[-1]["t"] >= killed_at + 5)
        assert not col.of("sim/status"), "the simulator ended before the restart was seen"
    finally:
        col.close()
        assert run.stop() == 0, run.log()
    new_pid = run.pids("elementary-tracker/b1")[1]
    assert new_pid != pid and gone(new_pid)
    assert "[run] stopped" in run.lines


def test_restartable_only_without_a_usage_error() -> None:
    assert restartable(1) and restartable(-9) and restartable(0)
    assert not restartable(2)


def test_run_does_not_restart_a_child_that_exits_with_a_configuration_error(tmp_path: Path) -> None:
    """Global fusion refuses range-Doppler bases (exit 2): run says so once and leaves it,
    instead of restarting it for ever; the other services keep running."""
    text = Path(TWO_TARGETS).read_text().replace("p = 1\n", "p = 1\nazimuth = false\n")
    cfg = tmp_path / "range_doppler.toml"
    cfg.write_text(text)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    run = Run("--config", str(cfg), "--connect", endpoint, "--with-router")
    try:
        run.wait_for("global fusion's exit", lambda: any("global-fusion exited with code 2" in line
                                                         for line in run.lines))
        time.sleep(3.0)  # six first back-off delays (0.5 s): a restart would have started
        assert len(run.pids("global-fusion")) == 1, run.log()
        assert any(re.match(r"\[run\] global-fusion exited with code 2 \(a configuration or usage "
                            r"error.*not restarted", line) for line in run.lines), run.log()
        assert all(len(run.pids(f"elementary-tracker/{b}")) == 1 for b in ("b1", "b2", "b3"))
    finally:
        assert run.stop() == 0, run.log()
