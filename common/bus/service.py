"""The thin shell every service runs in: subscribe, decode and validate, call the core,
encode, publish; plus liveliness, counters, metrics and clean shutdown.

A service registers handlers ``handler(key, payload)`` and lets :meth:`Service.run`
drain its :class:`~common.bus.transport.Inbox` on the main thread. A handler raises
:class:`~common.wire.protocol.DecodeError` (or :class:`Rejected`) for bad input: the runtime
logs the reason (first time per reason, then every 1000th), counts it and goes on.
Samples that never arrived are counted per key from the publishers' stamps
(``common.core.sequence``) and logged the same way.

Every service answers queries on ``<root>/control/<service>/<instance>`` with its
counters and ``fresh`` (nothing processed yet): ``pfusion replay`` learns there which
services are ahead of a recording. A query with the parameter ``reset`` restarts the
service with a fresh state: :meth:`Service.run` replies, stops without flushing
(``at_end`` is not called) and returns :data:`common.bus.RESTART`, on which ``common.cli`` runs
the command's ``main`` again in the same process (new cores, new session, new token).
"""

from __future__ import annotations

import logging
import signal
import threading
import time
from collections import Counter, deque
from collections.abc import Callable
from typing import Any

import numpy as np
import zenoh

from common.bus import RESTART
from common.bus.transport import (
    CLOSE_LINGER_S,
    LOG_EVERY,
    Envelope,
    Inbox,
    LossCount,
    Publisher,
    SignalBytes,
    linger,
    open_session,
    stopped_early,
)
from common.core.rejection import Rejected
from common.core.sequence import StampJump
from common.deploy.config import Config
from common.wire import protocol

Handler = Callable[[str, bytes], None]
QueryHandler = Callable[[zenoh.Query], None]
METRICS_PERIOD_S = 2.0
FINAL_LINGER_S = 0.1  # s the session stays open after the final counters (a status message)


class Service:
    """Runtime of one service instance on one Zenoh session."""

    def __init__(self, name: str, instance: str, cfg: Config) -> None:
        self.name, self.instance, self.cfg = name, instance, cfg
        self.root = cfg.zenoh.root
        self.log = logging.getLogger(f"{name}[{instance}]")
        self.inbox = Inbox()
        self.counters: Counter[str] = Counter()
        self.rejected: Counter[str] = Counter()
        self.losses = LossCount(self.log)
        self.last_t: float | None = None
        self.gauges: dict[str, Any] = {}  # a service's own fields of its metrics
        self._durations: deque[float] = deque(maxlen=2000)
        self._handlers: dict[str, Handler] = {}
        self._query_handlers: dict[str, QueryHandler] = {}
        self._routes: list[tuple[zenoh.KeyExpr, Handler]] = []
        self._qroutes: list[tuple[zenoh.KeyExpr, QueryHandler]] = []
        self._publishers: dict[str, Publisher] = {}
        self._entities: list[Any] = []
        self._stop = threading.Event()
        self._reset = False
        self._last_put = float("-inf")
        self._started = time.monotonic()
        self.session = open_session(cfg.zenoh)

    def key(self, suffix: str) -> str:
        """Full key of ``suffix`` under the deployment's root."""
        return f"{self.root}/{suffix}"

    def subscribe(self, suffix: str, handler: Handler) -> None:
        """Route samples of key expression root/suffix to ``handler`` on the loop."""
        ke = zenoh.KeyExpr(self.key(suffix))
        self._routes.append((ke, handler))
        self._entities.append(self.session.declare_subscriber(ke, self.inbox.on_sample))

    def local(self, suffix: str, handler: Handler) -> Callable[[bytes], None]:
        """Route items put by the returned function (from any thread, e.g. a poller's)
        to ``handler(key, payload)`` on the loop, as samples of root/suffix: counted
        and rejected alike, never published."""
        ke = zenoh.KeyExpr(self.key(suffix))
        self._routes.append((ke, handler))
        return lambda payload: self.inbox.put(Envelope(str(ke), payload))

    def serve(self, suffix: str, handler: QueryHandler) -> None:
        """Answer queries on root/suffix from the loop (handler calls query.reply)."""
        ke = zenoh.KeyExpr(self.key(suffix))
        self._qroutes.append((ke, handler))
        self._entities.append(self.session.declare_queryable(ke, self.inbox.on_query))

    def publish(self, suffix: str, msg: dict[str, Any]) -> None:
        """Encode and put ``msg`` on root/suffix (reliable, BLOCK, stamped)."""
        pub = self._publishers.get(suffix)
        if pub is None:
            pub = self._publishers[suffix] = Publisher(self.session, self.key(suffix))
        pub.put(protocol.encode(msg))
        self._last_put = time.monotonic()
        self.counters["out"] += 1

    def _finish(self) -> None:
        """A normal end: the last counters say so (the view shows "finished", not gone).
        A status, not an output: it lingers FINAL_LINGER_S of its own in ``close``, not
        the whole data linger (every exit would take CLOSE_LINGER_S longer)."""
        last = self._last_put
        self.publish(f"metrics/{self.name}/{self.instance}", self.metrics() | {"state": "finished"})
        self._last_put = max(last, time.monotonic() - (CLOSE_LINGER_S - FINAL_LINGER_S))

    def reject(self, reason: str, detail: str, key: str) -> None:
        """Count a rejected input and log it (first time per reason, then every 1000th)."""
        self.rejected[reason] += 1
        n = self.rejected[reason]
        if n == 1 or n % LOG_EVERY == 0:
            self.log.error("rejected input on %s (%s, %d so far): %s", key, reason, n, detail)

    def stop(self, *_: Any) -> None:
        self._stop.set()

    def run(self, at_end: Callable[[], None] | None = None) -> int:
        """Drain the inbox until SIGINT/SIGTERM, then call `at_end` (it may still
        publish; its errors are counted as a handler's); returns the exit code."""
        signal.signal(signal.SIGINT, self.stop)
        signal.signal(signal.SIGTERM, self.stop)
        if stopped_early():
            self.stop()
        signals = SignalBytes()  # read by the loop, beside the Python handlers
        token = self.session.liveliness().declare_token(
            f"{self.root}/alive/{self.name}/{self.instance}"
        )
        self.serve(f"control/{self.name}/{self.instance}", self._control)
        self.log.info("running")
        next_metrics = time.monotonic()
        try:
            while not self._stop.is_set():
                env = self.inbox.get(timeout=0.1)
                if env is not None:
                    self._dispatch(env)
                if signals.received():
                    self._stop.set()
                if time.monotonic() >= next_metrics:
                    self.publish(f"metrics/{self.name}/{self.instance}", self.metrics())
                    next_metrics = time.monotonic() + METRICS_PERIOD_S
            if at_end is not None and not self._reset:
                self._guard("(end of input)", at_end)
            if not self._reset:
                self._guard("(end)", self._finish)
        finally:
            signals.close()
            token.undeclare()
            self.close()
        if self._reset:
            self.log.warning("reset by a control query: restarting with a fresh state")
            return RESTART
        self.log.info("stopped: %s", dict(self.counters))
        return 0

    def _control(self, query: zenoh.Query) -> None:
        """Answer a control query with the counters and ``fresh``; with the parameter
        ``reset``, stop the loop for a restart (run returns RESTART)."""
        reset = "reset" in query.parameters
        reply = self.metrics() | {"fresh": self.last_t is None and self.counters["in"] == 0,
                                  "state": "resetting" if reset else "running"}
        query.reply(self.key(f"control/{self.name}/{self.instance}"), protocol.encode(reply))
        if reset:
            self._reset = True
            self._stop.set()

    def _dispatch(self, env: Any) -> None:
        ke = zenoh.KeyExpr(env.key)
        start = time.perf_counter()
        if env.query is not None:
            for route, qhandler in self._qroutes:
                if route.intersects(ke):
                    self._guard(env.key, lambda: qhandler(env.query))
            env.query.drop()
            return
        self.counters["in"] += 1
        try:
            self.losses.check(env.key, env.attachment)
        except StampJump as e:  # the sample itself is still handled
            self.reject("stamp_jump", str(e), env.key)
        except ValueError as e:
            self.reject("attachment", str(e), env.key)
        for route, handler in self._routes:
            if route.intersects(ke):
                self._guard(env.key, lambda: handler(env.key, env.payload))
        self._durations.append(time.perf_counter() - start)

    def _guard(self, key: str, call: Callable[[], None]) -> None:
        try:
            call()
        except Rejected as e:  # common.core.rejection: decode errors and core rejections
            self.reject(e.reason, e.detail, key)
        except Exception as e:  # a bug must not kill the service: count it, log the trace
            self.rejected[f"internal:{type(e).__name__}"] += 1
            self.log.exception("internal error while handling %s", key)

    def metrics(self) -> dict[str, Any]:
        """Counters published on root/metrics/<service>/<instance>."""
        d = np.asarray(self._durations) * 1e3
        return {
            "v": protocol.VERSION,
            "t": float(self.last_t or 0.0),
            "service": self.name,
            "instance": self.instance,
            "in": self.counters["in"],
            "out": self.counters["out"],
            "rejected": dict(self.rejected),
            "missed": dict(self.losses.missed),
            "p50_ms": float(np.percentile(d, 50)) if d.size else 0.0,
            "p99_ms": float(np.percentile(d, 99)) if d.size else 0.0,
            "queue": self.inbox.depth,
            "up_s": time.monotonic() - self._started,
        } | self.gauges

    def close(self) -> None:
        """Undeclare subscribers and queryables, linger after the last output, close the
        session (publishers are not undeclared: see common.bus.transport.Publisher)."""
        for e in self._entities:
            e.undeclare()
        linger(self._last_put)
        self.session.close()
