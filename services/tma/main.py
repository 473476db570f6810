"""``pfusion tma --config F --array A``: range, course and speed of every confirmed bearing
track of one array (TMA of seed 002, constrained TMA with error handling of seed 003).

Subscribes root/sonar/detections/A (own-ship positions), root/sonar/btracks/A (confirmed tracks)
root/sonar/tma/bounds/A (bounds at run time) and root/sonar/tma/support/A (002 support
values at run time); fetches root/sonar/history/A/<id> for
a newly confirmed track and whenever its TMA cycle is due (the associated detections);
publishes root/sonar/tma/A per btracks cycle (docs/protocol.md).

Configuration (common.deploy.tma_config): [sonar.tma] (TmaParams), [sonar.tma.ctma]
(CtmaParams), [sonar.tma.support] (SupportParams), [sonar.tma.bounds] (BoundsParams,
default of every array) overridden key by key by [sonar.tma.bounds.<A>].
"""

from __future__ import annotations

import argparse

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.tma_config import tma_config
from common.sonar.tma.manager import TmaManager, TrackHistory
from common.wire import protocol
from common.wire.sonar_messages import bounds_from, btracks_from, history_from, support_from, tma_message

HISTORY_TIMEOUT_S = 2.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--array", required=True, help="sonar array id of the deployment")


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    arr = cfg.array(args.array)
    params, core, bounds, support = tma_config(cfg, arr.id)
    svc = Service("tma", arr.id, cfg)
    mgr = TmaManager(arr.id, params, bounds, core, support)

    def history(tid: int) -> TrackHistory | None:
        """The bearing register of a newly confirmed track (None: not served in time)."""
        for reply in svc.session.get(svc.key(f"sonar/history/{arr.id}/{tid}"), timeout=HISTORY_TIMEOUT_S):
            if reply.ok is None:
                continue
            try:
                return history_from(protocol.decode("history", reply.ok.payload.to_bytes()))
            except protocol.DecodeError as e:
                svc.reject(f"history:{e.field}", str(e), f"sonar/history/{arr.id}/{tid}")
        svc.reject("history_missing", f"no history of track {tid} within {HISTORY_TIMEOUT_S} s", "sonar/history")
        return None

    def process() -> None:
        ready, dropped = mgr.ready()
        if dropped:
            svc.reject("no_own_ship", f"{dropped} btracks messages without own-ship position", "sonar/btracks")
        for b in ready:
            hist = {tid: history(tid) for tid in mgr.history_wanted(b)}
            svc.publish(f"sonar/tma/{arr.id}", tma_message(mgr.step(b, hist)))
            svc.last_t = b.t

    def on_det(key: str, payload: bytes) -> None:
        msg = protocol.decode("detections", payload)
        if msg["array"] != arr.id:
            raise Rejected("unknown_array", f"array '{msg['array']}' on {key}")
        mgr.add_own(msg["t"], msg["own"]["x"], msg["own"]["y"])
        process()

    def on_btracks(key: str, payload: bytes) -> None:
        mgr.push(btracks_from(protocol.decode("btracks", payload)))
        process()

    def on_bounds(key: str, payload: bytes) -> None:
        b, track = bounds_from(protocol.decode("tma_bounds", payload))
        svc.log.info("bounds %s for tracks %s", b, mgr.set_bounds(b, track))

    def on_support(key: str, payload: bytes) -> None:
        track, s = support_from(protocol.decode("tma_support", payload))
        mgr.add_support(track, s)
        svc.log.info("support %s %s +- %s for track %s", s.kind, s.value, s.sigma, track)

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.subscribe(f"sonar/btracks/{arr.id}", on_btracks)
    svc.subscribe(f"sonar/tma/bounds/{arr.id}", on_bounds)
    svc.subscribe(f"sonar/tma/support/{arr.id}", on_support)
    return svc.run()
