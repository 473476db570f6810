"""``pfusion record KEYEXPR... --out run.pfrec``: write every sample of the key
expressions (under the root) to a recording, for ``--duration`` seconds or, by default,
until the simulator reports ``sim/status`` done (then ``--linger`` seconds more).

One subscriber takes the whole root and the loop keeps the samples that match: every
Zenoh callback subscriber has a delivery thread of its own, so samples of two
subscribers would not keep their arrival order (sim/status overtook the last plots).
"""

from __future__ import annotations

import argparse
import logging
import queue
import time
from pathlib import Path

import zenoh

from common.bus.recording import RecordWriter
from common.bus.transport import LossCount, attachment_of, open_session, stop_on_signals
from common.cli import add_common, load_config
from common.wire import protocol

log = logging.getLogger("record")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p, config_required=False)
    p.add_argument("keyexpr", nargs="+", help="key expression under the root, e.g. 'radar/plots/**'")
    p.add_argument("--out", required=True, help="recording file to write (.pfrec)")
    p.add_argument("--duration", type=float, default=None,
                   help="record this many seconds (default: until sim/status is done)")
    p.add_argument("--linger", type=float, default=1.0,
                   help="seconds to keep recording after sim/status done")


class Stamped:
    """Zenoh callbacks stamp each sample with the monotonic clock and enqueue it."""

    def __init__(self) -> None:
        # a Queue, as common.bus.transport.Inbox: SimpleQueue.get(timeout) can miss the stop
        self.q: queue.Queue[tuple[float, str, bytes, bytes | None]] = queue.Queue()

    def on_sample(self, sample: zenoh.Sample) -> None:
        self.q.put((time.monotonic(), str(sample.key_expr), sample.payload.to_bytes(),
                    attachment_of(sample)))


class Writer:
    """Writes the wanted samples and counts the ones that never arrived (their
    publishers' stamps, ``common.bus.transport.LossCount``)."""

    def __init__(self, writer: RecordWriter, wanted: list[zenoh.KeyExpr], t0: float) -> None:
        self.writer, self.wanted, self.t0 = writer, wanted, t0
        self.losses = LossCount(log)
        self.last = 0.0

    def take(self, stamp: float, key: str, payload: bytes, attachment: bytes | None) -> None:
        if not any(w.intersects(zenoh.KeyExpr(key)) for w in self.wanted):
            return
        try:
            self.losses.check(key, attachment)
        except ValueError as e:
            log.error("%s: %s", key, e)
        self.last = max(self.last, stamp - self.t0)
        self.writer.write(key, self.last, payload)


def finished(payload: bytes) -> bool:
    """A sim/status payload that says the simulator is done."""
    try:
        return protocol.decode("sim_status", payload)["state"] == "done"
    except protocol.DecodeError as e:
        log.error("invalid sim/status ignored: %s", e)
        return False


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    root = cfg.zenoh.root
    stop = stop_on_signals()
    inbox = Stamped()
    wanted = [zenoh.KeyExpr(f"{root}/{k}") for k in args.keyexpr]
    status_key = f"{root}/sim/status"
    out = Path(args.out)
    with open_session(cfg.zenoh) as session, out.open("wb") as f:
        sub = session.declare_subscriber(f"{root}/**", inbox.on_sample)
        token = session.liveliness().declare_token(f"{root}/alive/record/{out.stem}")
        t0 = time.monotonic()
        rec = Writer(RecordWriter(f, root, time.time()), wanted, t0)
        end = t0 + args.duration if args.duration is not None else float("inf")
        log.info("recording %s to %s", ", ".join(args.keyexpr), out)
        while not stop.is_set() and time.monotonic() < end:
            try:
                stamp, key, payload, attachment = inbox.q.get(timeout=0.1)
            except queue.Empty:
                continue
            rec.take(stamp, key, payload, attachment)
            if key == status_key and args.duration is None and finished(payload):
                end = min(end, time.monotonic() + args.linger)
        token.undeclare()
        sub.undeclare()
        while not inbox.q.empty():
            rec.take(*inbox.q.get())
    log.info("wrote %d records to %s (%d samples missed)", rec.writer.count, out,
             sum(rec.losses.missed.values()))
    return 0
