"""README "A session by hand", run as written: its four lines (read from README.md) as
four real processes, the way four terminals would run them.

One substitution, so that the test neither collides with another test run in parallel
nor depends on port 7447 being free on the machine: ``--config scenarios/two_targets.toml``
becomes a copy of that file whose ``[zenoh] connect`` is a free loopback port (the
original sets no endpoint, so every command uses the default ``tcp/127.0.0.1:7447``; that
``run --with-router`` then listens there is ``test_run.test_router_endpoint_choice``).
``.venv/bin/pfusion`` is the ``pfusion`` of the interpreter running the tests (the same
file under ``make test``). The simulator runs at the README's ``--speed 1`` until the
global tracks and every service's counters are seen, then each terminal gets its Ctrl-C.
"""

from __future__ import annotations

import re
import shlex
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from common.bus.transport import free_port
from common.cli import COMMANDS
from common.deploy.config import load
from common.deploy.deployment import plan
from tests.harness import REPO, TIMEOUT_S, Terminal

CONFIG = "scenarios/two_targets.toml"


def readme_session() -> list[list[str]]:
    """The shell lines of the code block after "A session by hand", split like sh does."""
    text = (REPO / "README.md").read_text()
    block = re.search(r"A session by hand.*?```sh\n(.*?)```", text, re.S)
    assert block, "README.md has no 'A session by hand' sh block"
    return [shlex.split(line) for line in block.group(1).splitlines() if line.strip()]


def as_tested(argv: list[str], config: Path) -> list[str]:
    """``argv`` with the README's config replaced by ``config`` (and the entry point)."""
    assert argv[0] == ".venv/bin/pfusion", argv
    out = [str(Path(sys.executable).parent / "pfusion"), *argv[1:]]
    i = out.index("--config")
    assert out[i + 1] == CONFIG, argv
    out[i + 1] = str(config)
    return out


def config_on(tmp: Path, endpoint: str) -> Path:
    """A copy of the README's config whose [zenoh] connect is ``endpoint``."""
    text = (REPO / CONFIG).read_text()
    assert text.count("\n[zenoh]\n") == 1 and "connect" not in text.split("\n[radar]")[0]
    path = tmp / "two_targets.toml"
    path.write_text(text.replace("\n[zenoh]\n", f'\n[zenoh]\nconnect = ["{endpoint}"]\n'))
    return path


def status_rows(argv: list[str]) -> dict[str, list[str]]:
    """Run the README's status line once: service/instance -> its table row."""
    out = subprocess.run(argv, cwd=REPO, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert out.returncode == 0, out.stderr
    rows = [line.split() for line in out.stdout.splitlines()[1:] if line.strip()]
    return {f"{r[0]}/{r[1]}": r for r in rows if len(r) >= 4}


def running(lines: list[str]) -> set[str]:
    """The children of ``pfusion run`` that logged "running" (their token is declared)."""
    return {m.group(1) for line in list(lines) if (m := re.match(r"^\[(\S+)\] .* running$", line))}


@pytest.mark.slow
def test_readme_session_by_hand(tmp_path: Path) -> None:
    run_line, watch_line, status_line, sim_line = readme_session()
    assert (run_line[1], watch_line[1], status_line[1], sim_line[1]) == (
        "run", "watch", "status", "simulate")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    config = config_on(tmp_path, endpoint)
    specs = plan(load(REPO / CONFIG), "", COMMANDS)
    names = {s.name for s in specs}
    services = {s.alive.replace("/*", "/main") for s in specs}
    run = Terminal(as_tested(run_line, config))
    watch = sim = None
    try:
        run.wait_for("the router", lambda: f"[run] router listening on {endpoint} "
                     f"([zenoh] connect of {config})" in run.err)
        watch = Terminal(as_tested(watch_line, config))
        run.wait_for("every service running", lambda: running(run.err) == names)
        sim = Terminal(as_tested(sim_line, config))
        watch.wait_for("global tracks of both targets",
                       lambda: any(re.search(r" pf/v1/radar/gtracks tracks=2 ", line)
                                   for line in watch.out))
        rows = status_rows(as_tested(status_line, config))
        assert set(rows) == services | {"simulate/two_targets"}
        assert all(rows[s][2].isdigit() and int(rows[s][2]) > 0 and int(rows[s][3]) > 0
                   for s in services), rows
        assert sim.proc.poll() is None, "the simulator at --speed 1 ended before the check"
    finally:
        codes = [t.ctrl_c() for t in (sim, watch, run) if t is not None]
    assert codes == [0, 0, 0], f"{codes}\n{run.log()}"
    assert run.err[-1] == "[run] stopped"
    assert not any("Traceback" in line for t in (run, watch, sim) for line in t.err)


def test_run_with_router_on_a_busy_port_says_so_and_exits_2(tmp_path: Path) -> None:
    run_line = readme_session()[0]
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        endpoint = f"tcp/127.0.0.1:{busy.getsockname()[1]}"
        config = config_on(tmp_path, endpoint)
        out = subprocess.run(as_tested(run_line, config), cwd=REPO, capture_output=True,
                             text=True, timeout=TIMEOUT_S)
    assert out.returncode == 2, out.stderr
    assert out.stderr.splitlines() == [
        f"pfusion run: cannot listen on {endpoint} ([zenoh] connect of {config}): Address "
        "already in use; if a router already runs there, drop --with-router, else free the "
        "port or choose another with --connect"]
