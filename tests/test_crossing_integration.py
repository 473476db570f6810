"""Crossing management (seed 004) through the real pipeline: router, `pfusion simulate
--repeat`, bearing trackers (sonar) or channel plotters + elementary trackers (radar),
one "on" and one "off" sensor copy per case (benchmarks/crossing_swaps.py, same code).

Per case, RUNS = 50 seeded runs (seeds 1..50, as the benchmark):
with crossing management on, fewer than 5 % of the runs have a track number swap, no
more than with it off, no truth is lost, and the published ambiguity flag is set while
the truths are within one sigma of each other and almost never beyond eight sigmas.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.crossing_swaps import CASES, Case, run_case

RUNS = 50


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
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
