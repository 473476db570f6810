"""The demo's metrics tables: global radar tracks against truth (GOSPA, number
switches, position RMSE against the PCRLB, NEES) and TMA solutions against truth (range,
course, speed)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from common.core.angles import wrap_pi
from common.deploy.config import Config
from common.evaluation.pcrlb import Evaluation
from common.wire.sim_messages import truth_state
from services.evaluate.main import report

Msg = dict[str, Any]
GOSPA_C_M = 2000.0
KNOT = 0.514444
SETTLE_S = 20.0


@dataclass
class Collected:
    """Decoded messages of a run, by message kind."""

    radar_cfg: Config
    sonar_cfg: Config
    by_kind: dict[str, list[Msg]]

    def of(self, kind: str) -> list[Msg]:
        return self.by_kind.get(kind, [])


def radar_table(data: Collected) -> str:
    """The table of ``pfusion evaluate`` (GOSPA, switches, breaks, RMSE vs PCRLB, NEES)
    for the confirmed global tracks against truth."""
    if not data.of("gtracks"):
        return "radar: no global tracks (global fusion not running)"
    ev = Evaluation(c=GOSPA_C_M, gamma=GOSPA_C_M)
    truth = {round(m["t"], 6): m for m in data.of("truth_radar")}
    for g in data.of("gtracks"):
        m = truth.get(round(g["t"], 6))
        if m is None:
            continue
        conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
        ev.add(g["t"], m["id"], truth_state(m),
               np.array([k["id"] for k in conf], dtype=np.int64),
               np.array([k["x"] for k in conf], dtype=float).reshape(-1, 6),
               np.array([k["P"] for k in conf], dtype=float).reshape(-1, 6, 6))
    return "radar (confirmed global tracks vs truth, GOSPA c=2 km p=2)\n" + report(
        ev, data.radar_cfg, SETTLE_S)


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
