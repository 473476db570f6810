"""The one role of global fusion (001 step 24) and its factory, as `common.sonar.trackers`
is for the bearing tracker: `FusionCore` (a base's elementary tracks in, at wall time
`now`; global tracks out; `flush` at the end of input) and `fusion_core`, which picks
the core from the bases (docs/networks.md, "Running a network"):

- every base measures azimuth and all share one receiver: 001's `GlobalFusion` behind
  its arrival rule (common.radar.fusion.arrival), unchanged;
- otherwise (several receivers, or a range-Doppler base): `NetworkFusion`
  (common.radar.network), which needs >= 3 bases over >= 2 receivers.

Nobody else branches on the deployment's kind. Pure.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from common.core.crossing import CrossingParams
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracks
from common.radar.fusion.arrival import Arrival
from common.radar.fusion.cycle import GlobalFusion
from common.radar.fusion.params import FusionParams
from common.radar.fusion.report import GlobalTracks
from common.radar.geometry.bistatic import BaseGeometry
from common.radar.network.fusion import NetworkFusion, NetworkReport
from common.radar.network.params import NetworkParams
from common.radar.network.partition import Partition


class FusionCore(Protocol):
    """Global fusion: `bases` the configured base ids; `push` raises
    common.core.rejection.Rejected for a report it refuses."""

    bases: tuple[str, ...]

    def push(self, base: str, tracks: ElementaryTracks, now: float) -> list[GlobalTracks]:
        """The report of a configured base, arrived at wall time `now` (s, any origin):
        the global tracks it completed."""
        ...

    def flush(self) -> list[GlobalTracks]:
        """End of input: the global tracks of everything still buffered."""
        ...


class SingleReceiver:
    """001's GlobalFusion behind its arrival rule; a cycle waits for its bases, so
    nothing is forced out at the end (`flush` gives nothing)."""

    def __init__(self, fusion: GlobalFusion) -> None:
        self.fusion = fusion
        self.arrival = Arrival(fusion)
        self.bases = tuple(fusion.base_ids)

    def push(self, base: str, tracks: ElementaryTracks, now: float) -> list[GlobalTracks]:
        return self.arrival.push(base, tracks, now)

    def flush(self) -> list[GlobalTracks]:
        return []


class Network:
    """NetworkFusion, driven by message time alone (`now` is not used). Its reports as
    GlobalTracks: score 0 and ambiguous false (it keeps no elementary scores and runs
    no crossing management, docs/protocol.md). With a `partition` name, that partition
    of [radar.network] partitions (common.radar.network.partition): its reports leave
    out the tracks it is handing over."""

    def __init__(self, bases: Sequence[BaseGeometry], params: NetworkParams,
                 tracker: ElementaryParams, partition: str | None = None) -> None:
        self.core = NetworkFusion(bases, params, tracker.sigma_gamma, tracker.sigma_omega)
        self.bases = tuple(b.id for b in bases)
        self.partition = Partition(self.core, params, partition) if partition else None

    def _tracks(self, r: NetworkReport) -> GlobalTracks:
        if self.partition is not None:
            r = self.partition.visible(r)
        n = r.id.size
        return GlobalTracks(r.t, self.bases, r.id, r.status, r.x, r.P, np.zeros(n), r.member,
                            r.has, np.zeros(n, dtype=bool))

    def push(self, base: str, tracks: ElementaryTracks, now: float) -> list[GlobalTracks]:
        return [self._tracks(r) for r in self.core.push(base, tracks.t, tracks)]

    def flush(self) -> list[GlobalTracks]:
        return [self._tracks(r) for r in self.core.flush()]


def fusion_core(bases: Sequence[BaseGeometry], fusion: FusionParams,
                crossing: CrossingParams | None, tracker: ElementaryParams,
                network: NetworkParams | None = None, partition: str | None = None
                ) -> FusionCore:
    """The core of a deployment (module doc). `fusion`, `crossing`: [radar.fusion],
    [radar.fusion_crossing] of 001's core; `network`: [radar.network] of the network
    core (its defaults when None); `tracker` ([radar.tracker]): the elementary
    trackers' Q [20], for the decorrelation of either core; `partition`: the partition
    of [radar.network] partitions to run (None: the whole plane; required when the
    table names partitions). Raises ValueError for bases neither core can fuse, or a
    partition missing, unknown, or given without partitions."""
    network = network or NetworkParams()
    if bool(partition) != bool(network.partitions):
        raise ValueError(f"[radar.network] partitions {list(network.partitions)}: "
                         + ("run one global fusion per partition (--partition NAME)"
                            if network.partitions else f"no partition {partition!r}"))
    rx = np.array([b.rx for b in bases], dtype=float).reshape(-1, 3)
    if all(b.azimuth for b in bases) and (not len(bases) or np.ptp(rx, axis=0).max() <= 1e-6):
        if partition:
            raise ValueError("partitions need the network core (several receivers or "
                             "range-Doppler bases)")
        return SingleReceiver(GlobalFusion(bases, fusion, crossing, tracker))
    receivers = np.unique(np.round(rx, 3), axis=0).shape[0]
    if len(bases) < 3 or receivers < 2:
        no_az = [b.id for b in bases if not b.azimuth]
        raise ValueError(f"global fusion needs >= 3 bases over >= 2 receivers (network fusion) "
                         f"or the azimuth of every base on one receiver (001 step 24); "
                         f"{len(bases)} bases over {receivers} receiver(s)"
                         + (f", {', '.join(no_az)} declared azimuth = false (range-Doppler)"
                            if no_az else ""))
    return Network(bases, network, tracker, partition)
