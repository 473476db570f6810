"""The radar chain of 001 (modules 31-34, 41-44, 61-65), or of a network (global fusion
by common.radar.network, picked by common.radar.fusion_core), in one process, on message
dicts.

The services `channel-plotter`, `elementary-tracker` and `global-fusion` are thin
shells around the same cores and build their messages with common.wire.radar_messages, so a
chain run here gives what the processes publish for the same input (given the same
per-scan grouping; tests/integration/test_global_integration.py compares the two). Used for Monte Carlo
studies (many seeds in seconds), benchmarks and the consistency tests of the global
covariance. No I/O, no clock: 001's arrival rule (common.radar.fusion.arrival)
takes each report's message time as its wall time, a real-time run without latency. Every
base reports every scan, so with scans shorter than `max_wait` no base goes stale and no
report is rejected: the rule changes nothing here.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from common.deploy.config import Config, section
from common.radar.elementary.model import model_of
from common.radar.elementary.tracker import ElementaryParams, ElementaryTracker, RadarCrossingParams
from common.radar.fusion.params import FusionCrossingParams, FusionParams
from common.radar.fusion_core import FusionCore, fusion_core
from common.radar.network.params import NetworkParams
from common.radar.plots.channel_fusion import PlotFusion, PlotterParams
from common.wire.radar_messages import gtracks_message, plots_of


def global_fusion(cfg: Config, partition: str | None = None) -> FusionCore:
    """The global fusion core of a deployment (common.radar.fusion_core.fusion_core):
    [radar.fusion], [radar.fusion_crossing] (the sup-norm test of 004 when absent),
    [radar.network] (a network's fusion centre) and [radar.tracker] (for the
    decorrelation); `partition`: the partition of [radar.network] partitions to run.
    Raises ValueError if the bases cannot be fused or the partition is wrong."""
    crossing = (section(cfg, "radar.fusion_crossing", FusionCrossingParams)
                if "fusion_crossing" in cfg.doc.get("radar", {}) else None)
    return fusion_core(cfg.bases, section(cfg, "radar.fusion", FusionParams), crossing,
                       section(cfg, "radar.tracker", ElementaryParams),
                       section(cfg, "radar.network", NetworkParams), partition)


class RadarChain:
    """One channel plotter and one elementary tracker per base, and global fusion;
    `flush` at the end of input."""

    def __init__(self, cfg: Config) -> None:
        plotter = section(cfg, "radar.plotter", PlotterParams)
        tracker = section(cfg, "radar.tracker", ElementaryParams)
        crossing = section(cfg, "radar.crossing", RadarCrossingParams)
        self.azimuth = {b.id: b.azimuth for b in cfg.bases}
        self.plotters = {b.id: PlotFusion(b.channels, b.p, plotter, b.azimuth) for b in cfg.bases}
        self.trackers = {b.id: ElementaryTracker(tracker, crossing, model_of(b.azimuth))
                         for b in cfg.bases}
        self.fusion = global_fusion(cfg)
        self.origin = cfg.origin

    def step(self, messages: Iterable[tuple[str, dict[str, Any]]]) -> list[dict[str, Any]]:
        """Feed one scan's simulator messages (key suffix, message); `radar/plots/...`
        are used, others ignored. Returns the gtracks messages of the cycles completed."""
        out = []
        for key, msg in messages:
            if not key.startswith("radar/plots/"):
                continue
            base = msg["base"]
            plots = plots_of(msg, self.azimuth[base])
            for t, fused in self.plotters[base].push(msg["channel"], msg["t"], plots):
                tracks = self.trackers[base].step(t, fused)
                out += [gtracks_message(g, self.origin) for g in self.fusion.push(base, tracks, t)]
        return out

    def flush(self) -> list[dict[str, Any]]:
        """End of input: the gtracks messages of what global fusion still buffers."""
        return [gtracks_message(g, self.origin) for g in self.fusion.flush()]
