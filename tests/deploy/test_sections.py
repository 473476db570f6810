"""The configuration reference: complete, current, and enforced at start-up."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest

from common.deploy.config import ConfigError, load, parse
from common.deploy.sections import SECTIONS, _describe, _meanings, check_all, markdown

REPO = Path(__file__).resolve().parents[2]


def test_docs_page_is_generated_from_the_code() -> None:
    page = (REPO / "docs" / "configuration.md").read_text()
    assert page == markdown(), "run: .venv/bin/pfusion params > docs/configuration.md"


@pytest.mark.parametrize("name", sorted(SECTIONS))
def test_every_key_is_documented(name: str) -> None:
    cls = SECTIONS[name]
    meanings = _meanings(cls)
    missing = [f.name for f in dataclasses.fields(cls) if not _describe(f.name, meanings)]
    assert not missing, f"[{name}] keys without a description in the docstring: {missing}"


@pytest.mark.parametrize("path", sorted((REPO / "scenarios").glob("*.toml")) + [REPO / "deploy" / "sample.toml"],
                         ids=lambda p: p.name)
def test_shipped_files_are_valid(path: Path) -> None:
    check_all(load(path))


@pytest.mark.parametrize("doc,key", [
    ({"radar": {"trackr": {"gate_prob": 0.9}}}, "radar.trackr"),
    ({"sonar": {"tma": {"ctmaa": {}}}}, "sonar.tma.ctmaa"),
    ({"radar": {"tracker": {"gate_prb": 0.9}}}, "radar.tracker.gate_prb"),
    ({"extra": {}}, "extra"),
])
def test_unknown_tables_and_keys_are_errors(doc: dict, key: str) -> None:
    with pytest.raises(ConfigError) as e:
        check_all(parse(doc))
    assert e.value.key == key


def test_service_refuses_misspelt_table_with_exit_2(tmp_path: Path) -> None:
    cfg = tmp_path / "bad.toml"
    cfg.write_text((REPO / "scenarios" / "two_targets.toml").read_text() + "\n[radar.trackr]\nx = 1\n")
    r = subprocess.run([sys.executable, "-m", "common", "elementary-tracker", "--config", str(cfg),
                        "--base", "b1"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "radar.trackr" in r.stderr


def test_nested_sections_are_read_separately() -> None:
    doc = {"sonar": {"tma": {"cycle_dt": 30.0, "ctma": {"q1": 3.0}, "bounds": {"r_min": 500.0}}}}
    check_all(parse(doc))
    with pytest.raises(ConfigError) as e:
        check_all(parse({"sonar": {"tma": {"ctma": {"q9": 1.0}}}}))
    assert e.value.key == "sonar.tma.ctma.q9"
