"""Crossing management (seed 004) through the real pipeline: router, `pfusion simulate
--repeat`, bearing trackers (sonar) or channel plotters + elementary trackers (radar),
one "on" and one "off" sensor copy per case (benchmarks/crossing_swaps.py, same code).

Per case, RUNS = 50 seeded runs (seeds 1..50, as the benchmark):
with crossing management on, fewer than 5 % of the runs have a track number swap, no
more than with it off, no truth is lost, and the published ambiguity flag is set while
the truths are within one sigma of each other and almost never beyond eight sigmas.
Also a pure check of the simulator's --repeat / --gap stream.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from benchmarks.crossing_swaps import CASES, SCENARIOS, Case, run_case
from common.deploy.config import load
from common.sim.simulator import load_scenario
from common.wire.sim_messages import repeated, run_scenario

RUNS = 50


def test_repeat_shifts_times_seeds_and_fills_the_gap() -> None:
    path = SCENARIOS / "sonar_cross_4dpm_eq.toml"
    cfg, scn = load(path), load_scenario(tomllib.loads(path.read_text()))
    steps = list(repeated(scn, cfg, 5, None, 3, 80.0))
    assert [t for t, _ in steps] == [10.0 * k for k in range(3 * 38)]  # 30 scans + 8 gap
    det = [m for _, ms in steps for k, m in ms if k == "sonar/detections/a1"]
    truth = [m for _, ms in steps for k, m in ms if k == "sim/truth/sonar"]
    assert [m["seq"] for m in det] == list(range(3 * 38))
    assert [len(m["id"]) for m in truth[28:40]] == [2, 2] + [0] * 8 + [2, 2]
    second = [m for _, ms in run_scenario(scn, cfg.bases, cfg.arrays, 6) for k, m in ms
              if k == "sonar/detections/a1"]
    assert np.array_equal(det[38 + 3]["brg"], second[3]["brg"])  # run 1 = seed 6
    assert det[38 + 3]["t"] == second[3]["t"] + 300.0 + 80.0


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
@pytest.mark.slow
def test_crossing_swaps_off_and_on(case: Case, tmp_path: Path) -> None:
    res = run_case(case, RUNS, tmp_path)
    off, on = res["off"], res["on"]
    print(f"{case.name}: off {off}\n{case.name}: on  {on}")
    assert off.runs == on.runs == RUNS
    assert on.swap_runs < 0.05 * RUNS, on
    assert on.swaps <= off.swaps, (off, on)
    assert on.lost_runs == 0, on
    assert on.flag_during >= 0.9 and on.flag_outside <= 0.05, on
    assert off.flag_during == off.flag_outside == 0.0, off
