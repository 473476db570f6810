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
    r = subprocess.run([sys.executable, "-m", "common", "simulate", "--config", str(bad),
                        "--scenario", str(bad)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "radar.base[0].p" in r.stderr


@pytest.mark.parametrize("good_id", ["B1", "site.north", "b:1", "é-1", "x" * 60, "a@b"])
def test_ids_accept_what_a_zenoh_key_chunk_allows(tmp_path: Path, good_id: str) -> None:
    cfg = load(write(tmp_path, GOOD.replace('id = "b1"', f'id = "{good_id}"')))
    assert cfg.bases[0].id == good_id


@pytest.mark.parametrize("bad_id", ["", "b/1", "b*", "b$1", "b?", "b#1", "@b1", "b 1", "b\\t1"])
def test_ids_reject_what_a_key_chunk_cannot_hold(tmp_path: Path, bad_id: str) -> None:
    with pytest.raises(ConfigError, match="Zenoh key chunk") as e:
        load(write(tmp_path, GOOD.replace('id = "b1"', f'id = "{bad_id}"')))
    assert e.value.key == "radar.base[0].id"
    with pytest.raises(ConfigError) as e:
        load(write(tmp_path, GOOD.replace('"c2"', f'"{bad_id}"')))
    assert e.value.key == "radar.base[0].channels"


SECURE = GOOD + """
[zenoh.auth]
credentials = "creds.txt"
dictionary = "/etc/pfusion/dictionary.txt"

[zenoh.tls]
root_ca = "pki/ca.pem"
mtls = true

[[site]]
id = "rx1"
bases = ["b1"]
arrays = ["a1"]
"""


def test_security_tables_and_sites(tmp_path: Path) -> None:
    cfg = load(write(tmp_path, SECURE))
    assert cfg.zenoh.auth is not None and cfg.zenoh.tls is not None
    assert cfg.zenoh.auth.credentials == str(tmp_path / "creds.txt")
    assert cfg.zenoh.auth.dictionary == "/etc/pfusion/dictionary.txt"
    assert cfg.zenoh.auth.access_control
    assert cfg.zenoh.tls.root_ca == str(tmp_path / "pki/ca.pem") and cfg.zenoh.tls.cert == ""
    assert cfg.zenoh.tls.hosts == {}
    hosts = load(write(tmp_path, SECURE.replace("mtls = true", 'mtls = true\n[zenoh.tls.hosts]\n'
                                                 'host-rx1 = ["site-rx1", "viewer"]')))
    assert hosts.zenoh.tls is not None
    assert hosts.zenoh.tls.hosts == {"host-rx1": ["site-rx1", "viewer"]}
    assert [(s.id, s.bases, s.arrays) for s in cfg.sites] == [("rx1", ["b1"], ["a1"])]
    plain = load(write(tmp_path, GOOD))
    assert plain.zenoh.auth is None and plain.zenoh.tls is None
    assert [(s.id, s.bases, s.arrays) for s in plain.sites] == [("b1", ["b1"], []),
                                                                ("a1", [], ["a1"])]


@pytest.mark.parametrize("change,key", [
    (('credentials = "creds.txt"', 'credential = "creds.txt"'), "zenoh.auth.credential"),
    (('root_ca = "pki/ca.pem"', 'cert = "host.pem"'), "zenoh.tls.root_ca"),
    (("mtls = true", 'mtls = "yes"'), "zenoh.tls.mtls"),
    (("mtls = true", 'mtls = true\nhosts = ["h"]'), "zenoh.tls.hosts"),
    (("mtls = true", 'mtls = true\nhosts = {h = "site-rx1"}'), "zenoh.tls.hosts.h"),
    (('bases = ["b1"]', 'bases = ["b9"]'), "site[0].bases"),
    (('arrays = ["a1"]', 'arrays = "a1"'), "site[0].arrays"),
    (('id = "rx1"', 'id = "rx/1"'), "site[0].id"),
    (('id = "rx1"', 'name = "rx1"'), "site[0].name"),
    (('arrays = ["a1"]', 'arrays = ["a1"]\n[[site]]\nid = "rx2"\nbases = ["b1"]'), "site.bases"),
])
def test_security_errors_name_the_key(tmp_path: Path, change: tuple[str, str], key: str) -> None:
    with pytest.raises(ConfigError) as e:
        load(write(tmp_path, SECURE.replace(*change)))
    assert e.value.key == key
