"""Partitioned global fusion in one process (tests/radar/test_network_partition.py,
benchmarks/network_partition.py): every report pushed to every partition, then each due
handover adopted and acked and each partition's members claimed by the others, as the
services do over Zenoh (services/global_fusion)."""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from common.radar.network.fusion import NetworkFusion, NetworkReport
from common.radar.network.params import NetworkParams
from common.radar.network.partition import Partition
from tests.radar import network_scene as ns


def union(reports: list[NetworkReport]) -> NetworkReport:
    """The tracks of the partitions' reports of one time, as one report."""
    assert len({r.t for r in reports}) == 1
    return dataclasses.replace(reports[0], id=np.concatenate([r.id for r in reports]),
                               status=np.concatenate([r.status for r in reports]),
                               x=np.concatenate([r.x for r in reports]),
                               P=np.concatenate([r.P for r in reports]))


def exchange(parts: dict[str, Partition]) -> None:
    """Every due handover adopted and acked; every partition's members claimed."""
    for part in parts.values():
        for to, h in part.due(part.f.done):
            parts[to].adopt(h)
            part.acked(h.number)
    for part in parts.values():
        for other in parts.values():
            part.claim(other.name, [(other.f.ids[b], e) for b, e in other.f.tracks.owner])


def run(scene: ns.Scene, params: NetworkParams
        ) -> tuple[list[NetworkReport], dict[str, Partition], dict[str, float]]:
    """The union of the partitions' reports, the partitions, and each one's CPU seconds
    (process time of its pushes, handovers and claims)."""
    parts = {n: Partition(NetworkFusion(scene.bases, params), params, n)
             for n in params.partitions}
    outs: dict[str, list[NetworkReport]] = {n: [] for n in parts}
    cpu = dict.fromkeys(parts, 0.0)
    for b, t, rep in scene.reports:
        for n, part in parts.items():
            c = time.process_time()
            outs[n] += [part.visible(r) for r in part.f.push(scene.bases[b].id, t, rep)]
            cpu[n] += time.process_time() - c
        c = time.process_time()
        exchange(parts)
        for n in parts:
            cpu[n] += (time.process_time() - c) / len(parts)
    for n, part in parts.items():
        outs[n] += part.f.flush()
    return [union(list(rs)) for rs in zip(*outs.values(), strict=True)], parts, cpu
