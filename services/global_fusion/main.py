"""``pfusion global-fusion``: elementary tracks of all bases -> global Cartesian tracks
(001 step 24, modules 61-65; crossing management of 004).

Subscribes radar/etracks/*, publishes radar/gtracks once per fusion cycle with every
live global track. The algorithm is common.radar.fusion.cycle; this module only decodes
and validates (into typed arrays, common.wire.radar_messages.etracks_of) and publishes.
Parameters: [radar.fusion] (FusionParams) and, optionally,
[radar.fusion_crossing] (CrossingParams); without that table the global tracks use the
sup-norm ambiguity test of 004 (dimension-free; eq. 13 needs the surveillance volume
in m^3 as `volume`). [radar.tracker] (ElementaryParams) gives the elementary trackers'
F [19] / Q [20] noise, needed to recover their equivalent measurements.

Arrival rule (common.radar.fusion.arrival, given this process's monotonic clock as wall
time): a base silent for `max_wait` s is stale; late, duplicate and clock_ahead reports
are rejected, counted and logged (docs/faults.md). Also rejected: a report of a base not
configured (unknown_base) or published under another base's key (base_mismatch).
"""

from __future__ import annotations

import argparse
import time

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import ConfigError
from common.radar.fusion.arrival import Arrival
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
    arrival = Arrival(core)
    svc = Service("global_fusion", "main", cfg)

    def on_etracks(key: str, payload: bytes) -> None:
        base, tracks = etracks_of(payload)
        if base not in core.index:
            raise Rejected("unknown_base", f"base '{base}' is not configured")
        if key.rsplit("/", 1)[-1] != base:
            raise Rejected("base_mismatch", f"base '{base}' published on {key}")
        for out in arrival.push(base, tracks, time.monotonic()):
            svc.last_t = out.t
            svc.publish("radar/gtracks", gtracks_message(out, cfg.origin))

    svc.subscribe("radar/etracks/*", on_etracks)
    return svc.run()
