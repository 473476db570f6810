"""Benchmark of the TMA service glue (common.sonar.tma.manager) with the 002/003 cores: 50
confirmed tracks, one btracks message per 20 s for one hour of message time.

Run: .venv/bin/python benchmarks/tma_service.py

Own ship 3 m/s North, turning East at 900 s and back North at 2100 s; 50 targets at
4-15 km, 1-8 m/s, bearing sigma 1 deg. Prints TMA solutions (cycles) per second of wall
time and the real-time factor (message time / wall time); real time for 50 tracks needs
50 / cycle_dt solutions per second.
"""

from __future__ import annotations

import time

import numpy as np

from common.core.angles import wrap_2pi
from common.sonar.tma.bounds import MINIMAL_BOUNDS, Bounds
from common.sonar.tma.manager import TmaManager, TmaParams
from common.wire.sonar_messages import btracks_from, tma_message

N_TRACKS = 50
PERIOD = 20.0
DURATION = 3600.0
SIG = np.radians(1.0)
WRONG = Bounds(500.0, 3000.0, 0.0, np.pi, 0.5, 2.0)


def own_at(t: np.ndarray) -> np.ndarray:
    """Own-ship positions (N, 2) on the three legs."""
    leg = np.stack((np.zeros_like(t), 3.0 * t), 1)
    leg[t > 900] = np.stack((3.0 * (t[t > 900] - 900), np.full((t > 900).sum(), 2700.0)), 1)
    late = t > 2100
    leg[late] = np.stack((np.full(late.sum(), 3600.0), 2700.0 + 3.0 * (t[late] - 2100)), 1)
    return leg


def messages(seed: int = 0) -> list[tuple[float, np.ndarray, list[dict]]]:
    """(t, own xy, btracks message) every PERIOD seconds."""
    rng = np.random.default_rng(seed)
    r, b = rng.uniform(4e3, 15e3, N_TRACKS), rng.uniform(0, 2 * np.pi, N_TRACKS)
    v, k = rng.uniform(1.0, 8.0, N_TRACKS), rng.uniform(0, 2 * np.pi, N_TRACKS)
    p0 = np.stack((r * np.sin(b), r * np.cos(b)), 1)
    vel = np.stack((v * np.sin(k), v * np.cos(k)), 1)
    times = np.arange(0.0, DURATION, PERIOD)
    own = own_at(times)
    P = [SIG**2] + [0.0] * 15
    out = []
    for i, t in enumerate(times):
        d = p0 + vel * t - own[i]
        brg = wrap_2pi(np.arctan2(d[:, 0], d[:, 1]) + SIG * rng.standard_normal(N_TRACKS))
        tracks = [{"id": j, "status": "confirmed", "x": [float(brg[j]), 0.0, 20.0, 0.0], "P": P,
                   "quality": 5.0, "ambiguous": False} for j in range(N_TRACKS)]
        out.append((float(t), own[i], {"v": 1, "t": float(t), "array": "a1", "tracks": tracks}))
    return out


def run(cycle_dt: float, bounds: Bounds) -> tuple[float, float, int]:
    """Solutions per second, real-time factor and number of TMA cycles."""
    data = messages()
    mgr = TmaManager("a1", TmaParams(cycle_dt=cycle_dt), bounds)
    t0 = time.perf_counter()
    for t, own, msg in data:
        mgr.add_own(t, float(own[0]), float(own[1]))
        mgr.push(btracks_from(msg))
        for m in mgr.ready()[0]:
            tma_message(mgr.step(m, {}))
    wall = time.perf_counter() - t0
    return mgr.cycles / wall, DURATION / wall, mgr.cycles


def main() -> None:
    print(f"{'case (50 tracks, 1 h, 20 s btracks)':<46}{'solutions/s':>12}{'x real time':>12}{'cycles':>8}")
    for name, bounds, cycle_dt in (("minimal bounds", MINIMAL_BOUNDS, 60.0), ("minimal bounds", MINIMAL_BOUNDS, 20.0),
                                   ("wrong bounds (CTMA)", WRONG, 60.0)):
        sps, rt, n = run(cycle_dt, bounds)
        print(f"{f'{name}, cycle_dt {cycle_dt:.0f} s':<46}{sps:>12.0f}{rt:>12.1f}{n:>8d}")


if __name__ == "__main__":
    main()
