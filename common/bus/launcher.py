"""Start ``pfusion`` commands as forks of a fork server that has imported them once.

A fresh interpreter spends about 1 s of CPU importing numpy, scipy, zenoh and a
service's modules before it does any work; a test run starts some 300 service
processes, the demo a dozen. multiprocessing's fork server is a separate interpreter,
started once per launching process, that imports every command once and then forks a
child per command, which starts with everything imported. The server never opens a
Zenoh session, so no child is forked from a process with one (zenoh-notes pitfall 4)."""

from __future__ import annotations

import importlib
import multiprocessing
import os
import signal
import subprocess
import sys
from functools import cache
from multiprocessing.connection import Connection
from multiprocessing.context import ForkServerContext
from pathlib import Path
from typing import IO

from common.bus.transport import hold_early_signals

ENTRY = "common.cli"  # the module of ``pfusion``'s main and COMMANDS (``python -m common`` runs it)
SUPERVISORS = ("run", "demo")  # commands that start processes of their own: never forked


@cache
def _context() -> ForkServerContext:
    """The fork server, preloading the entry point and every forked command's module
    (looked up by name, as ``python -m`` does: common/ imports no command)."""
    commands = importlib.import_module(ENTRY).COMMANDS
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload([ENTRY, *(m for name, (m, _) in commands.items()
                                         if name not in SUPERVISORS)])
    return ctx


def _run_command(args: list[str], out: str | Connection | None, env: dict[str, str], cwd: str,
                 new_session: bool) -> None:
    """The child: stdout and stderr to ``out`` (a log file's path, the write end of a
    pipe, else /dev/null), the launcher's environment and directory, its own session if
    asked, then ``pfusion ARGS``; its return is the exit code. A stop signal that comes
    before the command's own handlers is held for them (``hold_early_signals``)."""
    hold_early_signals()
    if isinstance(out, Connection):
        fd = os.dup(out.fileno())
        out.close()
    else:
        fd = os.open(out or os.devnull, os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    os.close(fd)
    sys.stdout.reconfigure(line_buffering=True, write_through=True)  # type: ignore[union-attr]
    sys.stderr.reconfigure(line_buffering=True, write_through=True)  # type: ignore[union-attr]
    os.environ.clear()
    os.environ.update(env)
    os.chdir(cwd)
    if new_session:
        os.setsid()
    sys.exit(importlib.import_module(ENTRY).main(args))


class Forked:
    """The part of ``subprocess.Popen``'s interface that ``Child`` users need, over a
    fork-server child: ``pid``, ``poll``, ``wait``, ``returncode`` (negative for a
    signal, as Popen's), ``send_signal``, ``kill``. Daemonic (hence no command of
    SUPERVISORS): one still running when its launcher exits gets SIGTERM."""

    def __init__(self, args: list[str], log: Path | None, env: dict[str, str],
                 piped: bool = False, new_session: bool = False) -> None:
        """``log``: the file of the child's stdout and stderr; ``piped``: a pipe instead,
        whose read end is ``stdout``; ``new_session``: the child's own session and
        process group (signals of the terminal reach the launcher only)."""
        self.args = args
        self.stdout: IO[bytes] | None = None
        out: str | Connection | None = str(log) if log else None
        if piped:
            read, out = _context().Pipe(duplex=False)
        self._proc = _context().Process(  # in the launcher's directory, as Popen would be
            target=_run_command, args=(args, out, env, str(Path.cwd()), new_session),
            daemon=True)
        self._proc.start()
        if piped:
            assert isinstance(out, Connection)
            out.close()
            self.stdout = os.fdopen(os.dup(read.fileno()), "rb")
            read.close()
        assert self._proc.pid is not None
        self.pid: int = self._proc.pid

    @property
    def returncode(self) -> int | None:
        return self._proc.exitcode

    def poll(self) -> int | None:
        return self._proc.exitcode

    def wait(self, timeout: float | None = None) -> int:
        self._proc.join(timeout)
        code = self._proc.exitcode
        if code is None:
            raise subprocess.TimeoutExpired(["pfusion", *self.args], timeout or 0.0)
        return code

    def send_signal(self, sig: int) -> None:
        if self._proc.exitcode is None:
            os.kill(self.pid, sig)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)
