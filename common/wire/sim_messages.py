"""The simulator's messages (docs/protocol.md): builders from the typed scans of
common.sim.simulator (001 plots, 000 detections, ground truth), each with the protocol
VERSION and, for plots and detections, a ``seq`` per key; and the truth parser."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict
from typing import Any

import numpy as np

from common.deploy.config import Config, RadarBase, SonarArray
from common.sim.scenario import Scenario
from common.sim.simulator import RadarScan, RadarTruth, Scan, SonarTruth, repeated_scans, scans
from common.wire import protocol

Message = tuple[str, dict[str, Any]]


def run_scenario(scn: Scenario, bases: list[RadarBase], arrays: list[SonarArray], seed: int,
                 n_scans: int | None = None) -> Iterator[tuple[float, list[Message]]]:
    """Yield (t, [(key suffix, message)]) per scan time of common.sim.simulator.scans."""
    return stamped(scans(scn, bases, arrays, seed, n_scans))


def repeated(scn: Scenario, cfg: Config, seed: int, n_scans: int | None, repeat: int,
             gap: float) -> Iterator[tuple[float, list[Message]]]:
    """The messages of common.sim.simulator.repeated_scans, seq numbered across runs."""
    return stamped(repeated_scans(scn, cfg, seed, n_scans, repeat, gap))


def stamped(steps: Iterator[tuple[float, list[Scan]]]) -> Iterator[tuple[float, list[Message]]]:
    """(t, messages) of every (t, scans); seq counts each key's messages from 0."""
    seqs: dict[str, int] = {}
    for t, out in steps:
        yield t, [_message(s, seqs) for s in out]


def _message(s: Scan, seqs: dict[str, int]) -> Message:
    """(key suffix, message) of one scan."""
    if isinstance(s, RadarTruth):
        return "sim/truth/radar", {
            "v": protocol.VERSION, "t": s.t, "id": s.id.tolist(),
            **{c: s.pos[:, j].tolist() for j, c in enumerate("xyz")},
            **{f"v{c}": s.vel[:, j].tolist() for j, c in enumerate("xyz")},
        }
    if isinstance(s, SonarTruth):
        return "sim/truth/sonar", {
            "v": protocol.VERSION, "t": s.t, "array": s.array, "own": asdict(s.own), "id": s.id.tolist(),
            "x": s.pos[:, 0].tolist(), "y": s.pos[:, 1].tolist(),
            "vx": s.vel[:, 0].tolist(), "vy": s.vel[:, 1].tolist(), "brg": s.brg.tolist(),
        }
    head: dict[str, Any]
    if isinstance(s, RadarScan):
        key, head, cols = f"radar/plots/{s.base}/{s.channel}", {"base": s.base, "channel": s.channel}, s.plots
    else:
        key, head, cols = f"sonar/detections/{s.array}", {"array": s.array, "own": asdict(s.own)}, s.detections
    seqs[key] = seqs.get(key, -1) + 1
    return key, {"v": protocol.VERSION, "t": s.t, "seq": seqs[key], **head,
                 **{n: a.tolist() for n, a in cols.items()}}


def truth_state(m: dict[str, Any]) -> np.ndarray:
    """Truth states (n, 6) [x vx y vy z vz] of a sim/truth/radar message."""
    return np.column_stack([m["x"], m["vx"], m["y"], m["vy"], m["z"], m["vz"]])
