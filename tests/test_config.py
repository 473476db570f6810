"""Deployment configuration: parsing, parameter sections, and the exit code 2 rule."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from common.deploy.config import ConfigError, load, parse, section

GOOD = """
[zenoh]
connect = ["tcp/127.0.0.1:7999"]
root = "pf/v1"

[[radar.base]]
id = "b1"
tx = [30000.0, 0.0, 100.0]
rx = [0.0, 0.0, 10.0]
channels = ["c1", "c2", "c3"]
p = 1

[[sonar.array]]
id = "a1"
kind = "linear"
sigma0 = 0.02

[radar.tracker]
gate_prob = 0.99
mode = "fast"
"""


@dataclass(frozen=True)
class Params:
    gate_prob: float = 0.95
    n_delete: int = 5
    mode: Literal["fast", "slow"] = "slow"


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "deploy.toml"
    p.write_text(text)
    return p


def test_good_file(tmp_path: Path) -> None:
    cfg = load(write(tmp_path, GOOD))
    assert cfg.zenoh.connect == ["tcp/127.0.0.1:7999"]
    b = cfg.base("b1")
    np.testing.assert_array_equal(b.tx, [30000.0, 0.0, 100.0])
    assert b.channels == ["c1", "c2", "c3"] and b.p == 1
    assert cfg.array("a1").kind == "linear"
    prm = section(cfg, "radar.tracker", Params)
    assert prm == Params(gate_prob=0.99, n_delete=5, mode="fast")
    assert section(cfg, "sonar.tracker", Params) == Params()


@pytest.mark.parametrize("change,key", [
    (('channels = ["c1", "c2", "c3"]', 'channels = []'), "radar.base[0].channels"),
    (('channels = ["c1", "c2", "c3"]', 'channels = ["c1", "c1"]'), "radar.base[0].channels"),
    (('id = "b1"', 'id = "B/1"'), "radar.base[0].id"),
    (("tx = [30000.0, 0.0, 100.0]", "tx = [1.0, 2.0]"), "radar.base[0].tx"),
    (("p = 1", "p = -1"), "radar.base[0].p"),
    (('kind = "linear"', 'kind = "towed"'), "sonar.array[0].kind"),
    (("sigma0 = 0.02", "sigma0 = -0.02"), "sonar.array[0].sigma0"),
    (('connect = ["tcp/127.0.0.1:7999"]', 'connect = ["127.0.0.1:7999"]'), "zenoh.connect"),
    (("gate_prob = 0.99", "gate_prb = 0.99"), "radar.tracker.gate_prb"),
    (("gate_prob = 0.99", 'gate_prob = "high"'), "radar.tracker.gate_prob"),
    (('mode = "fast"', 'mode = "medium"'), "radar.tracker.mode"),
])
def test_errors_name_the_key(tmp_path: Path, change: tuple[str, str], key: str) -> None:
    cfg_text = GOOD.replace(*change)
    with pytest.raises(ConfigError) as e:
        section(load(write(tmp_path, cfg_text)), "radar.tracker", Params)
    assert e.value.key == key


def test_not_toml_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not valid TOML"):
        load(write(tmp_path, "[zenoh\n"))
    with pytest.raises(ConfigError, match="does not exist"):
        load(tmp_path / "nope.toml")


def test_defaults() -> None:
    cfg = parse({})
    assert cfg.zenoh.root == "pf/v1" and cfg.bases == [] and cfg.arrays == []


def test_cli_exits_2_with_key_named(tmp_path: Path) -> None:
    bad = write(tmp_path, GOOD.replace("p = 1", "p = -1"))
    r = subprocess.run([sys.executable, "-m", "common.cli", "simulate", "--config", str(bad),
                        "--scenario", str(bad)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "radar.base[0].p" in r.stderr
