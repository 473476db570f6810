"""The ``[sonar.tma]`` tables of one array (seeds 002, 003): parameters, core config,
initial bounds (the default table overridden key by key by ``[sonar.tma.bounds.<array>]``)
and support values, read in one place for ``pfusion tma``."""

from __future__ import annotations

from common.deploy.config import Config, ConfigError, section, table
from common.deploy.sections import array_bounds
from common.sonar.tma.bounds import Bounds
from common.sonar.tma.constrained import CtmaParams
from common.sonar.tma.manager import SupportParams, TmaParams, make_bounds

SUBTABLES = ("ctma", "bounds", "support")


def tma_config(cfg: Config, array: str) -> tuple[TmaParams, CtmaParams, Bounds, SupportParams]:
    """The TMA parameters, core config, initial bounds and support values of ``array``."""
    tma = table(cfg.doc, "sonar.tma")
    extra = sorted(k for k, v in tma.items() if isinstance(v, dict) and k not in SUBTABLES)
    if extra:
        raise ConfigError(f"sonar.tma.{extra[0]}", f"unknown table (known: {', '.join(SUBTABLES)})")
    params = section(cfg, "sonar.tma", TmaParams)
    core = section(cfg, "sonar.tma.ctma", CtmaParams)
    known = {a.id for a in cfg.arrays}
    for k, v in table(cfg.doc, "sonar.tma.bounds").items():
        if isinstance(v, dict) and k not in known:
            raise ConfigError(f"sonar.tma.bounds.{k}", "not an array of the deployment")
    # BoundsParams checks what make_bounds requires: no Rejected here
    b = make_bounds(array_bounds(cfg, array))
    return params, core, b, section(cfg, "sonar.tma.support", SupportParams)
