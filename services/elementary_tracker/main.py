"""``pfusion elementary-tracker``: fused plots of one base -> elementary tracks (001
modules 41-44, crossing management of 004).

Subscribes radar/fused/<base>, publishes radar/etracks/<base> once per scan with every
live track ([r_b, v_b, gamma_b] at a base declared `azimuth = false`). The algorithm is
common.radar.elementary.tracker; this module only decodes, validates and publishes.
"""

from __future__ import annotations

import argparse

from common.bus.service import Service
from common.cli import add_base_service, load_config
from common.core.rejection import Rejected
from common.deploy.config import section
from common.radar.elementary.model import model_of
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.wire import protocol
from common.wire.radar_messages import etracks_message, plots_of

add_arguments = add_base_service  # --config, --connect, --base


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    base = cfg.base(args.base)
    core = ElementaryTracker(section(cfg, "radar.tracker", ElementaryParams),
                             section(cfg, "radar.crossing", RadarCrossingParams),
                             model_of(base.azimuth))
    svc = Service("elementary_tracker", base.id, cfg)

    def on_fused(key: str, payload: bytes) -> None:
        msg = protocol.decode("fused", payload)
        if msg["base"] != base.id:
            raise Rejected("unknown_base", f"base '{msg['base']}' on a tracker of '{base.id}'")
        tracks = core.step(msg["t"], plots_of(msg, base.azimuth))
        svc.last_t = tracks.t
        svc.publish(f"radar/etracks/{base.id}", etracks_message(base.id, tracks))

    svc.subscribe(f"radar/fused/{base.id}", on_fused)
    return svc.run()
