"""The fork-server launch of pfusion commands (common.bus.launcher) behaves as a fresh
process would: exit code, working directory, environment, output in the log, signals."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from common.bus.launcher import Forked
from common.bus.procs import Child
from common.bus.transport import free_port

REPO = Path(__file__).resolve().parents[2]


def test_exit_code_output_and_relative_path_in_the_launchers_directory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A relative --config resolves against the launcher's directory at launch (not the
    fork server's), and the command's stdout and stderr both reach the log."""
    monkeypatch.chdir(REPO)
    good = Forked(["params", "--check", "scenarios/two_targets.toml"], tmp_path / "good.log",
                  dict(os.environ))
    assert good.wait(60) == 0
    assert "scenarios/two_targets.toml: valid" in (tmp_path / "good.log").read_text()
    (tmp_path / "bad.toml").write_text("x = [\n")
    monkeypatch.chdir(tmp_path)
    bad = Forked(["params", "--check", "bad.toml"], tmp_path / "bad.log", dict(os.environ))
    assert bad.wait(60) == 2
    assert "bad.toml is not valid TOML" in (tmp_path / "bad.log").read_text()


def test_environment_is_the_launchers_at_launch(tmp_path: Path) -> None:
    """RUST_LOG given to the child reaches Zenoh in it: a client whose router is not there
    has Zenoh's own warning in its log, without colour codes (NO_COLOR)."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    lost = Forked(["status", "--config", str(REPO / "scenarios/two_targets.toml"),
                   "--connect", endpoint], tmp_path / "status.log",
                  {**os.environ, "RUST_LOG": "warn", "NO_COLOR": "1"})
    assert lost.wait(60) == 2
    log = (tmp_path / "status.log").read_text()
    assert "WARN" in log and f"Unable to connect to any of [Single({endpoint})]" in log
    assert "\x1b[" not in log


def test_signals_and_timeouts_as_popen(tmp_path: Path) -> None:
    """SIGTERM stops a service cleanly (code 0, its stop line logged), SIGKILL gives
    -9, and wait() with a short timeout raises TimeoutExpired while it runs."""
    router = Child("router", "router", "--listen", "tcp/127.0.0.1:0", log=tmp_path / "r.log")
    assert isinstance(router.proc, Forked)
    with pytest.raises(subprocess.TimeoutExpired):
        router.proc.wait(0.5)
    assert router.stop(10) == 0
    assert "router stopped" in (tmp_path / "r.log").read_text()
    other = Forked(["router", "--listen", "tcp/127.0.0.1:0"], None, dict(os.environ))
    other.send_signal(signal.SIGKILL)
    assert other.wait(30) == -signal.SIGKILL


def test_piped_output_ends_at_exit_and_new_session(tmp_path: Path) -> None:
    """As ``pfusion run`` starts its children: the output pipe reaches EOF when the child
    exits (no copy of its write end left open elsewhere), and the child leads its own
    session, so that a terminal's Ctrl-C does not reach it."""
    router = Forked(["router", "--listen", "tcp/127.0.0.1:0"], None, dict(os.environ),
                    piped=True, new_session=True)
    assert router.stdout is not None
    assert b"router listening" in router.stdout.readline()
    assert os.getsid(router.pid) == router.pid != os.getsid(0)
    router.send_signal(signal.SIGTERM)
    assert b"router stopped" in router.stdout.read()
    assert router.wait(30) == 0


def test_a_stop_before_the_handlers_is_held_for_them(tmp_path: Path) -> None:
    """SIGTERM sent as soon as the forked command exists (while it still opens its
    session) stops it cleanly: code 0 and its stop line, not -15."""
    log = tmp_path / "r.log"
    router = Forked(["router", "--listen", "tcp/127.0.0.1:0"], log, dict(os.environ))
    deadline = time.monotonic() + 30
    while not log.exists() and time.monotonic() < deadline:  # the child opens it after the hold
        time.sleep(0.001)
    router.send_signal(signal.SIGTERM)
    assert router.wait(30) == 0
    assert "router stopped" in log.read_text()
