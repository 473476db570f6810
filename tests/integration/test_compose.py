"""docker-compose.yml and Dockerfile, checked without a Docker engine: every command is a
valid ``pfusion`` invocation for the real CLI parsers, every config file it names loads,
the services reach the router by its compose name and the simulators wait for tokens that
the compose services declare."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

import pytest
import yaml

from common.cli import COMMANDS
from common.deploy.config import load
from common.deploy.deployment import token_name

REPO = Path(__file__).resolve().parents[2]
COMPOSE = yaml.safe_load((REPO / "docker-compose.yml").read_text())
SERVICES = COMPOSE["services"]
ROUTER = "tcp/router:7447"


def parse(argv: list[str]) -> argparse.Namespace:
    """Parse ``pfusion ARGV`` with the command's own parser (as common.cli.main does)."""
    module = importlib.import_module(COMMANDS[argv[0]][0])
    p = argparse.ArgumentParser(prog=f"pfusion {argv[0]}", exit_on_error=False)
    module.add_arguments(p)
    try:
        return p.parse_args(argv[1:])
    except SystemExit as e:
        raise AssertionError(f"pfusion {' '.join(argv)}: invalid arguments") from e


def token(argv: list[str], args: argparse.Namespace) -> str:
    """The liveliness name of a service container (service/instance)."""
    instance = getattr(args, "base", None) or getattr(args, "array", None) or "*"
    return f"{token_name(argv[0])}/{instance}"


@pytest.mark.parametrize("name", sorted(SERVICES))
def test_every_command_is_a_valid_pfusion_invocation(name: str) -> None:
    argv = SERVICES[name]["command"]
    assert all(isinstance(a, str) for a in argv), name
    assert argv[0] in COMMANDS, f"{name}: unknown command {argv[0]}"
    args = parse(argv)
    for opt in ("config", "scenario"):
        if getattr(args, opt, None):
            assert load(REPO / getattr(args, opt)).path is not None
    if argv[0] == "router":
        assert args.listen == ["tcp/0.0.0.0:7447"]
    elif getattr(args, "config", None) and not args.connect:
        assert load(REPO / args.config).zenoh.connect == [ROUTER], name
    else:
        assert args.connect == [ROUTER], name


def test_sample_deployment_runs_every_service_once() -> None:
    cfg = load(REPO / "deploy" / "sample.toml")
    assert cfg.zenoh.connect == [ROUTER]
    want = {f"channel-plotter-{b.id}" for b in cfg.bases} | {
        f"elementary-tracker-{b.id}" for b in cfg.bases} | {"global-fusion"} | {
        f"bearing-tracker-{a.id}" for a in cfg.arrays} | {f"tma-{a.id}" for a in cfg.arrays}
    assert [b.id for b in cfg.bases] == ["b1", "b2", "b3"] and [a.id for a in cfg.arrays] == ["a1"]
    always = {n for n, s in SERVICES.items() if "profiles" not in s}
    assert always == want | {"router"}
    assert {n for n, s in SERVICES.items() if "sim" in s.get("profiles", [])} == {
        "simulate-radar", "simulate-sonar"}
    for n in always - {"router"}:
        assert SERVICES[n]["depends_on"] == ["router"], n


def test_simulators_wait_for_the_compose_services() -> None:
    tokens = set()
    for s in SERVICES.values():
        argv = s["command"]
        if argv[0] in ("channel-plotter", "elementary-tracker", "global-fusion",
                       "bearing-tracker", "tma") and "profiles" not in s:
            ns = argparse.Namespace(base=argv[argv.index("--base") + 1] if "--base" in argv else None,
                                    array=argv[argv.index("--array") + 1] if "--array" in argv else None)
            tokens.add(token(argv, ns))
    waited = set()
    for name in ("simulate-radar", "simulate-sonar"):
        args = parse(SERVICES[name]["command"])
        waited |= set(args.wait_alive)
        assert load(REPO / args.scenario).path is not None
    assert waited == tokens


def test_dockerfile_installs_the_project_with_pfusion_as_entrypoint() -> None:
    lines = [line.strip() for line in (REPO / "Dockerfile").read_text().splitlines()
             if line.strip() and not line.startswith("#")]
    assert lines[0] == "FROM python:3.11-slim"
    assert "RUN pip install --no-cache-dir ." in lines
    assert lines[-1] == 'ENTRYPOINT ["pfusion"]'
    copied = {line.split()[1] for line in lines if line.startswith("COPY ")}
    assert {"pyproject.toml", "common", "services", "scenarios", "deploy"} <= copied
    for c in copied:
        assert (REPO / c).exists(), c
