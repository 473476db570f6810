"""``pfusion tma --config F --array A``: range, course and speed of every confirmed bearing
track of one array (TMA of seed 002, constrained TMA with error handling of seed 003).

Subscribes root/sonar/detections/A (own-ship positions), root/sonar/btracks/A (confirmed tracks)
root/sonar/tma/bounds/A (bounds at run time) and root/sonar/tma/support/A (002 support
values at run time); fetches root/sonar/history/A/<id> for
a newly confirmed track and whenever its TMA cycle is due (the associated detections);
publishes root/sonar/tma/A per btracks cycle (docs/protocol.md).

Configuration: [sonar.tma] (TmaParams), [sonar.tma.ctma] (CtmaParams), [sonar.tma.support]
(SupportParams), [sonar.tma.bounds]
(BoundsParams, default of every array) overridden key by key by [sonar.tma.bounds.<A>].
"""

from __future__ import annotations

import argparse
from typing import Any

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import Config, ConfigError, section, table
from common.deploy.sections import array_bounds
from common.sonar.tma.bounds import Bounds
from common.sonar.tma.constrained import CtmaParams
from common.sonar.tma.manager import BOUNDS_FIELDS, SupportParams, TmaManager, TmaParams, make_bounds
from common.wire import protocol

HISTORY_TIMEOUT_S = 2.0
SUBTABLES = ("ctma", "bounds", "support")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--array", required=True, help="sonar array id of the deployment")


def tma_config(cfg: Config, array: str) -> tuple[TmaParams, CtmaParams, Bounds, SupportParams]:
    """The TMA parameters, core config, initial bounds and support values of ``array``."""
    tma = table(cfg.doc, "sonar.tma")
    extra = sorted(k for k, v in tma.items() if isinstance(v, dict) and k not in SUBTABLES)
    if extra:
        raise ConfigError(f"sonar.tma.{extra[0]}", f"unknown table (known: {', '.join(SUBTABLES)})")
    params = section(cfg, "sonar.tma", TmaParams)
    core = section(cfg, "sonar.tma.ctma", CtmaParams)
    known = {a.id for a in cfg.arrays}
    for k, v in table(cfg.doc, "sonar.tma.bounds").items():
        if isinstance(v, dict) and k not in known:
            raise ConfigError(f"sonar.tma.bounds.{k}", "not an array of the deployment")
    # BoundsParams checks what make_bounds requires: no Rejected here
    b = make_bounds(array_bounds(cfg, array))
    return params, core, b, section(cfg, "sonar.tma.support", SupportParams)


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    arr = cfg.array(args.array)
    params, core, bounds, support = tma_config(cfg, arr.id)
    svc = Service("tma", arr.id, cfg)
    mgr = TmaManager(arr.id, params, bounds, core, support)

    def history(tid: int) -> dict[str, Any] | None:
        """The bearing register of a newly confirmed track (None: not served in time)."""
        for reply in svc.session.get(svc.key(f"sonar/history/{arr.id}/{tid}"), timeout=HISTORY_TIMEOUT_S):
            if reply.ok is None:
                continue
            try:
                return protocol.decode("history", reply.ok.payload.to_bytes())
            except protocol.DecodeError as e:
                svc.reject(f"history:{e.field}", str(e), f"sonar/history/{arr.id}/{tid}")
        svc.reject("history_missing", f"no history of track {tid} within {HISTORY_TIMEOUT_S} s", "sonar/history")
        return None

    def process() -> None:
        ready, dropped = mgr.ready()
        if dropped:
            svc.reject("no_own_ship", f"{dropped} btracks messages without own-ship position", "sonar/btracks")
        for msg in ready:
            hist = {tid: history(tid) for tid in mgr.history_wanted(msg)}
            svc.publish(f"sonar/tma/{arr.id}", mgr.step(msg, hist))
            svc.last_t = msg["t"]

    def on_det(key: str, payload: bytes) -> None:
        msg = protocol.decode("detections", payload)
        if msg["array"] != arr.id:
            raise Rejected("unknown_array", f"array '{msg['array']}' on {key}")
        mgr.add_own(msg["t"], msg["own"]["x"], msg["own"]["y"])
        process()

    def on_btracks(key: str, payload: bytes) -> None:
        mgr.push(protocol.decode("btracks", payload))
        process()

    def on_bounds(key: str, payload: bytes) -> None:
        msg = protocol.decode("tma_bounds", payload)
        ids: list[int] = []
        ids.extend(mgr.set_bounds(msg))
        svc.log.info("bounds %s for tracks %s", [msg[k] for k in BOUNDS_FIELDS], ids)

    def on_support(key: str, payload: bytes) -> None:
        msg = protocol.decode("tma_support", payload)
        mgr.add_support(msg)
        svc.log.info("support %s %s +- %s for track %s", msg["kind"], msg["value"], msg["sigma"], msg["track"])

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.subscribe(f"sonar/btracks/{arr.id}", on_btracks)
    svc.subscribe(f"sonar/tma/bounds/{arr.id}", on_bounds)
    svc.subscribe(f"sonar/tma/support/{arr.id}", on_support)
    return svc.run()
