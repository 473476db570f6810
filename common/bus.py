"""Zenoh plumbing: sessions with explicit endpoints and no multicast scouting, and an
inbox that Zenoh callbacks only append to (see ../shared/zenoh-notes.md, pitfalls 1-3).
"""

from __future__ import annotations

import json
import queue
import signal
import socket
import threading
import time
from dataclasses import dataclass
from typing import Any

import zenoh

from common.config import ZenohConfig


def zenoh_config(
    connect: list[str], listen: list[str], mode: str = "client", lease_ms: int = 2000
) -> zenoh.Config:
    """A Zenoh config: multicast scouting off, explicit endpoints, short lease."""
    c = zenoh.Config()
    c.insert_json5("mode", json.dumps(mode))
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("connect/endpoints", json.dumps(connect))
    c.insert_json5("listen/endpoints", json.dumps(listen))
    c.insert_json5("transport/link/tx/lease", str(lease_ms))
    if mode == "client":
        c.insert_json5("connect/timeout_ms", "-1" if not connect else "10000")
    return c


def open_session(zc: ZenohConfig, mode: str = "client") -> zenoh.Session:
    """Open a session from a deployment's [zenoh] table (raises zenoh.ZError)."""
    return zenoh.open(zenoh_config(zc.connect, zc.listen, mode))


def stop_on_signals() -> threading.Event:
    """An event set by SIGINT or SIGTERM: the clean-exit flag of a tool's main loop."""
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    return stop


def free_port() -> int:
    """A currently free TCP port on 127.0.0.1."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_port(port: int, timeout: float = 10.0) -> None:
    """Block until something listens on 127.0.0.1:port (a router that just started)."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.2):
                return
        except OSError:
            if time.monotonic() > deadline:
                raise TimeoutError(f"nothing listens on 127.0.0.1:{port}") from None
            time.sleep(0.05)


def wait_alive(session: zenoh.Session, root: str, names: list[str], timeout: float,
               stop: threading.Event | None = None) -> None:
    """Block until every root/alive/<name> liveliness token is present (or ``stop``)."""
    stop = stop or threading.Event()
    deadline = time.monotonic() + timeout
    missing = set(names)
    while missing and not stop.is_set():
        for name in list(missing):
            if any(r.ok for r in session.liveliness().get(f"{root}/alive/{name}", timeout=1.0)):
                missing.discard(name)
        if missing and time.monotonic() > deadline:
            raise TimeoutError(f"services not alive after {timeout} s: {sorted(missing)}")
        if missing:
            stop.wait(0.1)
    stop.wait(0.3)  # let subscriber declarations reach every router on the path


@dataclass(frozen=True)
class Envelope:
    """One received item: a sample (key, payload) or a query to answer."""

    key: str
    payload: bytes
    query: Any = None


class Inbox:
    """Unbounded queue fed by Zenoh callbacks and drained by the service loop.

    The callbacks copy the payload and return at once: no Zenoh call, no blocking, so a
    slow service never stalls the session's receive thread. ``depth`` is monitored.
    """

    def __init__(self) -> None:
        self._q: queue.SimpleQueue[Envelope] = queue.SimpleQueue()

    def on_sample(self, sample: zenoh.Sample) -> None:
        self._q.put(Envelope(str(sample.key_expr), sample.payload.to_bytes()))

    def on_query(self, query: zenoh.Query) -> None:
        self._q.put(Envelope(str(query.key_expr), b"", query))

    def get(self, timeout: float) -> Envelope | None:
        try:
            return self._q.get(timeout=timeout)
        except queue.Empty:
            return None

    @property
    def depth(self) -> int:
        return self._q.qsize()


def flush(session: zenoh.Session, root: str, timeout: float = 5.0) -> None:
    """Round trip to the router before a publishing tool closes its session: a liveliness
    query leaves on the same link after every sample already put, so its answer means the
    router has them all (closing at once lost the tail of a fast replay under load:
    398 of 481 records)."""
    for _ in session.liveliness().get(f"{root}/alive/**", timeout=timeout):
        pass
