"""Parameters that check each other (issue 34): every Params class checks its ranges and
rules on construction, and ``pfusion params --check`` reports the same errors, [sim]
included, naming the keys and their table."""

from __future__ import annotations

import dataclasses
import importlib
import math
import pkgutil
from pathlib import Path
from typing import Any

import pytest

import common
from common.core.params import ParamError, Params, Range
from common.deploy.config import ConfigError
from common.deploy.sections import SECTIONS
from common.sim.scenario import SonarArraySim
from common.sonar.bearing.params import TrackerParams
from common.sonar.mht.params import MhtParams
from common.sonar.tma.constrained import CtmaParams
from common.sonar.tma.manager import BoundsParams
from services.params.main import check

REPO = Path(__file__).resolve().parents[2]
_SIM_HEAD = "[sim]\nn_scans = 3\n[sim.sonar]\nown = { pos = [0.0, 0.0], vel = [0.0, 5.0] }\n"


def _all_params() -> list[type]:
    """Every subclass of Params, at any depth, once every module of the packages that may
    define one (those below common.deploy, and common.sim) is imported."""
    for pkg in ("core", "radar", "sonar", "sim"):
        for m in pkgutil.walk_packages([str(Path(common.__file__).parent / pkg)], f"common.{pkg}."):
            importlib.import_module(m.name)
    out, todo = [], list(Params.__subclasses__())
    while todo:
        cls = todo.pop()
        out.append(cls)
        todo += cls.__subclasses__()
    return sorted(out, key=lambda c: c.__qualname__)


ALL = _all_params()


def test_every_parameter_table_class_is_a_params() -> None:
    assert set(SECTIONS.values()) <= set(ALL)
    assert not [c.__name__ for c in SECTIONS.values() if not dataclasses.is_dataclass(c)]


def _outside(r: Range) -> float:
    """A value just outside ``r`` (NaN for an interval without ends)."""
    if math.isfinite(r.lo):
        return r.lo - 1.0 if r.closed[0] == "[" else r.lo
    return r.hi + 1.0 if math.isfinite(r.hi) else math.nan


@pytest.mark.parametrize("cls", ALL, ids=lambda c: c.__name__)
def test_every_params_checks_its_ranges_on_construction(cls: type) -> None:
    cls()  # the defaults hold
    for name, r in cls.RANGES.items():
        default = getattr(cls(), name)
        bad: Any = _outside(r)
        if isinstance(default, (list, tuple)):
            bad = type(default)([bad] * len(default))
        with pytest.raises(ParamError) as e:
            cls(**{name: bad})
        assert e.value.keys == (name,) and f"[{cls.__name__}] {name} = " in str(e.value)


# (table, class, keys given, keys named, text the message holds)
BAD = [
    ("sonar.tma.ctma", CtmaParams, {"q1": 1.5, "q2": 1.5}, ("q2", "q1"), "q2 (1.5) >= q1 (1.5)"),
    ("sonar.tma.ctma", CtmaParams, {"q2": 1.2}, ("q3", "q2"), "q3 (1.25) >= q2 (1.2)"),
    ("radar.fusion", SECTIONS["radar.fusion"], {"z_min": 9000.0, "z_max": 8000.0}, ("z_min", "z_max"),
     "z_min (9000) >= z_max (8000)"),
    ("sonar.tracker.mht", MhtParams, {"za_krit": 7}, ("za_krit", "za_max"), "za_krit (7) > za_max (6)"),
    ("sonar.tracker.mht", MhtParams, {"A": 2.0}, ("A", "B"), "A (2) >= B (2)"),
    ("sonar.tracker", SECTIONS["sonar.tracker"], {"alpha": 0.6, "beta": 0.5}, ("alpha", "beta"), "alpha + beta < 1"),
    ("sonar.tracker", SECTIONS["sonar.tracker"], {"band_hz": [900.0, 100.0]}, ("band_hz",), "low < high"),
    ("sonar.tma.bounds", BoundsParams, {"r_min": 5e5}, ("r_min", "r_max"), "r_min (500000) >= r_max (100000)"),
    ("radar.network", SECTIONS["radar.network"], {"cell_fine": 2e4}, ("cell_fine", "cell_coarse"),
     "cell_fine (20000) > cell_coarse (10000)"),
    ("radar.network", SECTIONS["radar.network"], {"coast_tentative": 9.0}, ("coast_tentative", "coast"),
     "coast_tentative (9) > coast (5)"),
]


@pytest.mark.parametrize("table,cls,given,keys,text", BAD, ids=[f"{b[0]}-{'-'.join(b[3])}" for b in BAD])
def test_broken_rules_are_refused_by_the_constructor(table: str, cls: type, given: dict[str, Any],
                                                      keys: tuple[str, ...], text: str) -> None:
    with pytest.raises(ParamError) as e:
        cls(**given)
    assert e.value.keys == keys and text in str(e.value) and str(e.value).startswith(f"[{cls.__name__}] ")


def _toml(value: Any) -> str:
    return str(value).lower() if isinstance(value, bool) else repr(value)


@pytest.mark.parametrize("table,cls,given,keys,text", BAD, ids=[f"{b[0]}-{'-'.join(b[3])}" for b in BAD])
def test_broken_rules_are_refused_by_params_check(tmp_path: Path, table: str, cls: type, given: dict[str, Any],
                                                  keys: tuple[str, ...], text: str) -> None:
    f = tmp_path / "bad.toml"
    f.write_text(f"[{table}]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in given.items()))
    with pytest.raises(ConfigError) as e:
        check(str(f))
    assert e.value.key == f"{table}.{keys[0]}" and f"[{table}] {keys[0]} " in str(e.value)
    assert text in str(e.value) and all(k in str(e.value) for k in keys)


def test_per_array_bounds_are_checked_merged(tmp_path: Path) -> None:
    f = tmp_path / "bad.toml"
    f.write_text("[sonar.tma.bounds]\nr_max = 30000.0\n[sonar.tma.bounds.a1]\nr_min = 40000.0\n")
    with pytest.raises(ConfigError, match=r"\[sonar.tma.bounds.a1\] r_min \(40000\) >= r_max \(30000\)"):
        check(str(f))


def test_clock_reference_names_configured_bases(tmp_path: Path) -> None:
    f = tmp_path / "bad.toml"
    f.write_text('[[radar.base]]\nid = "b1"\ntx = [1.0, 0.0, 0.0]\nrx = [0.0, 0.0, 0.0]\n'
                 'channels = ["c"]\n[radar.network]\nclock_reference = ["b1", "b9"]\n')
    with pytest.raises(ConfigError, match=r"radar.network.clock_reference.*not a configured base: b9"):
        check(str(f))


def test_sim_detection_probability_is_checked_by_constructor_and_params_check(tmp_path: Path) -> None:
    with pytest.raises(ParamError, match=r"\[SonarArraySim\] pd = 1.9 is outside \[0, 1\]"):
        SonarArraySim(pd=1.9)
    f = tmp_path / "bad.toml"
    f.write_text(_SIM_HEAD + "pd = 1.9\n")
    with pytest.raises(ConfigError) as e:
        check(str(f))
    assert e.value.key == "sim.sonar.pd" and "[sim.sonar] pd = 1.9 is outside [0, 1]" in str(e.value)
    f.write_text(_SIM_HEAD + "pd = 0.9\n")
    check(str(f))


@pytest.mark.parametrize("path", sorted((REPO / "scenarios").glob("*.toml")) + [REPO / "deploy" / "sample.toml"],
                         ids=lambda p: p.name)
def test_shipped_files_pass_params_check(path: Path) -> None:
    check(str(path))


def test_valid_values_on_the_edge_of_a_rule_are_accepted() -> None:
    MhtParams(za_krit=6, za_max=6)
    CtmaParams(q1=3.0, q2=2.0, q3=1.5)
    TrackerParams(alpha=0.4, beta=0.5)
