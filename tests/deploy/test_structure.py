"""The structure tables (common.deploy.structure): the keys docs/configuration.md lists
are the keys the loader accepts, table by table, and every table the loader knows has
its section on the page."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from typing import Any

import pytest

from common.deploy.config import AuthConfig, ConfigError, Site, TlsConfig, ZenohConfig, parse
from common.deploy.sections import SECTIONS, STRUCTURE
from common.deploy.structure import ARRAY, BASE, ORIGIN, TABLES, ZENOH

REPO = Path(__file__).resolve().parents[2]
PAGE = (REPO / "docs" / "configuration.md").read_text()
BASE_OK = {"id": "b1", "tx": [0.0, 0.0, 0.0], "rx": [1000.0, 0.0, 0.0], "channels": ["c1"]}
GEO_BASE = {"id": "b1", "tx_geo": [48.0, 2.0, 100.0], "rx_geo": [48.01, 2.0, 100.0], "channels": ["c1"],
            "p": 0, "azimuth": False}
ORIGIN_OK = {"lat": 48.0, "lon": 2.0, "alt": 100.0}


def page_keys(heading: str) -> list[str]:
    """The key column of the page's table under ``## heading``."""
    block = PAGE.split(f"\n## {heading}\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"^\| (\w+) \|", block, re.M)[1:]  # [0] is the header's "key"


def rejected_key(doc: dict[str, Any]) -> str | None:
    try:
        parse(doc)
    except ConfigError as e:
        return e.key if "unknown key" in str(e) or "must be a table of exactly" in str(e) else None
    return None


def test_every_table_of_the_loader_has_a_section() -> None:
    headings = set(re.findall(r"^## (.+)$", PAGE, re.M))
    # STRUCTURE (check_tables' list) holds the plain parents radar / sonar / sim and the array tables'
    # parents; each of their tables is one of the sections below or [sim] (docs/scenarios.md);
    # [zenoh.tls.hosts] is the table-valued key `hosts` of [zenoh.tls]
    expected = {"[zenoh]", "[zenoh.auth]", "[zenoh.tls]", "[radar.origin]", "[[radar.base]]",
                "[[sonar.array]]", "[[site]]"} | {f"[{n}]" for n in SECTIONS}
    assert headings == expected
    assert set(STRUCTURE) - {"radar", "sonar", "sim"} <= {"zenoh", "zenoh.auth", "zenoh.tls", "zenoh.tls.hosts",
                                                                "radar.origin"}


@pytest.mark.parametrize("heading,names", [
    ("[zenoh]", {f.name for f in dataclasses.fields(ZenohConfig)}),
    ("[zenoh.auth]", {f.name for f in dataclasses.fields(AuthConfig)}),
    ("[zenoh.tls]", {f.name for f in dataclasses.fields(TlsConfig)}),
    ("[[site]]", {f.name for f in dataclasses.fields(Site)}),
    ("[radar.origin]", set(ORIGIN.names())),
    ("[[radar.base]]", set(BASE.names())),
    ("[[sonar.array]]", set(ARRAY.names())),
])
def test_documented_keys_are_the_loaders(heading: str, names: set[str]) -> None:
    assert set(page_keys(heading)) == names


def test_zenoh_declaration_is_zenoh_config() -> None:
    """[zenoh] is read into ZenohConfig (common.deploy.config._build): its fields are the keys."""
    assert ZENOH.names() == {f.name for f in dataclasses.fields(ZenohConfig)}


def test_every_declared_key_is_accepted() -> None:
    parse({"zenoh": {"connect": ["tcp/127.0.0.1:1"], "listen": [], "root": "x", "identity": "a"}})
    parse({"radar": {"base": [{**BASE_OK, "p": 2, "azimuth": True}]}})
    parse({"radar": {"origin": ORIGIN_OK, "base": [GEO_BASE]}})
    parse({"sonar": {"array": [{"id": "a1", "kind": "linear", "sigma0": 0.01}]}})
    parse({"radar": {"base": [BASE_OK]}, "sonar": {"array": [{"id": "a1", "sigma0": 0.01}]},
           "site": [{"id": "s", "bases": ["b1"], "arrays": ["a1"]}]})
    assert set(TABLES) == {"zenoh", "radar.origin", "radar.base", "sonar.array"}


@pytest.mark.parametrize("doc,key", [
    ({"radar": {"base": [{**BASE_OK, "gain": 1}]}}, "radar.base[0].gain"),
    ({"sonar": {"array": [{"id": "a1", "sigma0": 0.01, "depth": 3.0}]}}, "sonar.array[0].depth"),
    ({"site": [{"id": "s", "hosts": []}]}, "site[0].hosts"),
    ({"zenoh": {"mode": "peer"}}, "zenoh.mode"),
    ({"radar": {"origin": {**ORIGIN_OK, "datum": "wgs84"}}}, "radar.origin"),
])
def test_an_undeclared_key_is_refused(doc: dict[str, Any], key: str) -> None:
    assert rejected_key(doc) == key
