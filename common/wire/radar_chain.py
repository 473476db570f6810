"""The radar chain of 001 (modules 31-34, 41-44, 61-65) in one process, on message dicts.

The services `channel-plotter`, `elementary-tracker` and `global-fusion` are thin
shells around the same cores and build their messages with the functions below, so a
chain run here gives what the processes publish for the same input (given the same
per-scan grouping; tests/integration/test_global_integration.py compares the two). Used for Monte Carlo
studies (many seeds in seconds), benchmarks and the consistency tests of the global
covariance. No I/O, no clock.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from common.wire import protocol
from common.deploy.config import Config, section
from common.core.crossing import CrossingParams
from common.radar.elementary import ElementaryParams, ElementaryTracker, ElementaryTracks, RadarCrossingParams
from common.radar.global_fusion import FusionParams, GlobalFusion
from common.radar.plot_fusion import PlotFusion, PlotterParams, Plots
from common.core.track_table import STATUS_NAME, Status

def fused_message(base: str, t: float, fused: Plots) -> dict[str, Any]:
    """The `radar/fused/<base>` message of one scan."""
    return {"v": protocol.VERSION, "t": t, "base": base,
            "rb": fused.rb, "vb": fused.vb, "az": fused.az,
            "srb": fused.srb, "svb": fused.svb, "saz": fused.saz, "n_ch": fused.n_ch}


def etracks_message(base: str, tracks: ElementaryTracks) -> dict[str, Any]:
    """The `radar/etracks/<base>` message of one scan (every live track)."""
    return {
        "v": protocol.VERSION, "t": tracks.t, "base": base,
        "tracks": [
            {"id": int(tracks.id[k]), "status": STATUS_NAME[Status(int(tracks.status[k]))],
             "x": tracks.x[k], "P": tracks.P[k].ravel(), "score": float(tracks.score[k]),
             "n_ch": int(tracks.n_ch[k]), "updated": bool(tracks.updated[k]),
             "ambiguous": bool(tracks.ambiguous[k])}
            for k in range(len(tracks))
        ],
    }


def plots_of(msg: dict[str, Any]) -> Plots:
    """Plots of a `plots` or `fused` message, decoded or as built (n_ch only in the
    latter)."""
    cols = [np.asarray(msg[k], dtype=float) for k in ("rb", "vb", "az", "srb", "svb", "saz")]
    return (Plots(*cols, np.asarray(msg["n_ch"], dtype=np.int64)) if "n_ch" in msg
            else Plots(*cols))


def global_fusion(cfg: Config) -> GlobalFusion:
    """The global fusion core of a deployment: [radar.fusion], [radar.fusion_crossing]
    (the sup-norm test of 004 when absent) and [radar.tracker] (for the decorrelation).
    Raises ValueError if the bases cannot be fused (fewer than 2, several receivers)."""
    crossing = (section(cfg, "radar.fusion_crossing", CrossingParams)
                if "fusion_crossing" in cfg.doc.get("radar", {}) else None)
    return GlobalFusion(cfg.bases, section(cfg, "radar.fusion", FusionParams), crossing,
                        section(cfg, "radar.tracker", ElementaryParams))


class RadarChain:
    """One channel plotter and one elementary tracker per base, and global fusion."""

    def __init__(self, cfg: Config) -> None:
        plotter = section(cfg, "radar.plotter", PlotterParams)
        tracker = section(cfg, "radar.tracker", ElementaryParams)
        crossing = section(cfg, "radar.crossing", RadarCrossingParams)
        self.plotters = {b.id: PlotFusion(b.channels, b.p, plotter) for b in cfg.bases}
        self.trackers = {b.id: ElementaryTracker(tracker, crossing) for b in cfg.bases}
        self.fusion = global_fusion(cfg)

    def step(self, messages: Iterable[tuple[str, dict[str, Any]]]) -> list[dict[str, Any]]:
        """Feed one scan's simulator messages (key suffix, message); `radar/plots/...`
        are used, others ignored. Returns the gtracks messages of the cycles completed."""
        out = []
        for key, msg in messages:
            if not key.startswith("radar/plots/"):
                continue
            base = msg["base"]
            for t, fused in self.plotters[base].push(msg["channel"], msg["t"], plots_of(msg)):
                tracks = self.trackers[base].step(t, fused)
                out += self.fusion.push(etracks_message(base, tracks))
        return out
