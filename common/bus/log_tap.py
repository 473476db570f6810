"""The router's own Zenoh log through its audit (common.bus.audit): standard output (file
descriptor 1, where Zenoh's logger writes) becomes a pipe that a thread reads line by
line. Each line goes to the audit, and on to the real standard output only if the
operator's ``RUST_LOG`` asked for it (the audit raises a few targets for itself:
common.bus.rust_log.enabled decides); audit lines go to the Python log as WARNINGs.
Started before Zenoh's logger, closed after the session.
"""

from __future__ import annotations

import fcntl
import logging
import os
import select
import sys
import threading
import time
from collections.abc import Callable
from typing import BinaryIO

from common.bus.audit import ACL, GROUP_S, QUIET, Audit, Event, split
from common.bus.rust_log import Directive, enabled

PIPE_BYTES = 1 << 20  # Zenoh's threads block on a full pipe: room for bursts of denials
log = logging.getLogger("audit")


class LogTap:
    """Standard output through :class:`Audit` while open."""

    def __init__(self, audit: Audit, asked: list[Directive],
                 on_event: Callable[[Event], None] | None = None) -> None:
        self.audit, self.asked, self.on_event = audit, asked, on_event
        self._out = -1
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()  # the audit is fed by the reader, read by counters()

    def counters(self) -> dict[str, int]:
        """A copy of the audit's counters."""
        with self._lock:
            return dict(self.audit.counters)

    def __enter__(self) -> LogTap:
        sys.stdout.flush()
        self._out = os.dup(1)
        r, w = os.pipe()
        try:
            fcntl.fcntl(w, fcntl.F_SETPIPE_SZ, PIPE_BYTES)
        except OSError:  # above /proc/sys/fs/pipe-max-size: the default size
            pass
        os.dup2(w, 1)
        os.close(w)
        self._thread = threading.Thread(target=self._read, args=(r,), name="audit", daemon=True)
        self._thread.start()
        return self

    def _read(self, fd: int) -> None:
        # Zenoh writes a line per allowed message at the access control's TRACE: unless
        # the operator asked for them, they are dropped before any parsing
        allowed = None if enabled(self.asked, ACL, "trace") else b" is authorized to "
        rest = b""
        with os.fdopen(os.dup(self._out), "wb", buffering=0) as out:
            while True:
                ready, _, _ = select.select([fd], [], [], GROUP_S)
                chunk = os.read(fd, 1 << 16) if ready else b""
                if ready and not chunk:
                    break
                *lines, rest = (rest + chunk).split(b"\n")
                for raw in lines:
                    if allowed is None or allowed not in raw:
                        self._line(raw + b"\n", out)
                with self._lock:
                    self._report(self.audit.flush(time.monotonic()))
            if rest:
                self._line(rest, out)
            with self._lock:
                self._report(self.audit.flush(float("inf")))
        os.close(fd)

    def _line(self, raw: bytes, out: BinaryIO) -> None:
        line = raw.decode("utf-8", "replace")
        parts = split(line)
        if parts is None or enabled(self.asked, parts[2], parts[0]):
            out.write(raw)
        if parts is not None:
            with self._lock:
                self._report(self.audit.feed(line, time.monotonic()))

    def _report(self, events: list[Event]) -> None:
        for event in events:
            if self.on_event is not None:
                self.on_event(event)
            for text in self.audit.lines(event, time.monotonic()):
                log.log(logging.DEBUG if event.kind in QUIET else logging.WARNING, "%s", text)

    def __exit__(self, *_: object) -> None:
        """Give standard output back; the reader ends with the pipe (Zenoh's logger
        writes to file descriptor 1, which no longer is the pipe)."""
        sys.stdout.flush()
        os.dup2(self._out, 1)
        os.close(self._out)
        if self._thread is not None:
            self._thread.join(timeout=2.0)
