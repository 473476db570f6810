"""``pfusion bearing-tracker --config F --array A``: seed 000 bearing tracker of one array.

Subscribes root/sonar/detections/A, publishes root/sonar/btracks/A each cycle and
answers root/sonar/history/A/<id> with the bearing register of a confirmed track
(docs/protocol.md). Parameters: [sonar.tracker] (TrackerParams), [sonar.crossing]
(CrossingParams).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import Any

import zenoh

from common.wire import protocol
from common.sonar.bearing_tracker import BearingTracker, Cycle, TimeOrderError, TrackerParams
from common.cli import add_common, load_config
from common.deploy.config import section
from common.core.crossing import CrossingParams
from common.bus.service import Rejected, Service


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--array", required=True, help="sonar array id of the deployment")


def btracks_message(array: str, c: Cycle, narrowband: bool) -> dict[str, Any]:
    """The btracks message of one cycle (docs/protocol.md)."""
    cols = zip(c.ids.tolist(), c.confirmed.tolist(), c.x.tolist(), [p.ravel().tolist() for p in c.P],
               c.quality.tolist(), c.ambiguous.tolist(), c.ml.tolist())
    tracks = []
    for tid, conf, x, P, q, amb, ml in cols:
        tr = {"id": tid, "status": "confirmed" if conf else "tentative", "x": x, "P": P,
              "quality": q, "ambiguous": amb}
        if ml >= 0:
            tr["ml"] = ml
        tracks.append(tr)
    msg: dict[str, Any] = {"v": protocol.VERSION, "t": c.t, "array": array, "tracks": tracks}
    if narrowband:
        msg["multiline"] = [
            {"id": m.id, "lines": m.lines, "brg": m.brg, "brg_rate": m.brg_rate}
            for m in c.multiline
        ]
    return msg


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    arr = cfg.array(args.array)
    params = section(cfg, "sonar.tracker", TrackerParams)
    crossing = section(cfg, "sonar.crossing", CrossingParams)
    svc = Service("bearing_tracker", arr.id, cfg)
    cores: list[BearingTracker] = []

    def tracker(narrowband: bool) -> BearingTracker:
        """The core, built at the first detection list when mode = "auto"."""
        if not cores:
            mode = params.mode if params.mode != "auto" else ("narrowband" if narrowband else "broadband")
            cores.append(BearingTracker(replace(params, mode=mode), arr.kind, arr.sigma0, crossing))
        return cores[0]

    def on_det(key: str, payload: bytes) -> None:
        msg = protocol.decode("detections", payload)
        if msg["array"] != arr.id:
            raise Rejected("unknown_array", f"array '{msg['array']}' on {key}")
        freq, sbrg = msg.get("freq"), msg.get("sbrg")
        core = tracker(freq is not None)
        if core.narrowband and freq is None:
            raise Rejected("missing_freq", "narrowband tracking needs freq[]")
        brg, amp = msg["brg"], msg["amp"]
        good = amp > 0
        if not good.all():
            svc.reject("nonpositive_amp", f"{int((~good).sum())} detections dropped", key)
            brg, amp = brg[good], amp[good]
            freq = freq[good] if freq is not None else None
            sbrg = sbrg[good] if sbrg is not None else None
        own = msg["own"]
        try:
            cycle = core.step(msg["t"], brg, amp, own["heading"], own["x"], own["y"],
                              freq if core.narrowband else None, sbrg)
        except TimeOrderError as e:
            raise Rejected("time_order", str(e)) from None
        svc.last_t = msg["t"]
        svc.publish(f"sonar/btracks/{arr.id}", btracks_message(arr.id, cycle, core.narrowband))

    def on_query(query: zenoh.Query) -> None:
        chunk = str(query.key_expr).rsplit("/", 1)[-1]
        if not chunk.isdigit():
            raise Rejected("bad_history_id", f"'{chunk}' is not a track number")
        if not cores:
            return
        core = cores[0]
        found = core.history_of(int(chunk))
        if found is None:
            return
        status, h = found
        query.reply(query.key_expr, protocol.encode({
            "v": protocol.VERSION, "t": float(core.t or 0.0), "array": arr.id,
            "id": int(chunk), "status": status, "t_hist": h["t"], "brg": h["brg"],
            "sbrg": h["sbrg"], "own_x": h["own_x"], "own_y": h["own_y"],
        }))

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.serve(f"sonar/history/{arr.id}/*", on_query)
    return svc.run()
