"""Every parameter table of a deployment file, the dataclass that reads it, and the
reference page docs/configuration.md generated from them (``pfusion params``)."""

from __future__ import annotations

import dataclasses
import fnmatch
import re
import typing
from typing import Any

from common.core.crossing import CrossingParams
from common.core.params import Params
from common.deploy.config import AuthConfig, Config, ConfigError, Site, TlsConfig, section, table, tables
from common.deploy.structure import ARRAY, BASE, ORIGIN, ZENOH, Table
from common.radar.elementary.tracker import ElementaryParams, RadarCrossingParams
from common.radar.fusion.params import FusionCrossingParams, FusionParams
from common.radar.network.params import NetworkParams
from common.radar.plots.channel_fusion import PlotterParams
from common.radar.plots.units import IngestParams
from common.sonar.mht.params import MhtParams, SonarTrackerParams
from common.sonar.tma.constrained import CtmaParams
from common.sonar.tma.manager import BoundsParams, SupportParams, TmaParams

SECTIONS: dict[str, type] = {
    "radar.plotter": PlotterParams,
    "radar.tracker": ElementaryParams,
    "radar.crossing": RadarCrossingParams,
    "radar.fusion": FusionParams,
    "radar.fusion_crossing": FusionCrossingParams,
    "radar.network": NetworkParams,
    "radar.ingest": IngestParams,
    "radar.ingest.*": IngestParams,
    "sonar.tracker": SonarTrackerParams,
    "sonar.tracker.mht": MhtParams,
    "sonar.crossing": CrossingParams,
    "sonar.tma": TmaParams,
    "sonar.tma.ctma": CtmaParams,
    "sonar.tma.support": SupportParams,
    "sonar.tma.bounds": BoundsParams,
    "sonar.tma.bounds.*": BoundsParams,
}
STRUCTURE = ("zenoh", "zenoh.auth", "zenoh.tls", "zenoh.tls.hosts", "radar", "radar.origin", "sonar", "sim")


def check_tables(cfg: Config) -> None:
    """Raise ConfigError for a table that is neither structure nor a known section
    (a misspelt ``[radar.trackr]`` must not be ignored silently)."""
    known = (*STRUCTURE, *SECTIONS)
    for dotted in tables(cfg.doc):
        if not dotted.startswith("sim.") and not any(fnmatch.fnmatchcase(dotted, k) for k in known):
            raise ConfigError(dotted, f"unknown table (known: {', '.join(sorted(SECTIONS))})")


def check_all(cfg: Config) -> None:
    """Validate the whole file at start-up: tables, then every parameter section (the
    bounds of each array as that array's TMA reads them). [sim] is the simulator's."""
    check_tables(cfg)
    for name, cls in SECTIONS.items():
        if "*" not in name:
            section(cfg, name, cls)
    for k, v in table(cfg.doc, "sonar.tma.bounds").items():
        if isinstance(v, dict):
            array_bounds(cfg, k)
    unknown = sorted(set(section(cfg, "radar.network", NetworkParams).clock_reference)
                     - {b.id for b in cfg.bases})
    if unknown:
        raise ConfigError("radar.network.clock_reference", f"not a configured base: {', '.join(unknown)}")
    for k, v in table(cfg.doc, "radar.ingest").items():
        if isinstance(v, dict):
            cfg.base(k)
            base_ingest(cfg, k)


def array_bounds(cfg: Config, array: str) -> BoundsParams:
    """[sonar.tma.bounds] overridden key by key by [sonar.tma.bounds.<array>]."""
    merged = {**table(cfg.doc, "sonar.tma.bounds"), **table(cfg.doc, f"sonar.tma.bounds.{array}")}
    return section(cfg, f"sonar.tma.bounds.{array}", BoundsParams,
                   {k: v for k, v in merged.items() if not isinstance(v, dict)})


def base_ingest(cfg: Config, base: str) -> IngestParams:
    """[radar.ingest] overridden key by key by [radar.ingest.<base>]."""
    merged = {**table(cfg.doc, "radar.ingest"), **table(cfg.doc, f"radar.ingest.{base}")}
    return section(cfg, f"radar.ingest.{base}", IngestParams,
                   {k: v for k, v in merged.items() if not isinstance(v, dict)})


def _meanings(cls: type) -> dict[str, str]:
    """Field -> description from docstring lines ``name[, name...]: text`` of the class
    and its bases (a name list may continue on the next line after a comma)."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        text = re.sub(r",\s*\n\s*", ", ", klass.__doc__ or "")
        current: list[str] = []
        for line in text.splitlines()[1:]:
            m = re.match(r"^\s*([\w*`]+(?:\s*,\s*[\w*`]+)*)\s*:\s+(.*)$", line)
            if m:
                current = [n.strip().strip("`") for n in m.group(1).split(",")]
                for pattern in current:
                    out[pattern] = m.group(2).strip()
            elif current and line.strip():
                for pattern in current:
                    out[pattern] += " " + line.strip()
            else:
                current = []
    return out


def _describe(field: str, meanings: dict[str, str]) -> str:
    for pattern, text in meanings.items():
        if fnmatch.fnmatchcase(field, pattern):
            return text
    return ""


def _type_name(hint: Any) -> str:
    if typing.get_origin(hint) is typing.Literal:
        return " \\| ".join(f'"{a}"' for a in typing.get_args(hint))
    return getattr(hint, "__name__", str(hint))


def _default(f: dataclasses.Field) -> str:  # type: ignore[type-arg]
    if f.default is not dataclasses.MISSING:
        return repr(f.default)
    if f.default_factory is not dataclasses.MISSING:
        return repr(f.default_factory())
    return "(required)"


def markdown() -> str:
    """The reference page of every parameter table (docs/configuration.md)."""
    lines = [
        "# Configuration reference",
        "",
        "Generated by `pfusion params` from the structure tables (common.deploy.structure) and",
        "the parameter dataclasses (do not edit by hand; `tests/deploy/test_sections.py` fails",
        "when this page and the code disagree). It lists every table and key the loader",
        "(common.deploy.config) accepts; for the simulator a file may also have `[sim]`",
        "(docs/scenarios.md). Every table is optional; absent keys take the defaults below.",
        "An unknown table or key, a value of the wrong type, a number outside its range or a",
        "broken rule between keys (declared beside the fields: RANGES and RULES of each class,",
        "common.core.params) stops the service with exit code 2 and a message naming the keys;",
        "building the class in Python checks the same. Rules of a table follow its keys.",
        "",
        "Frame: every site and track is in one local East-North-Up frame, metres (x East,",
        "y North, z up). `[radar.origin]` places that frame on the Earth (WGS-84): its",
        "origin, z along the ellipsoid normal there. A base then gives each site either as",
        "`tx` / `rx` (local metres) or as `tx_geo` / `rx_geo` (same datum), converted to local",
        "metres on loading (common.radar.geometry.geodesy); `radar/gtracks` then also carries",
        "each track's lat, lon, alt (docs/protocol.md).",
        "",
        "Security (docs/security.md): `[zenoh.auth]`, `[zenoh.tls]` and `[[site]]` below; file",
        "paths are relative to the deployment file's directory. Without `[[site]]` each base",
        "and each array is a site of its own id; a site's identity `site-<id>` may publish",
        "only the plots of its bases and the detections of its arrays. A base or array",
        "belongs to at most one site.",
    ]
    order: list[tuple[str, type | Table]] = [
        ("zenoh", ZENOH), ("zenoh.auth", AuthConfig), ("zenoh.tls", TlsConfig), ("radar.origin", ORIGIN),
        ("[radar.base]", BASE), ("[sonar.array]", ARRAY), ("[site]", Site), *SECTIONS.items()]
    for name, what in order:
        lines += _structure(what) if isinstance(what, Table) else _dataclass_table(name, what)
    return "\n".join(lines) + "\n"


HEADER = ["| key | type | default | unit | range | meaning |", "| --- | --- | --- | --- | --- | --- |"]


def _structure(t: Table) -> list[str]:
    """The rows of a structure table (common.deploy.structure)."""
    lines = ["", f"## {t.heading}", "", t.summary, "", *HEADER]
    lines += [f"| {k.name} | {k.type} | {k.default} | {k.unit} | {k.range} | {k.meaning} |" for k in t.keys]
    return lines + (["", "Rules: " + "; ".join(t.rules) + "."] if t.rules else [])


def _dataclass_table(name: str, cls: type) -> list[str]:
    """The rows of a table read into dataclass ``cls`` (a parameter section or [zenoh.auth] ...)."""
    meanings = _meanings(cls)
    hints = typing.get_type_hints(cls)
    ranges = cls.RANGES if issubclass(cls, Params) else {}
    lines = ["", f"## [{name}]", "", (cls.__doc__ or "").strip().splitlines()[0], "", *HEADER]
    for f in dataclasses.fields(cls):
        r = ranges.get(f.name)
        unit, interval = (r.unit, f"{r} ({r.note})" if r.note else str(r)) if r is not None else ("", "")
        lines.append(f"| {f.name} | {_type_name(hints[f.name])} | {_default(f)} | {unit} | "
                     f"{interval} | {_describe(f.name, meanings)} |")
    rules = cls.RULES if issubclass(cls, Params) else ()
    if rules:
        lines += ["", "Rules: " + "; ".join(r.text for r in rules) + "."]
    return lines
