"""``pfusion replay run.pfrec``: republish a recording in order, at ``--speed`` times the
recorded pace or as fast as possible (0, the default), on reliable BLOCK publishers."""

from __future__ import annotations

import argparse
import logging
import threading
import time
from pathlib import Path

import zenoh

from common.bus.recording import RecordingError, RecordReader
from common.bus.refusal import silence_causes
from common.bus.transport import Publisher, linger, open_session, stop_on_signals, wait_alive
from common.cli import add_common, load_config

log = logging.getLogger("replay")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("recording", help="a .pfrec file written by pfusion record")
    p.add_argument("--speed", type=float, default=0.0,
                   help="times the recorded pace; 0 (default) as fast as possible")
    p.add_argument("--wait-alive", action="append", default=[], metavar="SERVICE/INSTANCE",
                   help="wait until this service's liveliness token exists (repeatable)")
    p.add_argument("--wait-timeout", type=float, default=60.0)


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
        with open_session(cfg.zenoh) as session:
            wait_alive(session, root, args.wait_alive, args.wait_timeout, stop,
                       silence_causes(cfg.zenoh) if cfg.zenoh.auth is not None else "")
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
