"""``pfusion tma --config F --array A``: range, course and speed of every confirmed bearing
track of one array (TMA of seed 002, constrained TMA with error handling of seed 003).

Subscribes root/sonar/detections/A (own-ship positions), root/sonar/btracks/A (confirmed tracks)
and the operator's inputs (issue 31): root/sonar/tma/bounds/A (bounds of the array or of
one track), root/sonar/tma/support/A (002 support values of one track) and
root/sonar/tma/clear/A; fetches root/sonar/history/A/<id>?as_of=<btracks t> for a newly
confirmed track and whenever its TMA cycle is due (the associated detections, as the
tracker's cycle of that btracks message left them); publishes root/sonar/tma/A per
btracks cycle, and root/sonar/tma/ack/A for every input with a request id: accepted, or
the reason it was not (docs/protocol.md). With ``[sonar.tma] state_dir`` the inputs (and
the births of their tracks) are written to <state_dir>/tma-<A>.json whenever they change
and read back at the start, so that a restarted service keeps them.

Configuration (common.deploy.tma_config): [sonar.tma] (TmaParams), [sonar.tma.ctma]
(CtmaParams), [sonar.tma.support] (SupportParams), [sonar.tma.bounds] (BoundsParams,
default of every array) overridden key by key by [sonar.tma.bounds.<A>].
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.tma_config import tma_config
from common.sonar.tma.manager import TmaManager, TrackHistory
from common.sonar.tma.operator_inputs import Accepted
from common.wire import protocol
from common.wire.sonar_messages import (
    ACCEPTED,
    ack_message,
    bounds_from,
    btracks_from,
    history_from,
    support_from,
    tma_message,
)
from services.tma.state import StateFile

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
    state = StateFile(params.state_dir, arr.id, svc)
    state.load(mgr)

    def history(tid: int, t: float) -> TrackHistory | None:
        """The bearing register of a track as of btracks time t (None: not served in time)."""
        selector = f"{svc.key(f'sonar/history/{arr.id}/{tid}')}?as_of={t!r}"
        for reply in svc.session.get(selector, timeout=HISTORY_TIMEOUT_S):
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
            hist = {tid: history(tid, b.t) for tid in mgr.history_wanted(b)}
            svc.publish(f"sonar/tma/{arr.id}", tma_message(mgr.step(b, hist)))
            svc.last_t = b.t
        state.save(mgr)

    def on_det(key: str, payload: bytes) -> None:
        msg = protocol.decode("detections", payload)
        if msg["array"] != arr.id:
            raise Rejected("unknown_array", f"array '{msg['array']}' on {key}")
        mgr.add_own(msg["t"], msg["own"]["x"], msg["own"]["y"])
        process()

    def on_btracks(key: str, payload: bytes) -> None:
        mgr.push(btracks_from(protocol.decode("btracks", payload)))
        process()

    def now() -> float:
        """The service's message time: its latest btracks cycle (0 before any)."""
        return max(float(mgr.t_pushed), 0.0)

    def operator(kind: str, apply: Callable[[dict[str, Any]], Accepted | None]) -> Callable[[str, bytes], None]:
        """A handler of operator inputs: decode, apply, save, ack when asked (a refused
        input is acked with its reason, then counted as rejected)."""
        def handle(key: str, payload: bytes) -> None:
            msg = protocol.unpack(payload)
            req = msg.get("req") if isinstance(msg.get("req"), str) and msg.get("req") else None
            try:
                msg = protocol.decode(kind, payload)
                a = apply(msg)
            except Rejected as e:
                if req is not None:
                    svc.publish(f"sonar/tma/ack/{arr.id}", ack_message(now(), req, e.reason))
                raise
            state.save(mgr)
            svc.log.info("%s %s", kind, {k: v for k, v in msg.items() if k != "v"})
            if req is not None:
                svc.publish(f"sonar/tma/ack/{arr.id}", ack_message(
                    now(), req, ACCEPTED, a.track if a else None, a.birth if a else None))
        return handle

    def on_bounds(msg: dict[str, Any]) -> Accepted | None:
        b, track = bounds_from(msg)
        mgr.set_bounds(b, track, msg.get("birth"))
        return None if track is None else Accepted(track, mgr.inputs.birth[track])

    def on_support(msg: dict[str, Any]) -> Accepted:
        track, s = support_from(msg)
        return mgr.add_support(track, s, msg.get("birth"))

    def on_clear(msg: dict[str, Any]) -> Accepted:
        return mgr.clear(msg["track"], msg["what"], msg.get("birth"))

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.subscribe(f"sonar/btracks/{arr.id}", on_btracks)
    svc.subscribe(f"sonar/tma/bounds/{arr.id}", operator("tma_bounds", on_bounds))
    svc.subscribe(f"sonar/tma/support/{arr.id}", operator("tma_support", on_support))
    svc.subscribe(f"sonar/tma/clear/{arr.id}", operator("tma_clear", on_clear))
    return svc.run()
