"""``pfusion run``: start every service of a deployment as child processes, prefix their
log lines with their names, restart crashed ones with back-off, stop them all cleanly.

Children are forks of the fork server (common.bus.launcher: a restarted service is up
without importing anything again), each in its own session (Ctrl-C reaches only
``run``, which then stops the simulator and the services first and the router last).

``--with-router`` listens where the other commands given the same file look for their
router (``router_endpoint``: the first --connect, else ``[zenoh] connect``, by default
``tcp/127.0.0.1:7447``) and fails with one line and code 2 when it cannot listen there.
Without it, ``run`` first checks that a router answers (else one line, code 2).

Under [zenoh.auth] ``run`` itself logs in as ``viewer`` (its router check and the
metrics of ``--exit-after-sim``), or as ``--identity``: on a site host, the site's
identity (``site-<site>``), so that the host needs no password of a read role; each
child logs in with its own identity (docs/security.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterable
from typing import IO

from common.bus.launcher import Forked
from common.bus.liveliness import Drain
from common.bus.procs import child_env
from common.bus.transport import open_session, stop_on_signals
from common.cli import COMMANDS, add_common, load_config
from common.deploy.config import ZenohConfig
from common.deploy.deployment import (
    Backoff,
    ChildSpec,
    loopback_port,
    plan,
    restartable,
    router_endpoint,
    simulator_spec,
)

STOP_TIMEOUT_S = 5.0
POLL_S = 0.1
LISTEN_TIMEOUT_S = 30.0
DRAIN_TIMEOUT_S = 120.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--with-router", action="store_true",
                   help="also run a router, listening on the first --connect endpoint, else "
                        "on [zenoh] connect (default tcp/127.0.0.1:7447)")
    p.add_argument("--with-simulator", metavar="SCENARIO",
                   help="run this scenario once every service is alive")
    p.add_argument("--seed", type=int, default=1, help="simulator seed")
    p.add_argument("--speed", type=float, default=0.0,
                   help="simulator speed, times real time (0: as fast as possible)")
    p.add_argument("--wait-alive", action="append", default=[], metavar="SERVICE/INSTANCE",
                   help="the simulator also waits for this liveliness token (repeatable)")
    p.add_argument("--exit-after-sim", type=float, default=None, metavar="SECONDS",
                   help="stop everything this long after the simulator is done and every "
                        "service has drained its input (its metrics: two reports in a row "
                        f"with nothing new), or {DRAIN_TIMEOUT_S:.0f} s after the simulator "
                        "if they never drain")


class Log:
    """Our stderr, shared by the children's log pumps: one whole line per write."""

    def __init__(self, stream: IO[str]) -> None:
        self._stream = stream
        self._lock = threading.Lock()

    def line(self, name: str, text: str) -> None:
        with self._lock:
            self._stream.write(f"[{name}] {text}\n")
            self._stream.flush()


class Supervised:
    """One child process; restarted with back-off when ``restart`` and it exits."""

    def __init__(self, spec: ChildSpec, log: Log, restart: bool = True) -> None:
        self.spec, self.log, self.restart = spec, log, restart
        self.backoff = Backoff()
        self.proc: Forked | None = None
        self.started_at = 0.0
        self.restart_at: float | None = None
        self.returncode: int | None = None

    def start(self) -> None:
        self.proc = Forked(list(self.spec.argv), None, child_env(), piped=True, new_session=True)
        self.started_at = time.monotonic()
        self.restart_at = None
        self.returncode = None
        assert self.proc.stdout is not None
        threading.Thread(target=self._pump, args=(self.proc.stdout,), daemon=True).start()
        self.log.line("run", f"started {self.spec.name} pid={self.proc.pid}")

    def _pump(self, stream: IO[bytes]) -> None:
        for raw in stream:
            self.log.line(self.spec.name, raw.decode(errors="replace").rstrip("\r\n"))
        stream.close()

    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def tick(self, now: float) -> None:
        """Notice an exit and schedule (or perform) the restart."""
        if self.proc is None:
            return
        if self.restart_at is not None:
            if now >= self.restart_at:
                self.start()
            return
        if self.returncode is not None or self.proc.poll() is None:
            return
        self.returncode = self.proc.returncode
        ran = now - self.started_at
        if not self.restart:
            self.log.line("run", f"{self.spec.name} exited with code {self.returncode}")
            return
        if not restartable(self.returncode):
            self.log.line("run", f"{self.spec.name} exited with code {self.returncode} (a configuration "
                                 "or usage error: see its log lines above); not restarted")
            return
        delay = self.backoff.next_delay(ran)
        self.restart_at = now + delay
        self.log.line("run", f"{self.spec.name} exited with code {self.returncode} after "
                             f"{ran:.1f} s; restarting in {delay:.1f} s")


def stop_all(children: Iterable[Supervised], log: Log) -> None:
    """SIGTERM to every running child, SIGKILL to those still running after 5 s."""
    live = [c for c in children if c.running()]
    for c in live:
        assert c.proc is not None
        c.proc.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + STOP_TIMEOUT_S
    for c in live:
        assert c.proc is not None
        try:
            c.proc.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            log.line("run", f"{c.spec.name} did not stop within {STOP_TIMEOUT_S} s: killed")
            c.proc.kill()
            c.proc.wait()


def listen_error(endpoint: str) -> str | None:
    """Why a router could not listen on ``tcp/HOST:PORT`` of this machine (e.g. "Address
    already in use"), or None; None too for an endpoint this check cannot bind."""
    proto, _, addr = endpoint.partition("/")
    host, _, port = addr.rpartition(":")
    if proto != "tcp" or not port.isdigit():
        return None
    try:
        family, kind, _, _, address = socket.getaddrinfo(host.strip("[]"), int(port),
                                                         type=socket.SOCK_STREAM)[0]
    except socket.gaierror:
        return None
    with socket.socket(family, kind) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as Zenoh's listener does
        try:
            s.bind(address)
        except OSError as e:
            return e.strerror
    return None


def wait_listening(router: Supervised, endpoint: str) -> bool:
    """Until the router accepts connections on a loopback endpoint (at once for another
    endpoint): True, or False if it exited first."""
    port = loopback_port(endpoint)
    deadline = time.monotonic() + LISTEN_TIMEOUT_S
    while port is not None and router.running() and time.monotonic() < deadline:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.2):
                return True
        except OSError:
            time.sleep(0.05)
    return router.running()


def start_router(endpoint: str, where: str, config: str, log: Log) -> Supervised | None:
    """The router of ``--with-router``, listening on ``endpoint`` (taken from ``where``)
    with the deployment's security if any; None (after one line on stderr) when it
    cannot listen."""
    why = listen_error(endpoint)
    if why is not None:
        print(f"pfusion run: cannot listen on {endpoint} ({where}): {why}; if a router "
              "already runs there, drop --with-router, else free the port or choose "
              "another with --connect", file=sys.stderr)
        return None
    router = Supervised(ChildSpec("router", ("router", "--listen", endpoint, "--config", config), ""),
                        log)
    router.start()
    if not wait_listening(router, endpoint):
        stop_all([router], log)
        print(f"pfusion run: the router could not listen on {endpoint} ({where}); "
              "its log lines are above", file=sys.stderr)
        return None
    log.line("run", f"router listening on {endpoint} ({where})")
    return router


def check_reachable(zc: ZenohConfig) -> None:
    """Open and close a session, so that an unreachable router ends ``run`` at once
    (RouterUnreachable) instead of every child failing and being restarted."""
    if zc.connect:
        open_session(dataclasses.replace(zc, listen=[])).close()


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    log = Log(sys.stderr)
    stop = stop_on_signals()
    connect: list[str] = list(args.connect or [])
    router: Supervised | None = None
    if args.with_router:
        endpoint = router_endpoint(cfg, args.connect)
        where = "--connect" if args.connect else f"[zenoh] connect of {args.config}"
        router = start_router(endpoint, where, args.config, log)
        if router is None:
            return 2
        connect = [endpoint]
    else:
        check_reachable(cfg.zenoh)
    services = [Supervised(s, log) for s in plan(cfg, args.config, COMMANDS, connect)]
    if not services:
        log.line("run", "the configuration describes no service whose command exists")
    for s in services:
        s.start()
    sim: Supervised | None = None
    if args.with_simulator:
        names = [s.spec.alive for s in services] + list(args.wait_alive)
        sim = Supervised(simulator_spec(args.config, args.with_simulator, args.seed, args.speed,
                                        names, connect), log, restart=False)
        sim.start()
    drain: Drain | None = None
    if sim is not None and args.exit_after_sim is not None:
        drain = Drain(dataclasses.replace(cfg.zenoh, connect=connect or cfg.zenoh.connect),
                      [s.spec.alive for s in services])
    try:
        code = supervise([*([router] if router else []), *services], sim, args.exit_after_sim,
                         stop, log, drain)
    finally:
        if drain is not None:
            drain.close()
    stop_all([*([sim] if sim else []), *services], log)
    if router is not None:
        stop_all([router], log)
    log.line("run", "stopped")
    return code


def supervise(children: list[Supervised], sim: Supervised | None, exit_after_sim: float | None,
              stop: threading.Event, log: Log, drain: Drain | None = None) -> int:
    """Restart crashed children until ``stop`` (or ``exit_after_sim`` seconds after the
    simulator ended and ``drain`` says the services have worked through their input);
    returns 1 if the simulator failed, else 0."""
    sim_done_at: float | None = None
    drained_at: float | None = None
    code = 0
    while not stop.wait(POLL_S):
        now = time.monotonic()
        for c in children:
            c.tick(now)
        if sim is not None and sim_done_at is None:
            sim.tick(now)
            if sim.returncode is not None:
                sim_done_at = now
                code = 0 if sim.returncode == 0 else 1
                log.line("run", "simulator done" if code == 0 else "simulator failed")
                if drain is not None:
                    drain.mark()
        if exit_after_sim is None or sim_done_at is None:
            continue
        if drained_at is None:
            if drain is None or drain.drained():
                drained_at = now
                log.line("run", "services drained")
            elif now - sim_done_at >= DRAIN_TIMEOUT_S:
                drained_at = now
                log.line("run", f"services not drained {DRAIN_TIMEOUT_S:.0f} s after the "
                                "simulator: stopping anyway")
        if drained_at is not None and now - drained_at >= exit_after_sim:
            break
    return code
