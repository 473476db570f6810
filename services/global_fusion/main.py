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

With `--partition NAME` (a deployment whose [radar.network] names partitions, one
instance each, docs/networks.md "Partitions"; common.radar.network.partition) it
publishes radar/gtracks/NAME, hands tracks over on radar/handover/<to> and acks those
handed to it on radar/handover_ack/<from>; it reads the other partitions'
radar/gtracks/* for the members they hold. A handover or ack addressed to another
partition is rejected (partition_mismatch). Its metrics add `handover` (handed,
acked, timeouts, adopted, conflicts, unknown_base).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

from common.bus.service import Service
from common.cli import add_common, load_config
from common.core.rejection import Rejected
from common.deploy.config import ConfigError
from common.radar.fusion.report import GlobalTracks
from common.radar.fusion_core import Network
from common.radar.network.partition import Partition
from common.wire import protocol
from common.wire.radar_chain import global_fusion
from common.wire.radar_messages import (
    claimed_members,
    etracks_of,
    gtracks_message,
    handed_of,
    handover_ack_message,
    handover_message,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    p.add_argument("--partition", help="the partition of [radar.network] partitions to run "
                   "(required when the deployment names partitions)")


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args)
    name = args.partition
    try:
        core = global_fusion(cfg, name)
    except ValueError as e:
        raise ConfigError("radar.network" if name or "partition" in str(e) else "radar.base",
                          str(e)) from None
    svc = Service("global_fusion", name or "main", cfg)
    out_key = f"radar/gtracks/{name}" if name else "radar/gtracks"

    def publish(out: list[GlobalTracks]) -> None:
        for g in out:
            svc.last_t = g.t
            svc.publish(out_key, gtracks_message(g, cfg.origin))

    def on_etracks(key: str, payload: bytes) -> None:
        base, tracks = etracks_of(payload)
        if base not in core.bases:
            raise Rejected("unknown_base", f"base '{base}' is not configured")
        if key.rsplit("/", 1)[-1] != base:
            raise Rejected("base_mismatch", f"base '{base}' published on {key}")
        publish(core.push(base, tracks, time.monotonic()))
        if isinstance(core, Network) and core.partition is not None:
            hand_over(core.partition)

    def hand_over(part: Partition) -> None:
        for to, h in part.due(part.f.done):
            svc.publish(f"radar/handover/{to}", handover_message(part.name, to, h))
        svc.gauges["handover"] = dict(part.counts)

    svc.subscribe("radar/etracks/*", on_etracks)
    if isinstance(core, Network) and core.partition is not None:
        partitioned(svc, core.partition, hand_over)
    return svc.run(at_end=lambda: publish(core.flush()))


def partitioned(svc: Service, part: Partition, hand_over: Callable[[Partition], None]) -> None:
    """The handover and claim subscriptions of partition `part` (module doc)."""

    def addressed(frm: str, to: str) -> None:
        if to != part.name or frm == part.name:
            raise Rejected("partition_mismatch", f"from {frm} to {to} at partition {part.name}")

    def on_handover(key: str, payload: bytes) -> None:
        frm, to, h = handed_of(payload)
        addressed(frm, to)
        part.adopt(h)
        svc.publish(f"radar/handover_ack/{frm}", handover_ack_message(part.name, frm, h.t,
                                                                       h.number))
        hand_over(part)

    def on_ack(key: str, payload: bytes) -> None:
        msg = protocol.decode("handover_ack", payload)
        addressed(msg["from"], msg["to"])
        part.acked(msg["id"])
        hand_over(part)

    def on_claims(key: str, payload: bytes) -> None:
        other = key.rsplit("/", 1)[-1]
        if other != part.name:
            part.claim(other, claimed_members(payload))

    svc.subscribe(f"radar/handover/{part.name}", on_handover)
    svc.subscribe(f"radar/handover_ack/{part.name}", on_ack)
    svc.subscribe("radar/gtracks/*", on_claims)
