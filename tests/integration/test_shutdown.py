"""SIGINT / SIGTERM: every service and the router exit cleanly (code 0) within 2 s, and a
service's liveliness token disappears with it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from common.bus.transport import SignalBytes
from tests.harness import REPO, ROOT, SCENARIOS, Deployment

RADAR = str(SCENARIOS / "two_targets.toml")
SONAR = str(SCENARIOS / "sonar_tma.toml")
SERVICES = [
    ("channel_plotter/b1", ("channel-plotter", "--config", RADAR, "--base", "b1")),
    ("elementary_tracker/b1", ("elementary-tracker", "--config", RADAR, "--base", "b1")),
    ("global_fusion/*", ("global-fusion", "--config", RADAR)),
    ("bearing_tracker/a1", ("bearing-tracker", "--config", SONAR, "--array", "a1")),
    ("tma/a1", ("tma", "--config", SONAR, "--array", "a1")),
]


def signal_state(pid: int) -> str:
    """The kernel's signal masks of a process and of each of its threads (pending,
    blocked, ignored, caught: /proc/PID/task/TID/status), to tell on a hung shutdown
    whether the signal was blocked, ignored or caught by a handler that did not act."""
    lines = []
    for task in sorted(Path(f"/proc/{pid}/task").glob("*")):
        try:
            status = (task / "status").read_text().splitlines()
        except OSError:
            continue
        keep = [ln for ln in status if ln.split(":")[0] in
                ("Name", "SigPnd", "ShdPnd", "SigBlk", "SigIgn", "SigCgt")]
        lines.append(f"task {task.name}: " + "; ".join(ln.replace("\t", " ") for ln in keep))
    return "\n".join(lines)


def alive(d: Deployment, name: str) -> bool:
    return any(r.ok for r in d.session.liveliness().get(f"{ROOT}/alive/{name}", timeout=1.0))


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_services_exit_cleanly_within_2_s(tmp_path: Path, sig: signal.Signals) -> None:
    with Deployment(tmp_path) as d:
        children = [(name, d.start(args[0], *args)) for name, args in SERVICES]
        d.wait_alive([name for name, _ in SERVICES])
        for name, child in children:
            t0 = time.monotonic()
            child.proc.send_signal(sig)
            try:
                code = child.proc.wait(5)
            except subprocess.TimeoutExpired:
                print(f"{name} ignored {sig.name}; signal masks:\n{signal_state(child.proc.pid)}")
                child.dump_stacks()  # into its log, which the Deployment prints on failure
                raise
            took = time.monotonic() - t0
            assert code == 0, f"{name} exited with {code}"
            assert took < 2.0, f"{name} took {took:.2f} s to exit"
            assert not alive(d, name), f"{name} still has a liveliness token"
        t0 = time.monotonic()
        d.router.proc.send_signal(sig)
        assert d.router.proc.wait(5) == 0 and time.monotonic() - t0 < 2.0


def test_sigusr1_writes_every_threads_stack_to_the_log_and_the_service_runs_on(tmp_path: Path) -> None:
    with Deployment(tmp_path) as d:
        child = d.start("elementary-tracker", *SERVICES[1][1])
        d.wait_alive([SERVICES[1][0]])
        child.dump_stacks()
        log = (tmp_path / "elementary-tracker.log").read_text()
        assert "Current thread" in log and "common/bus/service.py" in log, log
        assert child.alive() and child.stop() == 0


def test_signal_bytes_see_a_shutdown_signal_whatever_its_python_handler_does() -> None:
    """The service loop's fallback (common.bus.transport.SignalBytes): SIGTERM is seen
    even when the Python handler does nothing; another signal is not a shutdown."""
    old = {s: signal.signal(s, lambda *_: None) for s in (signal.SIGTERM, signal.SIGUSR2)}
    signals = SignalBytes()
    try:
        assert not signals.received()
        os.kill(os.getpid(), signal.SIGUSR2)
        assert not signals.received()
        os.kill(os.getpid(), signal.SIGTERM)
        assert signals.received()
        assert not signals.received()
    finally:
        signals.close()
        for s, h in old.items():
            signal.signal(s, h)


INTERRUPTED_WAIT = """
import signal, time
from common.bus.transport import Inbox
signal.signal(signal.SIGALRM, lambda *_: time.sleep(0.15))  # ends after get's deadline
signal.setitimer(signal.ITIMER_REAL, 0.05)
t0 = time.monotonic()
assert Inbox().get(timeout=0.1) is None
print(round(time.monotonic() - t0, 2))
"""


def test_an_inbox_wait_ends_when_a_signal_handler_outlasts_its_timeout() -> None:
    """The service loop's wait (common.bus.transport.Inbox.get): a signal whose handler
    ends after the wait's deadline does not turn it into a wait for ever (CPython 3.11's
    SimpleQueue.get did: the cause of services that ignored SIGINT / SIGTERM here)."""
    done = subprocess.run([sys.executable, "-c", INTERRUPTED_WAIT], cwd=REPO, capture_output=True,
                          text=True, timeout=10)
    assert done.returncode == 0, done.stderr
    assert float(done.stdout) < 1.0
