"""benchmarks/network_altitude.py on fewer runs: an aircraft outside the network's hull,
per-report updates from the best Gaussian start (docs/decisions/024-network-altitude.md).
The harness and the bound agree (the EKF with Jacobians at the truth is consistent and
at the PCRLB); inside the hull the global tracks' EKF is too; outside it is not."""

from __future__ import annotations

import pytest

from benchmarks import network_altitude

RUNS, DURATION = 60, 25.0


def test_truth_linearised_ekf_is_at_the_bound() -> None:
    """Columns: RMSE / PCRLB, z RMSE, z sigma, z PCRLB, NEES, % beyond 99 %. The errors
    of a run are correlated over its 13 s: 60 runs give the ratio to about 10 %."""
    r = network_altitude.run("outside", RUNS, DURATION, 1, kinds=("truth",))["truth"]
    assert 0.7 <= r[0] <= 1.2
    assert 2.0 <= r[4] <= 4.0
    assert 0.9 * r[3] <= r[2] <= 1.1 * r[3]


def test_ekf_inside_the_hull_meets_the_goals() -> None:
    r = network_altitude.run("inside", RUNS, DURATION, 1, kinds=("ekf",))["ekf"]
    assert r[0] <= 1.3 and r[4] <= 4.5 and r[5] < 2.0


@pytest.mark.xfail(strict=True, reason="the EKF's altitude covariance collapses below its error "
                   "outside the hull (docs/decisions/024-network-altitude.md): a fix makes this pass")
def test_ekf_outside_the_hull_is_consistent() -> None:
    r = network_altitude.run("outside", RUNS, DURATION, 1, kinds=("ekf",))["ekf"]
    assert r[0] <= 1.3 and r[4] <= 4.5 and r[5] < 2.0
