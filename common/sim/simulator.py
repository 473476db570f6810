"""Scenario simulator core: a deterministic generator of the typed scans of the 001 and
000 measurement models (common.wire.sim_messages turns them into wire messages).

Pure: no Zenoh, no clocks, no printing. :func:`scans` yields, for each scan time t of
scenario time (the sorted union of the radar and sonar scan times in [0, duration)),
the list of scans produced at t:

- :class:`RadarTruth`, then a :class:`RadarScan` per channel of every base scanning at t,
  at radar scan times (a base's own period and phase under [sim.radar.base.<id>], else
  the common scan_period; truth at the union of the bases' times);
- per array a :class:`SonarTruth` and a :class:`SonarScan`, at sonar scan times.

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
from dataclasses import dataclass

import numpy as np

from common.core.angles import wrap_2pi
from common.deploy.config import Config, ConfigError, RadarBase, SonarArray
from common.sim.mover import Mover
from common.sim.radar import radar_plots
from common.sim.scenario import Scenario, load_scenario
from common.sim.sonar import sonar_detections

__all__ = ["OwnShip", "RadarScan", "RadarTruth", "Scan", "SonarScan", "SonarTruth", "load_scenario",
           "repeated_scans", "scan_times", "scans"]


@dataclass(frozen=True)
class OwnShip:
    """Own-ship position (m), heading (rad) and speed (m/s) at a sonar scan."""

    x: float
    y: float
    heading: float
    speed: float


@dataclass(frozen=True)
class RadarTruth:
    """The radar targets present at a scan: ids (n,), positions and velocities (n, 3)."""

    t: float
    id: np.ndarray
    pos: np.ndarray
    vel: np.ndarray


@dataclass(frozen=True)
class RadarScan:
    """The 001 plots of one channel of one base: columns of common.sim.radar.COLUMNS."""

    t: float
    base: str
    channel: str
    plots: dict[str, np.ndarray]


@dataclass(frozen=True)
class SonarTruth:
    """The sonar targets present at a scan, seen from one array: ids (n,), positions and
    velocities (n, 3), true bearings (n,)."""

    t: float
    array: str
    own: OwnShip
    id: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    brg: np.ndarray


@dataclass(frozen=True)
class SonarScan:
    """The 000 detections of one array: columns brg, amp[, freq], sbrg."""

    t: float
    array: str
    own: OwnShip
    detections: dict[str, np.ndarray]


Scan = RadarTruth | RadarScan | SonarTruth | SonarScan


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


def _own(pos: np.ndarray, vel: np.ndarray, heading: float) -> OwnShip:
    return OwnShip(float(pos[0]), float(pos[1]), float(heading), float(np.hypot(vel[0], vel[1])))


def _check_ids(names: set[str], known: set[str], key: str) -> None:
    extra = sorted(names - known)
    if extra:
        raise ConfigError(f"{key}.{extra[0]}", "not in the deployment")


def scans(
    scn: Scenario,
    bases: list[RadarBase],
    arrays: list[SonarArray],
    seed: int,
    n_scans: int | None = None,
) -> Iterator[tuple[float, list[Scan]]]:
    """Yield (t, scans) per scan time; at most n_scans steps."""
    steps: dict[float, list[tuple[str, int]]] = {}
    radar, sonar = scn.radar, scn.sonar
    if radar is not None:
        _check_ids(set(radar.channels), {c for b in bases for c in b.channels}, "sim.radar.channel")
        _check_ids(set(radar.timing), {b.id for b in bases}, "sim.radar.base")
        own_t = {b.id: np.round(radar.base_times(b.id, scn.duration), 9) for b in bases}
        tr = (np.unique(np.concatenate(list(own_t.values()))) if radar.timing
              else scan_times(scn.duration, radar.scan_period))
        scanning = {b: set(v.tolist()) for b, v in own_t.items()}
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

    def rng(key: str) -> np.random.Generator:
        return rngs.setdefault(key, _rng(seed, key))

    for i, t in enumerate(sorted(steps)):
        if n_scans is not None and i >= n_scans:
            return
        out: list[Scan] = []
        for sensor, k in steps[t]:
            if sensor == "radar":
                on = ra[:, k]
                p, v = rp[on, k], rv[on, k]
                out.append(RadarTruth(t, rid[on], p, v))
                for b in (b for b in bases if t in scanning[b.id]):
                    for c in b.channels:
                        key = f"radar/plots/{b.id}/{c}"
                        out.append(RadarScan(t, b.id, c, radar_plots(p, v, b, radar.channel(c), radar, rng(key))))
            else:
                on = sa[:, k]
                p, v = sp[on, k], sv[on, k]
                own = _own(own_p[k], own_v[k], own_h[k])
                d = p[:, :2] - own_p[k, :2]
                brg = wrap_2pi(np.arctan2(d[:, 0], d[:, 1]))
                for arr in arrays:
                    out.append(SonarTruth(t, arr.id, own, sid[on], p, v, brg))
                    key = f"sonar/detections/{arr.id}"
                    cols = sonar_detections(own_p[k], own_v[k], float(own_h[k]), p, v, sl[on],
                                            [lines[j] for j in np.flatnonzero(on)], arr,
                                            sonar.array(arr.id), sonar, rng(key))
                    out.append(SonarScan(t, arr.id, own, cols))
        yield t, out


def repeated_scans(scn: Scenario, cfg: Config, seed: int, n_scans: int | None, repeat: int,
                   gap: float) -> Iterator[tuple[float, list[Scan]]]:
    """`repeat` runs of :func:`scans` back to back in scenario time, each followed by
    `gap` seconds of the scenario without targets. ``cfg`` is the deployment (its bases
    and arrays)."""
    empty = dataclasses.replace(
        scn, duration=gap,
        radar=None if scn.radar is None else dataclasses.replace(scn.radar, targets=[]),
        sonar=None if scn.sonar is None else dataclasses.replace(scn.sonar, targets=[]))
    for i in range(repeat):
        offset = i * (scn.duration + gap)
        parts = [(0.0, scans(scn, cfg.bases, cfg.arrays, seed + i, n_scans))]
        if gap > 0:
            parts.append((scn.duration, scans(empty, cfg.bases, cfg.arrays, seed + i)))
        for shift, steps in parts:
            for t, out in steps:
                t_run = t + shift + offset
                yield t_run, [dataclasses.replace(s, t=t_run) for s in out]
