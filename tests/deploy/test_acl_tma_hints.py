"""ACL of the hint loop (issue 31 section 1, docs/decisions/026-tma-predicted-bearing.md):
the bearing-tracker of an array may read its array's TMA solutions, nothing more."""

from __future__ import annotations

from pathlib import Path

from common.deploy.acl import grants
from common.deploy.config import load

COARSE = Path(__file__).resolve().parents[2] / "scenarios" / "sonar_cpa_coarse.toml"


def test_the_tracker_identity_may_read_its_arrays_tma_solutions() -> None:
    g = grants(load(COARSE))["bearing-tracker-a1"]
    assert sorted(g.subscribe) == ["sonar/detections/a1", "sonar/tma/a1"]
    assert "sonar/tma/a1" not in g.publish

