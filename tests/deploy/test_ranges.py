"""Declared unit and range of every numeric parameter (RANGES of each parameter class,
common.core.params), enforced when a deployment file is read."""

from __future__ import annotations

import dataclasses
import typing

import pytest

from common.core.params import Range
from common.deploy.config import ConfigError, parse, section
from common.deploy.sections import SECTIONS, check_all


def _numeric(hint: typing.Any) -> bool:
    """int, float or a list/tuple of them (bool is not a number here)."""
    if hint in (int, float):
        return True
    args = typing.get_args(hint)
    return typing.get_origin(hint) in (list, tuple) and bool(args) and args[0] in (int, float)


def _default(f: dataclasses.Field) -> typing.Any:  # type: ignore[type-arg]
    return f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]


@pytest.mark.parametrize("name", sorted(SECTIONS))
def test_every_numeric_parameter_has_a_range_that_holds_its_default(name: str) -> None:
    cls = SECTIONS[name]
    ranges = cls.RANGES
    hints = typing.get_type_hints(cls)
    fields = [f for f in dataclasses.fields(cls) if _numeric(hints[f.name])]
    missing = [f.name for f in fields if f.name not in ranges]
    assert not missing, f"[{name}] numeric keys without a range in RANGES: {missing}"
    for f in fields:
        d = _default(f)
        for v in d if isinstance(d, (list, tuple)) else [d]:
            assert ranges[f.name].contains(v), f"[{name}] {f.name} default {v} outside {ranges[f.name]}"
    stale = set(ranges) - {f.name for f in dataclasses.fields(cls)}
    assert not stale, f"[{name}] ranges of keys that do not exist: {sorted(stale)}"


@pytest.mark.parametrize("dotted,key,value", [
    ("radar.tracker", "gate_prob", 1.5),
    ("radar.tracker", "gate_prob", 0.0),
    ("radar.fusion", "alt_bands", 0),
    ("radar.fusion", "confirm_bases", 1),
    ("sonar.tracker", "p_fa", -0.1),
    ("sonar.tracker", "imm_sojourn_s", [60.0, -1.0]),
    ("sonar.tma.bounds.a1", "course_max", 7.0),
])
def test_out_of_range_values_are_rejected_with_the_key(dotted: str, key: str, value: object) -> None:
    doc: dict = {key: value}
    for part in reversed(dotted.split(".")):
        doc = {part: doc}
    with pytest.raises(ConfigError) as e:
        section(parse(doc), dotted, SECTIONS[dotted if dotted in SECTIONS else "sonar.tma.bounds.*"])
    assert e.value.key == f"{dotted}.{key}"
    assert "outside" in str(e.value)


def test_values_on_a_closed_end_are_accepted_and_on_an_open_end_refused() -> None:
    check_all(parse({"radar": {"tracker": {"max_coast": 0}, "fusion": {"az_gate_deg": 180.0}}}))
    with pytest.raises(ConfigError):
        check_all(parse({"radar": {"fusion": {"az_gate_deg": 0.0}}}))


def test_interval_notation() -> None:
    r = Range("m", 0.0, float("inf"), "(]")
    assert str(r) == "(0, inf]" and not r.contains(0.0) and r.contains(1e9)
    assert Range("", -1.0, 1.0, "[)").contains(-1.0) and not Range("", -1.0, 1.0, "[)").contains(1.0)
