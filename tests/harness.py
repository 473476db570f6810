"""The repository's paths for tests, the multi-process harness they use
(common.bus.local_run: a real router and real services on loopback ports), and a
command run as a user would in a terminal (``Terminal``)."""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

from common.bus.local_run import ROOT, Deployment

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = REPO / "scenarios"

TIMEOUT_S = 120.0

__all__ = ["REPO", "ROOT", "SCENARIOS", "TIMEOUT_S", "Deployment", "Terminal", "patient_scene"]


def patient_scene(tmp_path: Path, name: str) -> Path:
    """A copy of scenarios/<name>.toml whose global fusion waits up to 120 s of wall time
    for a base ([radar.fusion] max_wait) instead of 3 s: a base lagging on a loaded
    machine is never fused without, so no timing changes the result."""
    scene = tmp_path / f"{name}.toml"
    scene.write_text((SCENARIOS / scene.name).read_text() + "\n[radar.fusion]\nmax_wait = 120.0\n")
    return scene


class Terminal:
    """One command in its own process; stdout and stderr lines kept as they come."""

    def __init__(self, argv: list[str]) -> None:
        self.proc = subprocess.Popen(argv, cwd=REPO, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.out: list[str] = []
        self.err: list[str] = []
        assert self.proc.stdout is not None and self.proc.stderr is not None
        self._readers = [threading.Thread(target=self._read, args=(s, lines), daemon=True)
                         for s, lines in ((self.proc.stdout, self.out), (self.proc.stderr, self.err))]
        for r in self._readers:
            r.start()

    @staticmethod
    def _read(stream: IO[bytes], lines: list[str]) -> None:
        for raw in stream:
            lines.append(raw.decode(errors="replace").rstrip("\n"))

    def wait_for(self, what: str, predicate: Callable[[], bool], timeout: float = TIMEOUT_S) -> None:
        deadline = time.monotonic() + timeout
        while not predicate():
            assert time.monotonic() < deadline, f"timed out waiting for {what}\n{self.log()}"
            assert self.proc.poll() is None, f"exited with {self.proc.returncode}\n{self.log()}"
            time.sleep(0.1)

    def ctrl_c(self, timeout: float = 30.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise
        for r in self._readers:
            r.join(5)
        return code

    def log(self) -> str:
        return "\n".join([*self.out[-20:], *self.err[-40:]])

