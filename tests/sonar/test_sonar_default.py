"""The sonar defaults of issue 31 on one run of a crossing scene, in process
(benchmarks/sonar_default.py ranks them over every scene and seed)."""

from __future__ import annotations

from benchmarks.sonar_default import CONFIGS, default_config, run_one
from common.core.crossing import CrossingParams
from common.sonar.mht.params import SonarTrackerParams


def test_the_default_configuration_is_the_ranked_candidate() -> None:
    """default_config() follows the Params defaults (it is what the benchmark checks)."""
    d = default_config()
    p = SonarTrackerParams()
    assert (d.mode, d.block, d.law, d.auto) == (p.mode_association, p.block_estimator, p.clutter_level_db > 0,
                                                p.clutter_estimate)
    assert d.mode == "mht" or d.duration == CrossingParams().max_duration


def test_the_default_keeps_the_flag_up_through_a_three_contact_crossing() -> None:
    """sonar_x_three seed 3: with 004's maximum duration at 60 s the flag clears while the
    three contacts are unresolved and two tracks stay exchanged unflagged; with the
    default configuration no swap outlives the flag (under 1 s on an idle machine)."""
    gnn60 = next(c for c in CONFIGS if c.name == "gnn")
    assert run_one(("sonar_x_three", 3, gnn60))[3][0] >= 1
    assert run_one(("sonar_x_three", 3, default_config()))[3][0] == 0
