"""``pfusion channel-plotter``: channel plots of one base -> fused plots (001 modules 31-34).

Subscribes radar/plots/<base>/*, publishes radar/fused/<base> once per scan (also when
empty). A base declared `azimuth = false` (range-Doppler) fuses on (r_b, v_b) and
rejects plots that carry az (`unexpected_azimuth`). The algorithm is
common.radar.plots.channel_fusion; this module only decodes, validates and publishes.
"""

from __future__ import annotations

import argparse

from common.bus.service import Service
from common.cli import add_base_service, load_config
from common.core.rejection import Rejected
from common.deploy.config import section
from common.radar.plots.channel_fusion import PlotFusion, PlotterParams
from common.wire import protocol
from common.wire.radar_messages import fused_message, plots_of

add_arguments = add_base_service  # --config, --connect, --base


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    base = cfg.base(args.base)
    params = section(cfg, "radar.plotter", PlotterParams)
    svc = Service("channel_plotter", base.id, cfg)
    core = PlotFusion(base.channels, base.p, params, base.azimuth)

    def on_plots(key: str, payload: bytes) -> None:
        msg = protocol.decode("plots", payload)
        if msg["base"] != base.id:
            raise Rejected("unknown_base", f"base '{msg['base']}' on a plotter of '{base.id}'")
        if msg["channel"] != key.rsplit("/", 1)[-1]:
            raise Rejected("channel_mismatch", f"channel '{msg['channel']}' published on {key}")
        try:
            scans = core.push(msg["channel"], msg["t"], plots_of(msg, base.azimuth))
        finally:
            for channel, t in core.take_evicted():
                svc.reject("ahead", f"channel {channel}: plots of t={t} dropped, more than max_ahead "
                                    "ahead of the base's other channels", key)
        for t, fused in scans:
            svc.last_t = t
            svc.publish(f"radar/fused/{base.id}", fused_message(base.id, t, fused))

    svc.subscribe(f"radar/plots/{base.id}/*", on_plots)
    return svc.run()
