"""``pfusion evaluate`` against the real chain (router, simulator, plotters, elementary
trackers, global fusion, evaluate: each its own process): the table it prints must
match a direct computation (common.evaluation.pcrlb / common.evaluation.metrics) on the gtracks and truth
the test collected itself."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from common.bus.procs import Child
from common.deploy.config import load, section
from common.evaluation.metrics import count_switches
from common.evaluation.pcrlb import Evaluation, base_information, score_targets
from common.radar.fusion.params import FusionParams
from common.sim.scenario import radar_scene
from tests.harness import SCENARIOS, Deployment

SETTLE = 20.0
ROW = re.compile(r"^\s*(\d+)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)$")


def test_evaluate_table_matches_direct_computation(tmp_path: Path) -> None:
    scn = SCENARIOS / "two_targets.toml"
    cfg = load(scn)
    bases = [b.id for b in cfg.bases]
    out_path = tmp_path / "evaluate.out"
    with Deployment(tmp_path) as d, open(out_path, "wb") as out:
        d.collect("radar/gtracks")
        d.collect("sim/truth/radar")
        ev_proc = Child("evaluate", "evaluate", "--config", str(scn), "--settle", str(SETTLE),
                        "--connect", d.endpoint, log=tmp_path / "evaluate.log", stdout=out)
        d.children.append(ev_proc)
        for b in bases:
            d.start(f"plotter-{b}", "channel-plotter", "--config", str(scn), "--base", b)
            d.start(f"tracker-{b}", "elementary-tracker", "--config", str(scn), "--base", b)
        d.start("fusion", "global-fusion", "--config", str(scn))
        alive = [f"{s}/{b}" for b in bases for s in ("channel_plotter", "elementary_tracker")]
        alive += ["global_fusion/main", "evaluate/main"]
        d.wait_alive(alive)
        d.simulate(scn, seed=1, wait_alive=alive)
        assert ev_proc.wait(60.0) == 0  # stops by itself after sim/status "done"
        d.drain()
        gtracks = {m["t"]: m for m in d.of("radar/gtracks")}
        truth = sorted(d.of("sim/truth/radar"), key=lambda m: m["t"])
    text = out_path.read_text()
    print(text)

    ev = Evaluation(c=2000.0, gamma=2000.0)
    for m in truth:
        conf = [k for k in gtracks[m["t"]]["tracks"] if k["status"] == "confirmed"]
        ev.add(m["t"], m["id"], np.column_stack([m["x"], m["vx"], m["y"], m["vy"], m["z"], m["vz"]]),
               np.array([k["id"] for k in conf], dtype=np.int64),
               np.array([k["x"] for k in conf]).reshape(-1, 6),
               np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
    s = ev.metrics.summary()
    head = re.search(r"steps (\d+)\s+mean GOSPA ([\d.]+) m\s+mean OSPA ([\d.]+) m.*switches (\d+)\s+"
                     r"breaks (\d+)", text)
    assert head, text
    assert int(head[1]) == s.steps == len(truth)
    assert float(head[2]) == round(s.mean_gospa, 1)
    assert float(head[3]) == round(s.mean_ospa, 1)
    assert (int(head[4]), int(head[5])) == (s.switches, s.breaks)
    joint = count_switches(ev.metrics.joint_associations())
    assert f"(trajectory GOSPA): switches {joint.switches}  breaks {joint.breaks}" in text

    p = section(cfg, "radar.fusion", FusionParams)
    scores = score_targets(ev, np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
                           base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z,
                           np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]),
                           SETTLE)
    rows = {int(r[1]): r for r in (ROW.match(line) for line in text.splitlines()) if r}
    assert set(rows) == set(scores) == {1, 2}
    for tid, sc in scores.items():
        r = rows[tid]
        assert int(r[2]) == sc.n
        assert float(r[3]) == round(sc.rmse, 1)
        assert float(r[4]) == round(sc.bound, 1)
        assert float(r[6]) == round(sc.nees_pos, 2)
        assert float(r[7]) == round(sc.nees_state, 2)
    # the RMSE printed is the RMSE of the position errors, checked from the raw pairs
    for tid, rows_t in ev.after(SETTLE).items():
        assert scores[tid].rmse == np.sqrt(np.mean(rows_t[:, 3]))


def test_evaluate_with_no_scored_step_says_so_and_fails(tmp_path: Path) -> None:
    """Truth but no global tracks (no fusion running): no step can be scored, and the
    table of zeros ("mean GOSPA 0.0 m, switches 0") is not printed as if it were a result."""
    scn = SCENARIOS / "two_targets.toml"
    out_path = tmp_path / "evaluate.out"
    with Deployment(tmp_path) as d, open(out_path, "wb") as out:
        ev_proc = Child("evaluate", "evaluate", "--config", str(scn), "--connect", d.endpoint,
                        log=tmp_path / "evaluate.log", stdout=out)
        d.children.append(ev_proc)
        d.wait_alive(["evaluate/main"])
        d.simulate(scn, seed=1, scans=5, wait_alive=["evaluate/main"])
        assert ev_proc.wait(60.0) == 1
    text = out_path.read_text()
    assert "no step scored" in text and "mean GOSPA" not in text
