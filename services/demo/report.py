"""The demo's metrics tables: global radar tracks against truth (GOSPA, number
switches, position RMSE) and TMA solutions against truth (range, course, speed)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from common.angles import wrap_pi
from common.config import Config
from common.metrics import MetricsAccumulator

Msg = dict[str, Any]
GOSPA_C_M = 2000.0
KNOT = 0.514444


@dataclass
class Collected:
    """Decoded messages of a run, by message kind."""

    radar_cfg: Config
    sonar_cfg: Config
    by_kind: dict[str, list[Msg]]

    def of(self, kind: str) -> list[Msg]:
        return self.by_kind.get(kind, [])


def confirmed_positions(msg: Msg) -> tuple[np.ndarray, np.ndarray]:
    """Ids and (x, y, z) of the confirmed global tracks of one gtracks message."""
    trs = [tr for tr in msg["tracks"] if tr["status"] == "confirmed"]
    ids = np.array([tr["id"] for tr in trs], dtype=int)
    pos = np.array([[tr["x"][0], tr["x"][2], tr["x"][4]] for tr in trs]).reshape(-1, 3)
    return ids, pos


def radar_metrics(data: Collected) -> MetricsAccumulator | None:
    """GOSPA (c = 2 km, p = 2, switching penalty c) of confirmed global tracks."""
    truth = {round(m["t"], 6): m for m in data.of("truth_radar")}
    acc = MetricsAccumulator(GOSPA_C_M, 2.0, GOSPA_C_M)
    for m in data.of("gtracks"):
        tm = truth.get(round(m["t"], 6))
        if tm is None:
            continue
        ids, pos = confirmed_positions(m)
        tpos = np.column_stack([tm["x"], tm["y"], tm["z"]])
        acc.add(m["t"], np.asarray(tm["id"]), tpos, ids, pos)
    return acc if data.of("gtracks") else None


def radar_table(data: Collected) -> str:
    acc = radar_metrics(data)
    if acc is None:
        return "radar: no global tracks (global fusion not running)"
    s = acc.summary()
    lines = [
        "radar (global tracks vs truth, GOSPA c=2 km p=2)",
        f"  scans scored {s.steps}, mean GOSPA {s.mean_gospa:.0f} m, mean OSPA {s.mean_ospa:.0f} m",
        f"  number switches {s.switches}, track breaks {s.breaks}",
    ]
    for tid, r in sorted(s.rmse.items()):
        lines.append(f"  target {tid}: position RMSE {r:.0f} m")
    return "\n".join(lines)


def tma_errors(data: Collected) -> list[tuple[int, int, float, float, float, float]]:
    """Per TMA track (last solution): matched truth id, true range, range error (m),
    course error (deg), speed error (kn); matched by bearing from own ship."""
    truth = {round(m["t"], 6): m for m in data.of("truth_sonar")}
    final: dict[int, tuple[Msg, Msg]] = {}
    for m in data.of("tma"):
        tm = truth.get(round(m["t"], 6))
        if tm is None:
            continue
        for s in m["solutions"]:
            final[s["track"]] = (s, tm)
    rows = []
    for track, (s, tm) in sorted(final.items()):
        own = np.array([tm["own"]["x"], tm["own"]["y"]])
        brg_s = np.arctan2(s["x"] - own[0], s["y"] - own[1])
        k = int(np.argmin(np.abs(wrap_pi(np.asarray(tm["brg"]) - brg_s))))
        dx, dy = tm["x"][k] - own[0], tm["y"][k] - own[1]
        rng = float(np.hypot(dx, dy))
        course = np.arctan2(tm["vx"][k], tm["vy"][k])
        speed = float(np.hypot(tm["vx"][k], tm["vy"][k]))
        rows.append((track, int(tm["id"][k]), rng, s["range"] - rng,
                     float(np.degrees(wrap_pi(s["course"] - course))), (s["speed"] - speed) / KNOT))
    return rows


def sonar_table(data: Collected) -> str:
    btracks = data.of("btracks")
    n_conf = len({tr["id"] for m in btracks for tr in m["tracks"] if tr["status"] == "confirmed"})
    lines = [f"sonar: {len(btracks)} bearing-tracker cycles, {n_conf} confirmed bearing tracks"]
    rows = tma_errors(data)
    if not rows:
        lines.append("  no TMA solutions (tma service not running)")
        return "\n".join(lines)
    lines.append(f"  {'track':>5} {'target':>6} {'range km':>9} {'d range m':>10} "
                 f"{'d course deg':>13} {'d speed kn':>11}")
    for track, tid, rng, dr, dc, dv in rows:
        lines.append(f"  {track:>5} {tid:>6} {rng / 1e3:>9.2f} {dr:>10.0f} {dc:>13.1f} {dv:>11.2f}")
    return "\n".join(lines)
