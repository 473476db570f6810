"""``pfusion bearing-tracker --config F --array A``: seed 000 bearing tracker of one array.

Subscribes root/sonar/detections/A, publishes root/sonar/btracks/A each cycle and
answers root/sonar/history/A/<id> with the bearing register of a confirmed track
(docs/protocol.md; in the multiple-hypothesis mode the detections of the retrodicted
main hypothesis, with the retrodicted bearings beside). Also subscribes
root/sonar/tma/A: each solution is kept as its track's hint for the later cycles
(common.sonar.bearing.range_noise, tma_prediction; docs/decisions/026, 028); a tma message
publishes nothing, so the loop tracker -> tma -> tracker is one step per detection list,
never waited for. Parameters:
[sonar.tracker] (SonarTrackerParams; mode_association "gnn" or "mht"),
[sonar.tracker.mht] (MhtParams), [sonar.crossing] (CrossingParams, "gnn" only); the
core is built by common.sonar.trackers.bearing_tracker.
"""

from __future__ import annotations

import argparse

import zenoh

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.crossing import CrossingParams
from common.core.rejection import Rejected
from common.deploy.config import section
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.trackers import BearingTrackerCore, bearing_tracker
from common.wire import protocol
from common.wire.sonar_messages import btracks_message, history_message, tma_hints_from


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
    cores: list[BearingTrackerCore] = []

    def tracker(has_freq: bool) -> BearingTrackerCore:
        """The core, built at the first detection list (it resolves mode "auto")."""
        if not cores:
            cores.append(bearing_tracker(params, mht, arr.kind, arr.sigma0, crossing, has_freq))
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
        query.reply(query.key_expr, protocol.encode(
            history_message(arr.id, float(core.t or 0.0), int(chunk), found)))

    def on_tma(key: str, payload: bytes) -> None:
        msg = protocol.decode("tma", payload)
        if msg["array"] != arr.id:
            raise Rejected("unknown_array", f"array '{msg['array']}' on {key}")
        if not cores:
            return
        for tid, hint in tma_hints_from(msg):
            cores[0].tma_hint(tid, hint)

    svc.subscribe(f"sonar/detections/{arr.id}", on_det)
    svc.subscribe(f"sonar/tma/{arr.id}", on_tma)
    svc.serve(f"sonar/history/{arr.id}/*", on_query)
    return svc.run()
