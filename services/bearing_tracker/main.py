"""``pfusion bearing-tracker --config F --array A``: seed 000 bearing tracker of one array.

Subscribes root/sonar/detections/A, publishes root/sonar/btracks/A each cycle and
answers root/sonar/history/A/<id> with the bearing register of a confirmed track
(docs/protocol.md; in the multiple-hypothesis mode the detections of the retrodicted
main hypothesis, with the retrodicted bearings beside). Parameters:
[sonar.tracker] (SonarTrackerParams; mode_association "gnn" or "mht"),
[sonar.tracker.mht] (MhtParams), [sonar.crossing] (CrossingParams, "gnn" only).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import zenoh

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.crossing import CrossingParams
from common.core.rejection import Rejected
from common.deploy.config import section
from common.sonar.bearing.tracker import BearingTracker
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.mht.tracker import MhtTracker
from common.wire import protocol
from common.wire.sonar_messages import btracks_message


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--array", required=True, help="sonar array id of the deployment")


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    arr = cfg.array(args.array)
    params = section(cfg, "sonar.tracker", SonarTrackerParams)
    mht = section(cfg, "sonar.tracker.mht", MhtParams)
    crossing = section(cfg, "sonar.crossing", CrossingParams)
    svc = Service("bearing_tracker", arr.id, cfg)
    cores: list[BearingTracker | MhtTracker] = []

    def tracker(narrowband: bool) -> BearingTracker | MhtTracker:
        """The core, built at the first detection list when mode = "auto"."""
        if not cores:
            mode = params.mode if params.mode != "auto" else ("narrowband" if narrowband else "broadband")
            p = replace(params, mode=mode)
            cores.append(MhtTracker(p, mht, arr.kind, arr.sigma0) if params.mode_association == "mht"
                         else BearingTracker(p, arr.kind, arr.sigma0, crossing))
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
        cycle = core.step(msg["t"], brg, amp, own["heading"], own["x"], own["y"],
                          freq if core.narrowband else None, sbrg)
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
            "id": int(chunk), "status": status, "t_hist": h.pop("t"), **h,
        }))

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.serve(f"sonar/history/{arr.id}/*", on_query)
    return svc.run()
