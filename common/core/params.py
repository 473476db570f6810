"""Parameter classes that check themselves: every ``*Params`` dataclass derives from
:class:`Params` and declares, beside its fields, the unit and admissible interval of each
numeric field (``RANGES``) and the rules between fields (``RULES``). Every construction,
from Python or from a deployment file (common.deploy.config.section), checks them and
raises :class:`ParamError` naming the keys; docs/configuration.md shows the same
declarations. A list field has the range of each of its elements.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

INF = math.inf


@dataclass(frozen=True)
class Range:
    """An interval lo..hi of a parameter in ``unit``; ``closed`` says which ends belong
    to it ("[]", "[)", "(]" or "()"); ``note`` says why an end is unbounded."""

    unit: str
    lo: float
    hi: float
    closed: str = "[]"
    note: str = ""

    def contains(self, v: float) -> bool:
        """Whether v lies in the interval."""
        lo_ok = v >= self.lo if self.closed[0] == "[" else v > self.lo
        hi_ok = v <= self.hi if self.closed[1] == "]" else v < self.hi
        return lo_ok and hi_ok

    def __str__(self) -> str:
        def num(x: float) -> str:
            return "inf" if x == INF else "-inf" if x == -INF else f"{x:g}"
        return f"{self.closed[0]}{num(self.lo)}, {num(self.hi)}{self.closed[1]}"


def positive(unit: str = "") -> Range:
    """(0, inf)."""
    return Range(unit, 0.0, INF, "()")


def non_negative(unit: str = "") -> Range:
    """[0, inf)."""
    return Range(unit, 0.0, INF, "[)")


def count(lo: int = 1) -> Range:
    """Integers lo, lo + 1, ..."""
    return Range("count", lo, INF, "[)")


def unbounded(unit: str, note: str) -> Range:
    """(-inf, inf), with the reason why no end applies."""
    return Range(unit, -INF, INF, "()", note)


PROB_OPEN = Range("probability", 0.0, 1.0, "()")
ANGLE = Range("rad", 0.0, 2.0 * math.pi, "[]")


@dataclass(frozen=True)
class Rule:
    """A rule between fields ``keys``: ``holds(*values)`` must be true; ``text`` states
    it (docs/configuration.md); ``broken(values)`` is how a violation reads."""

    keys: tuple[str, ...]
    holds: Callable[..., bool]
    text: str
    broken: Callable[[dict[str, Any]], str] | None = None

    def message(self, values: dict[str, Any]) -> str:
        """What is wrong, with the keys and their values."""
        if self.broken is not None:
            return self.broken(values)
        given = ", ".join(f"{k} = {values[k]!r}" for k in self.keys)
        return f"{given}: needs {self.text}"


def order(lo: str, hi: str, strict: bool = True) -> Rule:
    """lo < hi (strict) or lo <= hi."""
    op, neg = ("<", ">=") if strict else ("<=", ">")
    holds = (lambda a, b: a < b) if strict else (lambda a, b: a <= b)
    return Rule((lo, hi), holds, f"{lo} {op} {hi}",
                lambda v: f"{lo} ({v[lo]:g}) {neg} {hi} ({v[hi]:g}): needs {lo} {op} {hi}")


def ascending_pair(key: str) -> Rule:
    """List ``key`` is [low, high] with low < high."""
    return Rule((key,), lambda v: len(v) == 2 and v[0] < v[1], f"{key} = [low, high], low < high")


def two_values(key: str) -> Rule:
    """List ``key`` has exactly two values."""
    return Rule((key,), lambda v: len(v) == 2, f"{key} has two values")


class ParamError(ValueError):
    """A parameter outside its range or a broken rule: ``keys`` are the offending fields
    of table (or class) ``table``; ``detail`` says what is wrong."""

    def __init__(self, table: str, keys: tuple[str, ...], detail: str) -> None:
        super().__init__(f"[{table}] {detail}")
        self.table, self.keys, self.detail = table, keys, detail


def problem(obj: Any) -> tuple[tuple[str, ...], str] | None:
    """The first (keys, detail) of ``obj`` outside a range or breaking a rule, or None."""
    for name, r in type(obj).RANGES.items():
        value = getattr(obj, name)
        for v in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(v, (int, float)) and not isinstance(v, bool) and not r.contains(float(v)):
                unit = f" {r.unit}" if r.unit else ""
                return (name,), f"{name} = {v!r} is outside {r}{unit}"
    for rule in type(obj).RULES:
        values = {k: getattr(obj, k) for k in rule.keys}
        if not rule.holds(*values.values()):
            return rule.keys, rule.message(values)
    return None


class Params:
    """Base of the parameter dataclasses: ``RANGES`` and ``RULES`` hold on every
    instance (checked in ``__post_init__``)."""

    RANGES: ClassVar[dict[str, Range]] = {}
    RULES: ClassVar[tuple[Rule, ...]] = ()

    def __post_init__(self) -> None:
        found = problem(self)
        if found is not None:
            raise ParamError(type(self).__name__, *found)
