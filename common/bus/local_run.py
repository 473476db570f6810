"""A local run of the real processes, for tests and benchmarks: a real ``pfusion router``
on a free loopback port, real services as child processes, and an in-process collector
of decoded messages (``Collector``, also used alone on a run's router; tests/harness.py
re-exports the Deployment with the repository's paths)."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Any

from common.bus.procs import Child, start_router
from common.bus.transport import Inbox, LossCount, open_session
from common.deploy.config import ZenohConfig, load
from common.deploy.deployment import plan
from common.wire import protocol
from common.wire.protocol import kind_of

ROOT = "pf/v1"


class Collector:
    """Decoded messages of key expressions under the root on a session, in ``messages``
    and per key in ``by_key``, with the liveliness token ``<root>/alive/<name>`` that a
    simulator may wait for; raises on invalid data, counts lost samples in ``losses``."""

    def __init__(self, session: Any, name: str = "test/collector") -> None:
        self.session, self.name = session, name
        self.inbox = Inbox()
        self.messages: list[tuple[str, dict[str, Any]]] = []
        self.by_key: dict[str, list[dict[str, Any]]] = {}
        self.losses = LossCount(logging.getLogger("collector"))
        self._subs: list[Any] = []
        self._token: Any = None

    @property
    def announced(self) -> bool:
        return self._token is not None

    def subscribe(self, keyexpr: str) -> None:
        """Subscribe to root/keyexpr (before the data starts)."""
        self._subs.append(self.session.declare_subscriber(f"{ROOT}/{keyexpr}", self.inbox.on_sample))
        self.announce()

    def announce(self) -> None:
        """(Re)declare the liveliness token after the latest subscription, so a simulator
        that waits for it never publishes before the collector listens."""
        if self._token is not None:
            self._token.undeclare()
        self._token = self.session.liveliness().declare_token(f"{ROOT}/alive/{self.name}")

    def drain(self) -> None:
        """Decode everything received so far into ``messages`` and ``by_key`` and count
        the samples that never arrived in ``losses`` (raises on invalid data)."""
        while (env := self.inbox.get(0.0)) is not None:
            self.losses.check(env.key, env.attachment)
            kind = kind_of(env.key, ROOT)
            msg = protocol.decode(kind, env.payload) if kind else protocol.unpack(env.payload)
            self.messages.append((env.key, msg))
            self.by_key.setdefault(env.key, []).append(msg)

    def of(self, suffix: str) -> list[dict[str, Any]]:
        """The messages of root/suffix received so far, in arrival order (a copy of the
        per-key list: polled by wait predicates, it does not rescan every message)."""
        self.drain()
        return list(self.by_key.get(f"{ROOT}/{suffix}", ()))

    def close(self) -> None:
        """Undeclare the subscribers and the token (the session stays open)."""
        for s in self._subs:
            s.undeclare()
        if self._token is not None:
            self._token.undeclare()
        self._subs, self._token = [], None


class Deployment:
    """Router + children + collector; stops everything on exit and prints child logs
    of a failed test (pytest shows them)."""

    def __init__(self, logdir: Path) -> None:
        self.logdir = logdir
        self.router, self.endpoint = start_router(log=logdir / "router.log")
        self.children: list[Child] = []
        self.session = open_session(ZenohConfig([self.endpoint], [], ROOT))
        self.collector = Collector(self.session)

    def __enter__(self) -> "Deployment":
        return self

    def __exit__(self, exc_type: type | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        for c in reversed(self.children):
            c.stop()
        self.collector.close()
        self.session.close()
        self.router.stop()
        if exc is not None:
            for log in sorted(self.logdir.glob("*.log")):
                print(f"==== {log.name} (last 40 lines) ====")
                print("\n".join(log.read_text(errors="replace").splitlines()[-40:]))

    def start(self, name: str, *args: str) -> Child:
        """Start ``pfusion ARGS --connect <router>``; stderr goes to <logdir>/<name>.log."""
        child = Child(name, *args, "--connect", self.endpoint, log=self.logdir / f"{name}.log")
        self.children.append(child)
        return child

    def start_services(self, config: Path, commands: tuple[str, ...]) -> list[str]:
        """Start the services of ``config`` that run ``commands`` (common.deploy.deployment.plan);
        returns their liveliness names, for ``wait_alive`` and ``simulate``."""
        specs = plan(load(config), str(config), commands)
        for spec in specs:
            self.start(spec.name.replace("/", "-"), *spec.argv)
        return [spec.alive for spec in specs]

    @property
    def messages(self) -> list[tuple[str, dict[str, Any]]]:
        return self.collector.messages

    @property
    def by_key(self) -> dict[str, list[dict[str, Any]]]:
        return self.collector.by_key

    @property
    def losses(self) -> LossCount:
        return self.collector.losses

    def collect(self, keyexpr: str) -> None:
        """Subscribe the collector to root/keyexpr (before the data starts)."""
        self.collector.subscribe(keyexpr)

    def announce(self) -> None:
        """(Re)declare the collector's liveliness token ``test/collector``."""
        self.collector.announce()

    def wait_alive(self, names: list[str], timeout: float = 60.0) -> None:
        """Block until every root/alive/<name> token exists (a service is subscribed)."""
        deadline = time.monotonic() + timeout
        for name in names:
            while not any(r.ok for r in self.session.liveliness().get(f"{ROOT}/alive/{name}", timeout=1.0)):
                if time.monotonic() > deadline:
                    raise TimeoutError(f"{name} not alive; see logs in {self.logdir}")
                for c in self.children:
                    if not c.alive():
                        raise RuntimeError(f"{c.name} exited with {c.proc.returncode}")
                time.sleep(0.1)

    def simulate(self, scenario: Path, seed: int = 1, scans: int | None = None,
                 wait_alive: list[str] = (), timeout: float = 300.0, repeat: int = 1,
                 gap: float = 0.0, speed: float = 0.0) -> Child:
        """Run the simulator to completion (waiting for ``wait_alive`` services first);
        `repeat` runs with seeds seed, seed + 1, ... separated by `gap` target-free
        seconds (``pfusion simulate --repeat --gap``); `speed` times real time (0: as
        fast as possible)."""
        if not self.collector.announced:
            self.announce()
        args = ["simulate", "--config", str(scenario), "--scenario", str(scenario),
                "--seed", str(seed), "--wait-alive", "test/collector"]
        for name in wait_alive:
            args += ["--wait-alive", name]
        if scans is not None:
            args += ["--scans", str(scans)]
        if repeat > 1:
            args += ["--repeat", str(repeat), "--gap", str(gap)]
        if speed > 0:
            args += ["--speed", repr(speed)]
        sim = self.start("simulate", *args)
        deadline = time.monotonic() + timeout
        while sim.alive():
            self.drain()
            if time.monotonic() > deadline:
                raise TimeoutError("simulator did not finish")
            time.sleep(0.05)
        assert sim.proc.returncode == 0, f"simulator exited with {sim.proc.returncode}"
        return sim

    def drain(self) -> None:
        """``Collector.drain`` of the deployment's collector."""
        self.collector.drain()

    def wait_for(self, predicate: Callable[[], bool], timeout: float = 60.0) -> None:
        """Drain until ``predicate()`` holds (e.g. the last scan's tracks arrived)."""
        deadline = time.monotonic() + timeout
        while True:
            self.drain()
            if predicate():
                return
            if time.monotonic() > deadline:
                raise TimeoutError("condition not met; see logs in " + str(self.logdir))
            time.sleep(0.05)

    def of(self, key_suffix: str) -> list[dict[str, Any]]:
        """``Collector.of`` of the deployment's collector."""
        return self.collector.of(key_suffix)
