"""``pfusion global-fusion``: elementary tracks of all bases -> global Cartesian tracks
(001 step 24, modules 61-65; crossing management of 004), or a network's tracks.

Subscribes radar/etracks/*, publishes radar/gtracks with every live global track. The
core is common.radar.fusion_core.fusion_core's pick for the deployment (docs/networks.md):
001's GlobalFusion (common.radar.fusion.cycle) when every base measures azimuth and all
share one receiver, common.radar.network's NetworkFusion otherwise (several receivers or
range-Doppler bases); this module only decodes and validates (into typed arrays,
common.wire.radar_messages.etracks_of), publishes, and flushes the core on stop.
Parameters: [radar.fusion] (FusionParams) and, optionally, [radar.fusion_crossing]
(CrossingParams) of 001's core; without that table the global tracks use the sup-norm
ambiguity test of 004 (dimension-free; eq. 13 needs the surveillance volume in m^3 as
`volume`). [radar.tracker] (ElementaryParams) gives the elementary trackers' F [19] /
Q [20] noise, needed to recover their equivalent measurements.

001's arrival rule (common.radar.fusion.arrival, given this process's monotonic clock as
wall time): a base silent for `max_wait` s is stale; late, duplicate and clock_ahead
reports are rejected, counted and logged (docs/faults.md). The network core orders
reports in its window by message time and rejects one older than what it processed
(too_late). Also rejected: a report of a base not configured (unknown_base) or published
under another base's key (base_mismatch).
"""

from __future__ import annotations

import argparse
import time

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import ConfigError
from common.radar.fusion.report import GlobalTracks
from common.wire.radar_chain import global_fusion
from common.wire.radar_messages import etracks_of, gtracks_message


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    try:
        core = global_fusion(cfg)
    except ValueError as e:
        raise ConfigError("radar.base", str(e)) from None
    svc = Service("global_fusion", "main", cfg)

    def publish(out: list[GlobalTracks]) -> None:
        for g in out:
            svc.last_t = g.t
            svc.publish("radar/gtracks", gtracks_message(g, cfg.origin))

    def on_etracks(key: str, payload: bytes) -> None:
        base, tracks = etracks_of(payload)
        if base not in core.bases:
            raise Rejected("unknown_base", f"base '{base}' is not configured")
        if key.rsplit("/", 1)[-1] != base:
            raise Rejected("base_mismatch", f"base '{base}' published on {key}")
        publish(core.push(base, tracks, time.monotonic()))

    svc.subscribe("radar/etracks/*", on_etracks)
    return svc.run(at_end=lambda: publish(core.flush()))
