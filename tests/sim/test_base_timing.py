"""Per-base scan periods and phases of the simulator ([sim.radar.base.<id>]): each base's
plots at its own times, truth at the union, the common scan without the table."""

from __future__ import annotations

import numpy as np
import pytest

from common.deploy.config import ConfigError
from common.sim.simulator import load_scenario
from tests.sim.test_simulator import BASES, radar_doc, run


def plot_times(steps: list) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    for t, msgs in steps:
        for k, m in msgs:
            if k.startswith("radar/plots/"):
                assert m["t"] == t
                out.setdefault(k, []).append(t)
    return out


def test_each_base_scans_at_its_own_times() -> None:
    doc = radar_doc(base={"b1": {"period": 0.7, "phase": 0.25}})
    steps = run(doc)
    times = plot_times(steps)
    own = 0.25 + 0.7 * np.arange(14)  # phase + k period < 10 s
    assert times["radar/plots/b1/c1"] == times["radar/plots/b1/c2"]
    np.testing.assert_allclose(times["radar/plots/b1/c1"], own)
    assert times["radar/plots/b2/c1"] == [float(k) for k in range(10)]  # the common scan
    truth = [t for t, msgs in steps if any(k == "sim/truth/radar" for k, _ in msgs)]
    np.testing.assert_allclose(truth, np.unique(np.round(np.r_[own, np.arange(10.0)], 9)))


def test_default_timing_is_the_common_scan() -> None:
    doc = radar_doc()
    same = radar_doc(base={"b1": {"period": 1.0, "phase": 0.0}, "b2": {}})
    assert run(doc, seed=4) == run(same, seed=4)


@pytest.mark.parametrize("base, key", [
    ({"b1": {"period": 0.5, "phase": 0.5}}, "sim.radar.base.b1.phase"),
    ({"b1": {"period": 0.0}}, "sim.radar.base.b1.period"),
    ({"b1": {"offset": 0.1}}, "sim.radar.base.b1.offset"),
])
def test_bad_timing_is_refused(base: dict, key: str) -> None:
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_scenario(radar_doc(base=base))


def test_timing_of_an_unknown_base_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"sim\.radar\.base\.b9"):
        run(radar_doc(base={"b9": {"period": 0.5}}), bases=BASES)
