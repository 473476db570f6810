"""``pfusion`` itself: --version, an example in every --help, and one clear line with
exit code 2 (never a traceback) when a command's router is unreachable or a router
cannot listen."""

from __future__ import annotations

import argparse
import importlib
import shlex
import socket
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from common.bus.procs import pfusion_argv
from common.bus.recording import RecordWriter
from common.bus.transport import CONNECT_TIMEOUT_S, free_port
from common.cli import COMMANDS, EXAMPLES

REPO = Path(__file__).resolve().parents[2]
TWO = "scenarios/two_targets.toml"
SONAR = "scenarios/sonar_tma.toml"

# Commands that never connect to a router, and why.
NO_ROUTER = {
    "router": "it is the router: it listens (a busy port is tested below)",
    "demo": "starts its own router on a free loopback port",
    "params": "prints or checks the configuration, no Zenoh at all",
    "acl": "prints the access control generated from a deployment, no Zenoh session",
}
# The arguments of every other command, before --connect; {tmp} is a scratch folder.
ARGS = {
    "simulate": f"--config {TWO} --scenario {TWO}",
    "watch": f"--config {TWO} 'radar/gtracks'",
    "bearing-tracker": f"--config {SONAR} --array a1",
    "tma": f"--config {SONAR} --array a1",
    "tma-input": f"clear --config {SONAR} --array a1 --track 1",
    "channel-plotter": f"--config {TWO} --base b1",
    "elementary-tracker": f"--config {TWO} --base b1",
    "run": f"--config {TWO}",
    "status": f"--config {TWO}",
    "record": f"--config {TWO} 'radar/**' --out {{tmp}}/out.pfrec",
    "replay": "{tmp}/in.pfrec",
    "global-fusion": f"--config {TWO}",
    "evaluate": f"--config {TWO}",
    "view": f"--config {TWO} --port 0",
    "export": "--config scenarios/geodetic_two_targets.toml --geojson {tmp}/out.geojson --seconds 1",
    "ingest": f"csv {{tmp}}/in.pfrec --config {TWO}",
}


def run(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(pfusion_argv(*args), cwd=REPO, capture_output=True, text=True,
                          timeout=timeout)


def test_every_command_is_either_tested_unreachable_or_says_why_not() -> None:
    assert set(COMMANDS) == set(ARGS) | set(NO_ROUTER)
    assert not set(ARGS) & set(NO_ROUTER)


def test_version() -> None:
    out = run("--version")
    assert out.returncode == 0 and out.stdout.strip() == "pfusion 0.1.0"


def test_top_help_shows_examples_and_every_command() -> None:
    out = run("--help")
    assert out.returncode == 0, out.stderr
    assert f"examples:\n  {EXAMPLES['run']}\n" in out.stdout
    for name in COMMANDS:
        assert name in out.stdout


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_example_is_valid_for_its_command(name: str) -> None:
    argv = shlex.split(EXAMPLES[name])
    assert argv[:2] == ["pfusion", name]
    p = argparse.ArgumentParser(exit_on_error=False)
    importlib.import_module(COMMANDS[name][0]).add_arguments(p)
    try:
        args = p.parse_args(argv[2:])
    except SystemExit as e:
        raise AssertionError(f"{EXAMPLES[name]}: invalid arguments") from e
    for opt in ("config", "scenario", "check"):
        if getattr(args, opt, None):
            assert (REPO / getattr(args, opt)).is_file(), EXAMPLES[name]


def test_help_of_one_command_shows_its_example() -> None:
    # one subprocess: the epilog is built by common.cli.main for every command alike
    out = run("watch", "--help")
    assert out.returncode == 0, out.stderr
    assert out.stdout.rstrip().endswith(f"example:\n  {EXAMPLES['watch']}")


@pytest.fixture(scope="module")
def unreachable(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Every command of ARGS started at once (they wait CONNECT_TIMEOUT_S each) with
    --connect to a loopback port where nothing listens; name -> (code, stderr, seconds)."""
    tmp = tmp_path_factory.mktemp("cli")
    with (tmp / "in.pfrec").open("wb") as f:
        RecordWriter(f, "pf/v1", 0.0).write("pf/v1/sim/status", 0.0, b"\x80")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    started = time.monotonic()
    procs = {name: subprocess.Popen(
        pfusion_argv(name, *shlex.split(a.format(tmp=tmp)), "--connect", endpoint), cwd=REPO,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True) for name, a in ARGS.items()}
    results = {}
    for name, p in procs.items():  # generous: a dozen interpreters start on a loaded machine
        _, err = p.communicate(timeout=max(1.0, started + 240 - time.monotonic()))
        results[name] = (p.returncode, err, time.monotonic() - started)
    return {"endpoint": endpoint, "results": results, "tmp": tmp}


@pytest.mark.parametrize("name", sorted(ARGS))
def test_unreachable_router_gives_one_line_and_code_2(name: str, unreachable: dict[str, Any]) -> None:
    code, err, _ = unreachable["results"][name]
    endpoint = unreachable["endpoint"]
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert lines == [
        f"pfusion {name}: no Zenoh router reachable at {endpoint} (nothing answered within "
        f"{CONNECT_TIMEOUT_S} s): start one with 'pfusion router --listen {endpoint}', "
        "or pass --connect ENDPOINT"], err
    if name == "record":
        assert not (unreachable["tmp"] / "out.pfrec").exists()


def test_router_on_a_busy_port_gives_one_line_and_code_2() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        endpoint = f"tcp/127.0.0.1:{busy.getsockname()[1]}"
        out = run("router", "--listen", endpoint)
    assert out.returncode == 2, out.stderr
    [line] = [s for s in out.stderr.splitlines() if s.strip()]
    assert line.startswith(f"pfusion router: Can not create a new TCP listener bound to {endpoint}")
    assert "Address already in use" in line and ".rs:" not in line
