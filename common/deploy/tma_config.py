"""The ``[sonar.tma]`` tables of one array (seeds 002, 003): parameters, core config,
initial bounds (the default table overridden key by key by ``[sonar.tma.bounds.<array>]``)
and support values, read in one place for ``pfusion tma``."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from common.core.rejection import Rejected
from common.deploy.config import Config, ConfigError, section
from common.sonar.tma.bounds import Bounds
from common.sonar.tma.constrained import CtmaParams
from common.sonar.tma.manager import BoundsParams, SupportParams, TmaParams, make_bounds

SUBTABLES = ("ctma", "bounds", "support")


def _table(doc: dict[str, Any], dotted: str) -> dict[str, Any]:
    for part in dotted.split("."):
        doc = doc.get(part, {})
        if not isinstance(doc, dict):
            raise ConfigError(dotted, "expected a table")
    return doc


def _leaf_section(cfg: Config, dotted: str, table: dict[str, Any], cls: type) -> Any:
    """section() of ``table`` placed at ``dotted`` (its sub-tables read separately)."""
    doc: dict[str, Any] = {k: v for k, v in table.items() if not isinstance(v, dict)}
    for part in reversed(dotted.split(".")):
        doc = {part: doc}
    return section(replace(cfg, doc=doc), dotted, cls)


def tma_config(cfg: Config, array: str) -> tuple[TmaParams, CtmaParams, Bounds, SupportParams]:
    """The TMA parameters, core config, initial bounds and support values of ``array``."""
    tma = _table(cfg.doc, "sonar.tma")
    extra = sorted(k for k, v in tma.items() if isinstance(v, dict) and k not in SUBTABLES)
    if extra:
        raise ConfigError(f"sonar.tma.{extra[0]}", f"unknown table (known: {', '.join(SUBTABLES)})")
    params = _leaf_section(cfg, "sonar.tma", tma, TmaParams)
    core = section(cfg, "sonar.tma.ctma", CtmaParams)
    bounds = _table(cfg.doc, "sonar.tma.bounds")
    known = {a.id for a in cfg.arrays}
    for k, v in bounds.items():
        if isinstance(v, dict) and k not in known:
            raise ConfigError(f"sonar.tma.bounds.{k}", "not an array of the deployment")
    merged = {**bounds, **_table(cfg.doc, f"sonar.tma.bounds.{array}")}
    try:
        b = make_bounds(_leaf_section(cfg, f"sonar.tma.bounds.{array}", merged, BoundsParams))
    except Rejected as e:
        raise ConfigError(f"sonar.tma.bounds.{array}", e.detail) from None
    return params, core, b, section(cfg, "sonar.tma.support", SupportParams)
