"""Child processes for the demo and the integration tests: a ``pfusion`` command is a
fork of the fork server (common.bus.launcher) unless its stdout is wanted; any other
program, or a command whose stdout is read, is a fresh process (subprocess)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import IO

from common.bus.launcher import SUPERVISORS, Forked
from common.bus.transport import free_port, wait_port

# Zenoh's own warnings and errors (a link closed, a lease expired) in each child's log,
# without colour codes, unless the environment says otherwise
ZENOH_LOG = {"RUST_LOG": "warn", "NO_COLOR": "1"}


def child_env() -> dict[str, str]:
    """A child's environment: this one, unbuffered Python output, Zenoh's log."""
    return {**ZENOH_LOG, **os.environ, "PYTHONUNBUFFERED": "1"}


def pfusion_argv(*args: str) -> list[str]:
    """argv that runs ``pfusion ARGS`` with this interpreter."""
    return [sys.executable, "-m", "common", *args]


class Child:
    """A ``pfusion`` subcommand in its own process; its output goes to ``log`` if given
    (stdout too, unless ``stdout`` is given: Zenoh's own log, under RUST_LOG, is there)."""

    def __init__(self, name: str, *args: str, log: Path | None = None,
                 stdout: int | IO[bytes] | None = None) -> None:
        if stdout is not None or args[0] in SUPERVISORS:
            self._spawn(name, pfusion_argv(*args), log, stdout)
            return
        self.name, self.argv, self._log = name, pfusion_argv(*args), None
        self.proc: subprocess.Popen[bytes] | Forked = Forked(list(args), log, child_env())

    def _spawn(self, name: str, argv: list[str], log: Path | None,
               stdout: int | IO[bytes] | None, cwd: Path | None = None) -> None:
        """Start ``argv`` (unbuffered Python output; stdout to ``stdout``, else the log)."""
        self.name = name
        self.argv = argv
        self._log: IO[bytes] | None = open(log, "ab") if log else None
        self.proc = subprocess.Popen(
            self.argv, stdout=stdout if stdout is not None else self._log or subprocess.DEVNULL,
            stderr=self._log if self._log else subprocess.DEVNULL, cwd=cwd,
            env=child_env(),
        )

    def wait(self, timeout: float) -> int:
        return self.proc.wait(timeout)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def dump_stacks(self) -> None:
        """Have a hung child write every thread's Python stack to its log (SIGUSR1:
        ``faulthandler``, registered by common.cli.main)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGUSR1)
            time.sleep(0.5)

    def stop(self, timeout: float = 5.0) -> int:
        """SIGTERM, then (stacks to the log and) SIGKILL after ``timeout``; returns the
        exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.dump_stacks()
                self.proc.kill()
                self.proc.wait()
        if self._log:
            self._log.close()
        return int(self.proc.returncode)


def start_router(log: Path | None = None, port: int | None = None) -> tuple[Child, str]:
    """A ``pfusion router`` on a free loopback port; returns it and its endpoint."""
    port = port or free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    child = Child("router", "router", "--listen", endpoint, log=log)
    wait_port(port)
    return child, endpoint
