"""``pfusion export --geojson OUT``: the global picture of a geodetic deployment as RFC
7946 GeoJSON (common.wire.geojson): the sites, and the tracks of the last radar/gtracks
message with their 2-sigma ellipses and trails, from a recording (``--recording``) or
live (subscribing for ``--seconds``). In a partitioned deployment the tracks are the
union of the latest radar/gtracks/<p> of every partition (common.wire.gtracks_union)."""

from __future__ import annotations

import argparse
import json
import logging
import queue
import time
from pathlib import Path

from common.bus.recording import RecordingError, RecordReader
from common.bus.transport import open_session, stop_on_signals
from common.cli import add_common, load_config
from common.wire import protocol
from common.wire.geojson import TrackHistory
from common.wire.gtracks_union import GtracksUnion, partition_of

log = logging.getLogger("export")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--geojson", required=True, metavar="OUT", help="GeoJSON file to write ('-': stdout)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--recording", metavar="FILE.pfrec", help="read radar/gtracks from a recording")
    src.add_argument("--seconds", type=float, metavar="N", help="subscribe to radar/gtracks for N seconds")


def _record(history: TrackHistory, path: Path) -> int:
    """Ingest the recording's gtracks; the number of undecodable ones."""
    bad = 0
    union = GtracksUnion(())
    with path.open("rb") as f:
        reader = RecordReader(f)
        for rec in reader:
            if protocol.kind_of(rec.key, reader.root) == "gtracks":
                try:
                    msg = protocol.decode("gtracks", rec.payload)
                    history.ingest(union.latest(partition_of(rec.key, reader.root), msg))
                except protocol.DecodeError as e:
                    bad += 1
                    log.error("%s: %s", rec.key, e)
    return bad


def _live(history: TrackHistory, args: argparse.Namespace) -> int:
    """Ingest live gtracks for args.seconds; the number of undecodable ones."""
    cfg = load_config(args)
    q: queue.Queue[tuple[str, bytes]] = queue.Queue()
    stop = stop_on_signals()
    bad = 0
    union = GtracksUnion(())
    root = cfg.zenoh.root
    with open_session(cfg.zenoh) as session:
        subs = [session.declare_subscriber(f"{root}/{k}", lambda s: q.put(
            (str(s.key_expr), s.payload.to_bytes()))) for k in ("radar/gtracks", "radar/gtracks/*")]
        end = time.monotonic() + args.seconds
        while not stop.is_set() and time.monotonic() < end:
            try:
                key, payload = q.get(timeout=0.1)
            except queue.Empty:
                continue
            try:
                msg = protocol.decode("gtracks", payload)
                history.ingest(union.latest(partition_of(key, root), msg))
            except protocol.DecodeError as e:
                bad += 1
                log.error("radar/gtracks: %s", e)
        for sub in subs:
            sub.undeclare()
    return bad


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    if cfg.origin is None:
        print("pfusion export: --geojson needs a geodetic deployment ([radar.origin])", flush=True)
        return 2
    history = TrackHistory()
    try:
        bad = _record(history, Path(args.recording)) if args.recording else _live(history, args)
    except (OSError, RecordingError) as e:
        print(f"pfusion export: {args.recording}: {e}", flush=True)
        return 2
    text = json.dumps(history.geojson(cfg, cfg.origin), separators=(",", ":"))
    if args.geojson == "-":
        print(text, flush=True)
    else:
        Path(args.geojson).write_text(text)
    n = len(history.last["tracks"]) if history.last is not None else 0
    log.info("wrote %d tracks (%d trails) to %s; %d gtracks rejected", n, len(history.trails), args.geojson, bad)
    return 0
