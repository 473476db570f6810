"""``pfusion replay run.pfrec``: republish a recording in order, at ``--speed`` times the
recorded pace or as fast as possible (0, the default), on reliable BLOCK publishers.

Before it publishes, it asks every service's control queryable (common.bus.control)
what it has processed: services already at or past the recording's first message time
would reject the replayed inputs as late, so the replay exits with code 3 naming them,
or, with ``--reset``, restarts them with a fresh state and waits until they answer
again."""

from __future__ import annotations

import argparse
import logging
import sys
import threading
import time
from pathlib import Path

import zenoh

from common.bus import control
from common.bus.recording import RecordingError, RecordReader
from common.bus.refusal import silence_causes
from common.bus.transport import Publisher, linger, open_session, stop_on_signals, wait_alive
from common.cli import add_common, load_config
from common.wire import protocol

AHEAD = 3  # exit code: services ahead of the recording, no --reset

log = logging.getLogger("replay")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("recording", help="a .pfrec file written by pfusion record")
    p.add_argument("--speed", type=float, default=0.0,
                   help="times the recorded pace; 0 (default) as fast as possible")
    p.add_argument("--wait-alive", action="append", default=[], metavar="SERVICE/INSTANCE",
                   help="wait until this service's liveliness token exists (repeatable)")
    p.add_argument("--wait-timeout", type=float, default=60.0)
    p.add_argument("--reset", action="store_true",
                   help="restart the services that already processed the recording's times "
                        "with a fresh state (without it, the replay refuses to start into them)")


def first_time(path: Path) -> float | None:
    """The earliest message time ``t`` of the recording's payloads (None: none has one)."""
    first = None
    with path.open("rb") as f:
        for rec in RecordReader(f):
            try:
                t = protocol.unpack(rec.payload).get("t")
            except protocol.DecodeError:
                continue
            if isinstance(t, (int, float)) and not isinstance(t, bool) and (first is None or t < first):
                first = float(t)
    return first


def clear_ahead(session: zenoh.Session, root: str, t_first: float | None, reset: bool,
                timeout: float) -> str:
    """'' when no service is ahead of ``t_first`` (after resetting them with ``reset``);
    else why the replay must not start."""
    if t_first is None:
        return ""
    late = control.ahead(control.states(session, root), t_first)
    if not late:
        return ""
    names = ", ".join(f"{s}/{i} (t={t:g})" for (s, i), t in late.items())
    if not reset:
        return (f"services ahead of the recording (it starts at t={t_first:g}): {names}; "
                "they would reject every replayed input as late: pass --reset to restart them")
    log.warning("resetting services ahead of the recording (t=%g): %s", t_first, names)
    missing = control.reset(session, root, list(late), timeout)
    return f"reset services not back within {timeout:g} s: {missing}" if missing else ""


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    stop = stop_on_signals()
    path = Path(args.recording)
    with path.open("rb") as f:
        try:
            reader = RecordReader(f)
        except RecordingError as e:
            log.error("%s: %s", path, e)
            return 2
        root = cfg.zenoh.root if args.config else reader.root
        try:
            t_first = first_time(path)
        except RecordingError as e:
            log.error("%s: %s", path, e)
            return 2
        with open_session(cfg.zenoh) as session:
            wait_alive(session, root, args.wait_alive, args.wait_timeout, stop,
                       silence_causes(cfg.zenoh) if cfg.zenoh.auth is not None else "")
            refused = clear_ahead(session, root, t_first, args.reset, args.wait_timeout)
            if refused:
                print(f"pfusion replay: {refused}", file=sys.stderr)
                return AHEAD
            try:
                n = replay(session, reader, root, args.speed, stop)
            except RecordingError as e:
                log.error("%s: %s", path, e)
                return 2
            linger()
    if reader.errors:
        log.warning("%s: last record truncated (%d bytes ignored)", path, reader.truncated_bytes)
    log.info("replayed %d records from %s", n, path)
    return 0


def replay(session: zenoh.Session, reader: RecordReader, root: str, speed: float,
           stop: threading.Event) -> int:
    """Publish every record under ``root`` (in place of the recorded root); returns the count."""
    pubs: dict[str, Publisher] = {}
    n = 0
    wall0 = time.monotonic()
    prefix = reader.root + "/"
    for rec in reader:
        if stop.is_set():
            break
        if speed > 0:
            delay = wall0 + rec.t / speed - time.monotonic()
            if delay > 0 and stop.wait(delay):
                break
        key = root + "/" + rec.key[len(prefix):] if rec.key.startswith(prefix) else rec.key
        pub = pubs.get(key)
        if pub is None:
            pub = pubs[key] = Publisher(session, key)
        pub.put(rec.payload)
        n += 1
    return n
