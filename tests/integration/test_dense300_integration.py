"""Issue 14's quality goals on a 300-target scene through the real processes: router,
simulator, a channel plotter and an elementary tracker per base, global fusion
(scenarios/dense300.toml: 4 bases with 2-4 channels, Pd 0.85, 4 false plots per channel
and scan, 120 s). One run, scored against the simulator's truth (confirmed global
tracks, GOSPA assignment with a 2 km cut-off):

* missed targets < 2 % and false tracks < 1 % of the targets present, per scan, after
  a 30 s warm-up (means over the scans);
* number switches < 1 per 100 targets over the 120 s, counted on the trajectory GOSPA
  assignment minimised over the whole run (common.evaluation.trajectory_gospa: a truth
  changes track only when the exchange pays for its switches, gamma = 2 km); the
  per-step assignment, an upper bound, is printed beside it (this run measured 1-2 for
  300 targets, its crossings of correctly fed tracks with honest altitude errors);
* RMSE / PCRLB <= 1.5 (median over targets, 30 s after each target's first track);
* mean position NEES within a factor 1.5 of its dimension 3.
No timing is asserted (benchmarks/dense_scale.py and load.py measure speed), and no
timing may change the result: the run's global fusion waits up to 120 s of wall time
for a base (`max_wait`) instead of 3 s, so a base lagging behind on a loaded machine
(two test workers on 2 cores) is never fused without (with 3 s, one such run measured
false 2.0 % and 9 switches).
Measured (2 shared cores, load ~10): missed 0.54 %, false 0.76 %, 1 switch, 3 breaks,
RMSE/PCRLB 0.95, NEES 3.83; 102 s. 2026-11-26 (idle, after the module 61 clean-up of
common.radar.fusion.merge.explained): missed 0.55 %, false 0.77 %, 2 switches (3 at the
commit before it), 9 breaks (9 before), RMSE/PCRLB 0.92, NEES 3.77; 10 s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from common.deploy.config import load, section
from common.evaluation.metrics import count_switches
from common.evaluation.pcrlb import Evaluation, base_information, score_targets
from common.radar.fusion.params import FusionParams
from common.sim.scenario import radar_scene
from common.wire.sim_messages import truth_state
from tests.harness import SCENARIOS, Deployment, patient_scene

SCENE = SCENARIOS / "dense300.toml"
WARMUP = 30.0


@pytest.mark.slow
def test_dense300_quality_goals(tmp_path: Path) -> None:
    scene = patient_scene(tmp_path, SCENE.stem)
    cfg = load(scene)
    with Deployment(tmp_path) as d:
        d.collect("radar/gtracks")
        d.collect("sim/truth/radar")
        alive = d.start_services(scene, ("channel-plotter", "elementary-tracker", "global-fusion"))
        d.wait_alive(alive, timeout=120.0)
        d.simulate(scene, seed=1, wait_alive=alive, timeout=900.0)
        truth = sorted(d.of("sim/truth/radar"), key=lambda m: m["t"])
        t_last = truth[-1]["t"]
        d.wait_for(lambda: any(m["t"] == t_last for m in d.of("radar/gtracks")), timeout=600.0)
        gtracks = {m["t"]: m for m in d.of("radar/gtracks")}
    assert sorted(gtracks) == [m["t"] for m in truth]  # a fusion cycle for every scan
    ev = Evaluation(c=2000.0, gamma=2000.0)
    missed, false, present = [], [], []
    for m in truth:
        conf = [k for k in gtracks[m["t"]]["tracks"] if k["status"] == "confirmed"]
        ev.add(m["t"], np.asarray(m["id"]), truth_state(m), np.array([k["id"] for k in conf], dtype=np.int64),
               np.array([k["x"] for k in conf]).reshape(-1, 6),
               np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
        paired = ev.metrics.gospa_series[-1].rows.size
        if m["t"] >= WARMUP:
            present.append(len(m["id"]))
            missed.append(len(m["id"]) - paired)
            false.append(len(conf) - paired)
    p = section(cfg, "radar.fusion", FusionParams)
    scores = score_targets(ev, np.array([b.tx for b in cfg.bases]), np.array([b.rx for b in cfg.bases]),
                           base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z,
                           np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2]), WARMUP)
    s = ev.metrics.summary()
    joint = count_switches(ev.metrics.joint_associations())
    n_targets = len(ev.truth)
    ratio = float(np.median([v.rmse / v.bound for v in scores.values()]))
    nees = float(np.mean([v.nees_pos for v in scores.values()]))
    n = float(np.mean(present))
    print(f"dense300 through the processes: {n_targets} targets, missed {np.mean(missed):.2f} "
          f"per scan ({100 * np.mean(missed) / n:.2f} %), false {np.mean(false):.2f} "
          f"({100 * np.mean(false) / n:.2f} %), switches {joint.switches} (per step {s.switches}), "
          f"breaks {joint.breaks} (per step {s.breaks}), "
          f"RMSE/PCRLB median {ratio:.2f}, mean position NEES {nees:.2f}")
    assert np.mean(missed) < 0.02 * n
    assert np.mean(false) < 0.01 * n
    assert joint.switches < n_targets / 100
    assert ratio <= 1.5
    assert 3 / 1.5 <= nees <= 3 * 1.5
