"""Scenario simulator core: a deterministic generator of wire-protocol v1 messages.

Pure: no Zenoh, no clocks, no printing. :func:`run_scenario` yields, for each scan time
t of scenario time (the sorted union of the radar and sonar scan times in
[0, duration)), the list of (key suffix, message) produced at t:

- ``sim/truth/radar`` and ``radar/plots/<base>/<channel>`` at radar scan times;
- ``sim/truth/sonar`` (one per array) and ``sonar/detections/<array>`` at sonar
  scan times.

In a geodetic deployment (scn.origin set) a radar target's mover runs in the tangent
plane with z its ellipsoidal height; each position is re-projected along the vertical to
that height (common.radar.geometry.geodesy.LocalFrame.lift_motion), the velocity is the
derivative of that path, and both the truth and the plots use the ENU result.

Each key draws from its own numpy Generator seeded by ``[seed, crc32(key)]``, so a run
is reproducible for a seed and adding a base does not change another base's plots.
"""

from __future__ import annotations

import dataclasses
import zlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from common.core.angles import wrap_2pi
from common.deploy.config import Config, ConfigError, RadarBase, SonarArray
from common.sim.mover import Mover
from common.sim.radar import radar_plots
from common.sim.scenario import Scenario, load_scenario
from common.sim.sonar import sonar_detections

__all__ = ["load_scenario", "repeated", "run_scenario", "scan_times"]

Message = tuple[str, dict[str, Any]]


def scan_times(duration: float, period: float) -> np.ndarray:
    """Scan times k * period in [0, duration)."""
    return np.arange(int(np.ceil(duration / period - 1e-9))) * period


def _rng(seed: int, key: str) -> np.random.Generator:
    return np.random.default_rng([seed, zlib.crc32(key.encode())])


def _truth(movers: list[Mover], t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Stacked positions (M, T, 3), velocities (M, T, 3), presence (M, T), ids (M,)."""
    if not movers:
        empty = np.zeros((0, len(t), 3))
        return empty, empty, np.zeros((0, len(t)), bool), np.zeros(0, int)
    pos, vel, alive = zip(*(m.states(t) for m in movers))
    return np.stack(pos), np.stack(vel), np.stack(alive), np.array([m.id for m in movers])


def _own(pos: np.ndarray, vel: np.ndarray, heading: float) -> dict[str, float]:
    return {"x": float(pos[0]), "y": float(pos[1]), "heading": float(heading),
            "speed": float(np.hypot(vel[0], vel[1]))}


def _check_ids(names: set[str], known: set[str], key: str) -> None:
    extra = sorted(names - known)
    if extra:
        raise ConfigError(f"{key}.{extra[0]}", "not in the deployment")


def run_scenario(
    scn: Scenario,
    bases: list[RadarBase],
    arrays: list[SonarArray],
    seed: int,
    n_scans: int | None = None,
) -> Iterator[tuple[float, list[Message]]]:
    """Yield (t, [(key suffix, message)]) per scan time; at most n_scans steps."""
    steps: dict[float, list[tuple[str, int]]] = {}
    radar, sonar = scn.radar, scn.sonar
    if radar is not None:
        _check_ids(set(radar.channels), {c for b in bases for c in b.channels}, "sim.radar.channel")
        tr = scan_times(scn.duration, radar.scan_period)
        rp, rv, ra, rid = _truth(radar.targets, tr)
        if scn.origin is not None:  # [x, y, ellipsoidal height] -> ENU (docstring)
            rp, rv = scn.origin.lift_motion(rp, rv)
        for k, t in enumerate(tr):
            steps.setdefault(round(float(t), 9), []).append(("radar", k))
    if sonar is not None:
        _check_ids(set(sonar.arrays), {a.id for a in arrays}, "sim.sonar.array")
        ts = scan_times(scn.duration, sonar.scan_period)
        own_p, own_v, _ = sonar.own.states(ts)
        own_h = sonar.own.headings(ts)
        sp, sv, sa, sid = _truth(sonar.targets, ts)
        sl = np.array([m.sl_db for m in sonar.targets], dtype=float)
        lines = [m.lines_hz for m in sonar.targets]
        for k, t in enumerate(ts):
            steps.setdefault(round(float(t), 9), []).append(("sonar", k))
    rngs: dict[str, np.random.Generator] = {}
    seqs: dict[str, int] = {}

    def stamp(key: str, msg: dict[str, Any]) -> Message:
        seqs[key] = seqs.get(key, -1) + 1
        return key, {"v": 1, "t": msg.pop("t"), "seq": seqs[key], **msg}

    def rng(key: str) -> np.random.Generator:
        return rngs.setdefault(key, _rng(seed, key))

    for i, t in enumerate(sorted(steps)):
        if n_scans is not None and i >= n_scans:
            return
        out: list[Message] = []
        for sensor, k in steps[t]:
            if sensor == "radar":
                on = ra[:, k]
                p, v = rp[on, k], rv[on, k]
                out.append(("sim/truth/radar", {
                    "v": 1, "t": t, "id": rid[on].tolist(),
                    **{c: p[:, j].tolist() for j, c in enumerate("xyz")},
                    **{f"v{c}": v[:, j].tolist() for j, c in enumerate("xyz")},
                }))
                for b in bases:
                    for c in b.channels:
                        key = f"radar/plots/{b.id}/{c}"
                        cols = radar_plots(p, v, b, radar.channel(c), radar, rng(key))
                        out.append(stamp(key, {"t": t, "base": b.id, "channel": c,
                                               **{n: a.tolist() for n, a in cols.items()}}))
            else:
                on = sa[:, k]
                p, v = sp[on, k], sv[on, k]
                own = _own(own_p[k], own_v[k], own_h[k])
                d = p[:, :2] - own_p[k, :2]
                brg = wrap_2pi(np.arctan2(d[:, 0], d[:, 1]))
                for arr in arrays:
                    out.append(("sim/truth/sonar", {
                        "v": 1, "t": t, "array": arr.id, "own": dict(own), "id": sid[on].tolist(),
                        "x": p[:, 0].tolist(), "y": p[:, 1].tolist(),
                        "vx": v[:, 0].tolist(), "vy": v[:, 1].tolist(), "brg": brg.tolist(),
                    }))
                    key = f"sonar/detections/{arr.id}"
                    cols = sonar_detections(own_p[k], own_v[k], float(own_h[k]), p, v, sl[on],
                                            [lines[j] for j in np.flatnonzero(on)], arr,
                                            sonar.array(arr.id), sonar, rng(key))
                    out.append(stamp(key, {"t": t, "array": arr.id, "own": dict(own),
                                           **{n: a.tolist() for n, a in cols.items()}}))
        yield t, out


def repeated(scn: Scenario, cfg: Config, seed: int, n_scans: int | None, repeat: int,
             gap: float) -> Iterator[tuple[float, list[Message]]]:
    """`repeat` runs of run_scenario back to back in scenario time, each followed by
    `gap` seconds of the scenario without targets; seq renumbered per key. ``cfg`` is the
    deployment (its bases and arrays)."""
    empty = dataclasses.replace(
        scn, duration=gap,
        radar=None if scn.radar is None else dataclasses.replace(scn.radar, targets=[]),
        sonar=None if scn.sonar is None else dataclasses.replace(scn.sonar, targets=[]))
    seqs: dict[str, int] = {}
    for i in range(repeat):
        offset = i * (scn.duration + gap)
        parts = [(0.0, run_scenario(scn, cfg.bases, cfg.arrays, seed + i, n_scans))]
        if gap > 0:
            parts.append((scn.duration, run_scenario(empty, cfg.bases, cfg.arrays, seed + i)))
        for shift, steps in parts:
            for t, messages in steps:
                t_run = t + shift + offset
                for key, msg in messages:
                    msg["t"] = t_run
                    if "seq" in msg:
                        msg["seq"] = seqs[key] = seqs.get(key, -1) + 1
                yield t_run, messages
