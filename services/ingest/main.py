"""``pfusion ingest``: detections of external nodes -> radar/plots/<base>/<channel>.

``ingest blah2 --base B --url U`` polls a blah2 node (its /api/config checked against
the deployment at start: exit 2 on a mismatch; then /api/detection every --interval s,
/stash/detection after an outage), or replays its saved detections (``--file``);
``ingest csv FILE`` publishes the rows of a CSV file. Parsing, units and time rules:
common.wire.blah2, common.wire.plot_feed; every bad input is counted, never fatal.
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from pathlib import Path

import numpy as np

from common.bus.poller import NodePoller, paced
from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import Config, ConfigError, RadarBase, section
from common.deploy.sections import base_ingest
from common.radar.plots.channel_fusion import PlotterParams
from common.wire import blah2
from common.wire.plot_feed import CsvFeed, NodeFeed, Units, csv_rows

TIMEOUT_S = 5.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="source", required=True)
    b = sub.add_parser("blah2", help="a blah2 node (HTTP API) or its saved detections")
    add_common(b)
    b.add_argument("--base", required=True, help="the node's [[radar.base]] id (one channel)")
    src = b.add_mutually_exclusive_group(required=True)
    src.add_argument("--url", help="the node's API, e.g. http://192.168.1.20:3000")
    src.add_argument("--file", help="a node's saved detections (JSON array, or one frame a line)")
    b.add_argument("--interval", type=float, default=0.5, help="polling period (s, default 0.5)")
    b.add_argument("--speed", type=float, default=0.0, help="--file: times real time (0: at once)")
    c = sub.add_parser("csv", help="plots from a CSV file (columns: docs/networks.md)")
    c.add_argument("file", help="CSV file")
    add_common(c)
    c.add_argument("--speed", type=float, default=0.0, help="times real time (0: at once)")


def _units(cfg: Config, base: RadarBase, fc: float = 0.0, fs: float = 0.0) -> Units:
    p = base_ingest(cfg, base.id)
    return Units(float(np.linalg.norm(base.tx - base.rx)), p.fc or fc, p.fs or fs, p)


def _stamp(doc: object) -> float:
    """A saved frame's time for pacing (0 when it has none: its handler rejects it)."""
    try:
        return blah2.unix_seconds(doc.get("timestamp") if isinstance(doc, dict) else None)
    except Rejected:
        return 0.0


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    max_ahead = section(cfg, "radar.plotter", PlotterParams).max_ahead
    if args.source == "csv":
        return _csv(args, cfg, max_ahead)
    base = cfg.base(args.base)
    if len(base.channels) != 1:
        raise ConfigError(f"radar.base.{base.id}.channels", "a blah2 node feeds a base of one channel")
    if args.url and cfg.origin is None:
        raise ConfigError("radar.origin", "is needed to check a node's sites (WGS-84)")
    feed = NodeFeed(base, _units(cfg, base), max_ahead)
    if args.file and (feed.units.fc <= 0 or (feed.units.fs <= 0 and feed.units.params.srb <= 0)):
        raise ConfigError(f"radar.ingest.{base.id}.fc", "--file needs fc and fs (or srb) in the deployment")
    svc = Service("ingest", base.id, cfg)
    code = [0]

    def publish(frame: blah2.Frame, now: float | None) -> None:
        if frame.t + feed.units.params.time_offset == feed.stamps.last:
            svc.counters["unchanged"] += 1  # polled again before the node's next frame
            return
        key, msg = feed.message(frame, now)
        svc.last_t = msg["t"]
        svc.publish(key, msg)

    def on_config(_: str, body: bytes) -> None:
        try:
            node = blah2.parse_config(body)
        except Rejected as e:
            svc.log.error("node %s: %s", args.url, e.detail)
            code[0] = 2
            svc.stop()
            return
        assert cfg.origin is not None
        bad = blah2.mismatches(node, base, cfg.origin, feed.units.params.fc, feed.units.params.fs)
        if bad:
            svc.log.error("node %s does not match base %s of the deployment: %s", args.url, base.id, "; ".join(bad))
            code[0] = 2
            svc.stop()
            return
        p = feed.units.params
        feed.units = Units(feed.units.baseline, p.fc or node.fc, p.fs or node.fs,
                           p if node.cpi is None else type(p)(**{**vars(p), "cpi": node.cpi}))
        svc.log.info("node %s matches base %s (fc %g Hz, fs %g Hz)", args.url, base.id, node.fc, node.fs)

    def on_down(_: str, body: bytes) -> None:
        reason, _, detail = body.decode().partition(": ")
        raise Rejected(reason, detail)

    def on_stash(_: str, body: bytes) -> None:
        frames = feed.newer(blah2.parse_stash(body))
        svc.counters["caught_up"] += len(frames)
        for f in frames:
            publish(f, time.time())

    stop = threading.Event()
    suffix = f"local/ingest/{base.id}"
    if args.file:
        put = svc.local(f"{suffix}/frame", lambda _, b: publish(blah2.frame_of(json.loads(b)), None))
        end = svc.local(f"{suffix}/end", lambda _, b: svc.stop())
        docs = blah2.parse_saved(Path(args.file).read_text())
        items = [(_stamp(d), json.dumps(d).encode()) for d in docs]
        thread = threading.Thread(target=lambda: (paced(items, put, args.speed, stop), end(b"")), daemon=True)
    else:
        thread = NodePoller(args.url, args.interval, TIMEOUT_S, svc.local(f"{suffix}/config", on_config),
                            svc.local(f"{suffix}/latest", lambda _, b: publish(blah2.parse_frame(b), time.time())),
                            svc.local(f"{suffix}/stash", on_stash), svc.local(f"{suffix}/down", on_down))
    thread.start()
    try:
        svc.run()
    finally:
        stop.set()
        if isinstance(thread, NodePoller):
            thread.stop()
    svc.log.info("rejected: %s", dict(svc.rejected))
    return code[0]


def _csv(args: argparse.Namespace, cfg: Config, max_ahead: float) -> int:
    feed = CsvFeed(cfg.bases, {b.id: _units(cfg, b) for b in cfg.bases}, max_ahead)
    svc = Service("ingest", "csv", cfg)
    groups: list[tuple[tuple[float, str, str], list[dict[str, float]]]] = []
    for row in csv_rows(Path(args.file).read_text()):
        if isinstance(row, Rejected):
            svc.reject(row.reason, row.detail, args.file)
            continue
        try:
            key, cols = feed.row(row)
        except Rejected as e:
            svc.reject(e.reason, e.detail, args.file)
            continue
        if groups and groups[-1][0] == key:
            groups[-1][1].append(cols)
        else:
            groups.append((key, [cols]))

    def on_group(_: str, body: bytes) -> None:
        key, rows = groups[int(body)]
        suffix, msg = feed.message(key, rows)
        svc.last_t = msg["t"]
        svc.publish(suffix, msg)

    put = svc.local("local/ingest/csv/group", on_group)
    end = svc.local("local/ingest/csv/end", lambda _, b: svc.stop())
    stop = threading.Event()
    items = [(key[0], str(i).encode()) for i, (key, _) in enumerate(groups)]
    threading.Thread(target=lambda: (paced(items, put, args.speed, stop), end(b"")), daemon=True).start()
    try:
        svc.run()
    finally:
        stop.set()
    svc.log.info("rejected: %s", dict(svc.rejected))
    return 0
