"""``pfusion elementary-tracker``: fused plots of one base -> elementary tracks (001
modules 41-44, crossing management of 004).

Subscribes radar/fused/<base>, publishes radar/etracks/<base> once per scan with every
live track. The algorithm is common.elementary; this module only decodes, validates and
publishes.
"""

from __future__ import annotations

import argparse

from common import protocol
from common.cli import add_common, load_config
from common.config import section
from common.elementary import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.plot_fusion import LateInput, Plots
from common.service import Rejected, Service
from common.track_table import Status

STATUS = {int(Status.TENTATIVE): "tentative", int(Status.CONFIRMED): "confirmed",
          int(Status.COASTING): "coasting"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--base", required=True, help="bistatic base id (a [[radar.base]] id)")


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    base = cfg.base(args.base)
    core = ElementaryTracker(section(cfg, "radar.tracker", ElementaryParams),
                             section(cfg, "radar.crossing", RadarCrossingParams))
    svc = Service("elementary_tracker", base.id, cfg)

    def on_fused(key: str, payload: bytes) -> None:
        msg = protocol.decode("fused", payload)
        if msg["base"] != base.id:
            raise Rejected("unknown_base", f"base '{msg['base']}' on a tracker of '{base.id}'")
        plots = Plots(msg["rb"], msg["vb"], msg["az"], msg["srb"], msg["svb"], msg["saz"],
                      msg["n_ch"])
        try:
            tracks = core.step(msg["t"], plots)
        except LateInput as e:
            raise Rejected(e.reason, e.detail) from None
        svc.last_t = tracks.t
        svc.publish(f"radar/etracks/{base.id}", {
            "v": protocol.VERSION, "t": tracks.t, "base": base.id,
            "tracks": [
                {"id": int(tracks.id[k]), "status": STATUS[int(tracks.status[k])],
                 "x": tracks.x[k], "P": tracks.P[k].ravel(), "score": float(tracks.score[k]),
                 "n_ch": int(tracks.n_ch[k]), "updated": bool(tracks.updated[k]),
                 "ambiguous": bool(tracks.ambiguous[k])}
                for k in range(len(tracks))
            ],
        })

    svc.subscribe(f"radar/fused/{base.id}", on_fused)
    return svc.run()
