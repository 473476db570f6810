"""Zenoh plumbing: sessions with explicit endpoints and no multicast scouting, TLS and
user/password authentication from the deployment's [zenoh.tls] / [zenoh.auth]
(docs/security.md), and an inbox that Zenoh callbacks only append to (see
../shared/zenoh-notes.md, pitfalls 1-3).
"""

from __future__ import annotations

import json
import logging
import queue
import signal
import socket
import threading
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import zenoh

from common.bus.certs import check_validity
from common.bus.refusal import refusal_causes
from common.bus.rust_log import init_zenoh_log
from common.core.sequence import SequenceCheck
from common.deploy.config import ConfigError, ZenohConfig

LOG_EVERY = 1000
CLOSE_LINGER_S = 0.5
CONNECT_TIMEOUT_S = 10
ROUTER_RETRY = {"period_init_ms": 250, "period_max_ms": 1000, "period_increase_factor": 2.0}
ROUTER_OPEN_TIMEOUT_MS = 3000
# The lease a process announces: how long the other end of each of its links waits
# without a byte before it closes the link. A router's is short, so that a cut
# router-to-router link is found within 2 s (docs/deployment.md); a client's is Zenoh's
# default, so that a router keeps the link of a client starved of CPU on a loaded
# machine (a killed client's link closes at once with its socket, lease or not).
ROUTER_LEASE_MS = 2000
CLIENT_LEASE_MS = 10000


def zenoh_config(
    connect: list[str], listen: list[str], mode: str = "client",
    security: ZenohConfig | None = None,
) -> zenoh.Config:
    """A Zenoh config: multicast scouting off, explicit endpoints, the lease of the mode;
    the TLS and authentication of ``security`` (its [zenoh.tls], [zenoh.auth] and identity).
    With RUST_LOG set (e.g. ``RUST_LOG=warn``), Zenoh's own log goes to stdout, never
    with a password (common.bus.rust_log)."""
    init_zenoh_log()
    c = zenoh.Config()
    c.insert_json5("mode", json.dumps(mode))
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("connect/endpoints", json.dumps(connect))
    c.insert_json5("listen/endpoints", json.dumps(listen))
    c.insert_json5("transport/link/tx/lease", str(ROUTER_LEASE_MS if mode == "router" else CLIENT_LEASE_MS))
    if mode == "client":
        c.insert_json5("connect/timeout_ms", "-1" if not connect else str(CONNECT_TIMEOUT_S * 1000))
    if mode == "router":  # a lost router-router session is retried every <= 1 s (docs/deployment.md)
        c.insert_json5("connect/retry", json.dumps(ROUTER_RETRY))
        # a connect attempt begun while the link was down waits for TCP's SYN back-off
        # (1, 2, 4 s...) until this timeout: 3 s instead of 10 s bounds the wait
        c.insert_json5("transport/unicast/open_timeout", str(ROUTER_OPEN_TIMEOUT_MS))
    if security is not None:
        _secure(c, security, mode, bool(connect))
    return c


def _secure(c: zenoh.Config, zc: ZenohConfig, mode: str, connects: bool) -> None:
    """TLS: root CA, a router's listening certificate, the certificate presented under
    mutual TLS (refused when expired, common.bus.certs). Auth: a router's dictionary of
    identities, this identity's password."""
    router = mode == "router"
    if zc.tls is not None:
        t = zc.tls
        mine = ((t.router_cert or t.cert, "router_cert"), (t.router_key or t.key, "router_key")) \
            if router else ((t.cert, "cert"), (t.key, "key"))
        tls: dict[str, Any] = {"root_ca_certificate": _existing(t.root_ca, "zenoh.tls.root_ca"),
                               "enable_mtls": t.mtls}
        present = t.mtls and (connects or not router)
        if router or present:
            (cert_path, cert_name), (key_path, key_name) = mine
            cert = check_validity(_existing(cert_path, f"zenoh.tls.{cert_name}"),
                                  f"zenoh.tls.{cert_name}")
            key = _secret(key_path, f"zenoh.tls.{key_name}")
            if router:
                tls |= {"listen_certificate": cert, "listen_private_key": key}
            if present:
                tls |= {"connect_certificate": cert, "connect_private_key": key}
        c.insert_json5("transport/link/tls", json.dumps(tls))
    if zc.auth is not None:
        usrpwd: dict[str, str] = {}
        if router:
            usrpwd["dictionary_file"] = _secret(zc.auth.dictionary, "zenoh.auth.dictionary")
        if zc.identity:
            usrpwd |= {"user": zc.identity, "password": password(zc.auth.credentials, zc.identity)}
        elif not router or connects:
            raise ConfigError("zenoh.auth", "this command has no Zenoh identity: pass "
                                            "--identity NAME (docs/security.md)")
        c.insert_json5("transport/auth/usrpwd", json.dumps(usrpwd))


def _existing(path: str, key: str) -> str:
    if not path:
        raise ConfigError(key, "missing (a file path)")
    if not Path(path).is_file():
        raise ConfigError(key, f"{path} does not exist")
    return path


def _secret(path: str, key: str) -> str:
    """A private key, password or dictionary file that only its owner may read: one that
    group or others can read or write is refused (docs/security.md, attacker model (b))."""
    mode = Path(_existing(path, key)).stat().st_mode & 0o777
    if mode & 0o077:
        raise ConfigError(key, f"{path} may be read or written by group or others (mode {mode:o}): "
                               f"chmod 600 {path}")
    return path


def password(credentials: str, identity: str) -> str:
    """The password of ``identity`` in a ``user:password`` file (Zenoh's dictionary
    format)."""
    for line in Path(_secret(credentials, "zenoh.auth.credentials")).read_text().splitlines():
        user, sep, pw = line.strip().partition(":")
        if sep and user == identity:
            return pw
    raise ConfigError("zenoh.auth.credentials", f"{credentials} has no line for identity "
                                                f"'{identity}'")


class RouterUnreachable(zenoh.ZError):
    """A client session found no router at its connect endpoints; the message names them,
    the likely causes and the fix (``pfusion`` prints it as one line and exits with code 2)."""


def open_session(zc: ZenohConfig, mode: str = "client") -> zenoh.Session:
    """Open a session from a deployment's [zenoh] table (raises zenoh.ZError, and
    RouterUnreachable for a client whose routers do not answer)."""
    try:
        return zenoh.open(zenoh_config(zc.connect, zc.listen, mode, security=zc))
    except zenoh.ZError as e:
        if mode != "client" or not zc.connect:
            raise
        why = f"nothing answered within {CONNECT_TIMEOUT_S} s" if "Unable to connect" in str(e) else str(e)
        if zc.auth is not None or zc.tls is not None:
            why += f"; {refusal_causes(zc)}"
        raise RouterUnreachable(
            f"no Zenoh router reachable at {', '.join(zc.connect)} ({why}): start one with "
            f"'pfusion router --listen {zc.connect[0]}', or pass --connect ENDPOINT") from None


class SignalBytes:
    """SIGINT and SIGTERM as bytes on a socket (signal.set_wakeup_fd, main thread only),
    read by a loop beside its Python handlers. CPython runs a Python handler only in the
    main thread, at its next check of pending signals, whichever thread the kernel
    delivered the signal to (here often one of Zenoh's); the C handler writes the byte
    at delivery, so the loop sees the signal at its next poll in any case."""

    def __init__(self) -> None:
        self._r, self._w = socket.socketpair()
        self._r.setblocking(False)
        self._w.setblocking(False)
        signal.set_wakeup_fd(self._w.fileno(), warn_on_full_buffer=False)

    def received(self) -> bool:
        """True once SIGINT or SIGTERM arrived since the last call."""
        try:
            data = self._r.recv(256)
        except BlockingIOError:
            return False
        return signal.SIGINT in data or signal.SIGTERM in data

    def close(self) -> None:
        signal.set_wakeup_fd(-1)
        self._r.close()
        self._w.close()


_EARLY: list[int] = []  # SIGINT / SIGTERM that arrived before a command's own handlers


def hold_early_signals() -> None:
    """In a command just forked: keep SIGINT / SIGTERM until the command installs its own
    handlers (``stop_on_signals``, ``Service.run``), which then stop at once. Without it a
    stop sent while the command still imports or opens its session kills it uncleanly."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda n, _frame: _EARLY.append(n))


def stopped_early() -> bool:
    """Whether SIGINT or SIGTERM arrived while ``hold_early_signals`` held them."""
    return bool(_EARLY)


def stop_on_signals() -> threading.Event:
    """An event set by SIGINT or SIGTERM: the clean-exit flag of a tool's main loop (set
    already when one arrived before, see ``hold_early_signals``)."""
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    if stopped_early():
        stop.set()
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
               stop: threading.Event | None = None, hint: str = "") -> None:
    """Block until every root/alive/<name> liveliness token is present (or ``stop``);
    ``hint`` ends the TimeoutError's message (common.bus.refusal.silence_causes)."""
    stop = stop or threading.Event()
    deadline = time.monotonic() + timeout
    missing = set(names)
    while missing and not stop.is_set():
        for name in list(missing):
            if any(r.ok for r in session.liveliness().get(f"{root}/alive/{name}", timeout=1.0)):
                missing.discard(name)
        if missing and time.monotonic() > deadline:
            raise TimeoutError(f"services not alive after {timeout} s: {sorted(missing)}"
                               + (f" ({hint})" if hint else ""))
        if missing:
            stop.wait(0.1)
    stop.wait(0.3)  # let subscriber declarations reach every router on the path


class Publisher:
    """A reliable BLOCK publisher (never drops) that stamps each sample's attachment with
    (source, n): the session id and n = 0, 1, 2, ... on this key, so that a receiver can
    count a missed sample (``common.core.sequence``; format in docs/protocol.md).

    It has no ``undeclare``: closing the session delivers every queued sample, whereas
    undeclaring a publisher right after a burst loses its samples still in flight, and a
    liveliness round trip before the undeclare does not order with data
    (docs/decisions/015-publisher-no-undeclare.md). Close after :func:`linger`."""

    def __init__(self, session: zenoh.Session, key: str) -> None:
        self._pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK,
                                              reliability=zenoh.Reliability.RELIABLE)
        self._source = str(session.zid())
        self._n = 0

    def put(self, payload: bytes) -> None:
        self._pub.put(payload, attachment=stamp(self._source, self._n))
        self._n += 1


def stamp(source: str, n: int) -> bytes:
    """The attachment of a sample: msgpack [source, n]."""
    return msgpack.packb([source, n])


def read_stamp(attachment: bytes) -> tuple[str, int]:
    """(source, n) of an attachment made by :func:`stamp`; ValueError if it is not one."""
    try:
        source, n = msgpack.unpackb(attachment)
    except (ValueError, TypeError, msgpack.UnpackException) as e:
        raise ValueError(f"attachment is not a [source, n] stamp: {e}") from None
    if not isinstance(source, str) or not isinstance(n, int) or isinstance(n, bool) or n < 0:
        raise ValueError(f"attachment is not a [source, n] stamp: {[source, n]!r:.80}")
    return source, n


class LossCount:
    """Samples missed per key, from the stamps of the samples that did arrive; logged
    the first time on a key and then every ``LOG_EVERY``-th."""

    def __init__(self, log: logging.Logger) -> None:
        self.log = log
        self.missed: Counter[str] = Counter()
        self._sequence = SequenceCheck()

    def check(self, key: str, attachment: bytes | None) -> None:
        """Account for one received sample's stamp: nothing if it has none (a tool of
        the user's), ValueError if it is not a stamp."""
        if attachment is None:
            return
        source, n = read_stamp(attachment)
        missed = self._sequence.observe(key, source, n)
        if missed:
            before = self.missed[key]
            self.missed[key] += missed
            if before == 0 or before // LOG_EVERY != self.missed[key] // LOG_EVERY:
                self.log.error("missed %d sample(s) on %s before stamp %d of %s (%d so far)",
                               missed, key, n, source, self.missed[key])


def attachment_of(sample: zenoh.Sample) -> bytes | None:
    """A received sample's attachment as bytes (None without one)."""
    att = sample.attachment
    return None if att is None else att.to_bytes()


@dataclass(frozen=True)
class Envelope:
    """One received item: a sample (key, payload, attachment) or a query to answer."""

    key: str
    payload: bytes
    query: Any = None
    attachment: bytes | None = None


class Inbox:
    """Unbounded queue fed by Zenoh callbacks and drained by the service loop.

    The callbacks copy the payload and return at once: no Zenoh call, no blocking, so a
    slow service never stalls the session's receive thread. ``depth`` is monitored.

    A ``queue.Queue``, not a ``queue.SimpleQueue``: CPython 3.11's ``SimpleQueue.get``
    with a timeout, interrupted by a signal whose handler (with the GIL taken back)
    ends after the deadline, waits again with the negative remainder, which means for
    ever. A service then sat in ``get`` with its stop flag set and ignored SIGINT and
    SIGTERM (tests/integration/test_shutdown.py, 1 run in about 15 with 5 services; the
    thread's wait seen in gdb: ``PyThread_acquire_lock_timed(microseconds=-61)``).
    ``Queue.get`` waits through ``Lock.acquire``, which treats that remainder as a timeout.
    """

    def __init__(self) -> None:
        self._q: queue.Queue[Envelope] = queue.Queue()

    def put(self, env: Envelope) -> None:
        self._q.put(env)

    def on_sample(self, sample: zenoh.Sample) -> None:
        self.put(Envelope(str(sample.key_expr), sample.payload.to_bytes(), attachment=attachment_of(sample)))

    def on_query(self, query: zenoh.Query) -> None:
        self.put(Envelope(str(query.key_expr), b"", query))

    def get(self, timeout: float) -> Envelope | None:
        try:
            return self._q.get(timeout=timeout)
        except queue.Empty:
            return None

    @property
    def depth(self) -> int:
        return self._q.qsize()


def linger(since: float | None = None) -> None:
    """Keep a session open ``CLOSE_LINGER_S`` after its last put (monotonic time
    ``since``, default now) before closing it. Closing at once lost the tail of a
    fast replay (131 and 83 of 481 samples, once each in a full test run); neither a
    liveliness nor a data query round trip waits for the queued samples (both answered
    in under 5 ms after a 16000-sample burst), while 0.5 s always did here."""
    remaining = CLOSE_LINGER_S - (time.monotonic() - since if since is not None else 0.0)
    if remaining > 0:
        time.sleep(remaining)
