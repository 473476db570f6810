"""docs/tutorial.md run as written: its files written, its commands run in order, each
``sh terminal`` block in a process of its own (left running, as in its own terminal),
each ``sh`` line to completion, in a fresh directory.

Substitutions, so that the test neither collides with a parallel run nor needs ports
7448 and 8080 free: the router endpoint and the page's port become free 127.0.0.1
ports. ``.venv/bin/X`` is the X of the interpreter running the tests (PYTHONPATH = this
tree). Bounded: the whole run under 90 s."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

from common.bus.transport import free_port
from tests.docs.blocks import DOCS, REPO

TUTORIAL = DOCS / "tutorial.md"
BUDGET_S = 90.0
# what a terminal prints when it is ready, by pfusion subcommand
READY = {"run": "global_fusion[main]: running", "view": "view: http://127.0.0.1:",
         "evaluate": "evaluate[main]: running"}


def steps() -> list[tuple[str, str]]:
    """(info string, body) of every fenced block of the tutorial, in order."""
    return [(m.group(1).strip(), m.group(2)) for m in
            re.finditer(r"^```([^\n`]*)\n(.*?)^```\s*$", TUTORIAL.read_text(), re.M | re.S)]


class Term:
    """One command in its own process, in the tutorial's directory; output lines kept."""

    def __init__(self, argv: list[str], cwd: Path, env: dict[str, str]) -> None:
        self.argv = argv
        self.proc = subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        self.reader = threading.Thread(target=lambda: self.lines.extend(iter(self.proc.stdout.readline, "")),
                                       daemon=True)
        self.reader.start()

    def wait_for(self, text: str, deadline: float) -> None:
        while not any(text in line for line in list(self.lines)):
            assert self.proc.poll() is None, f"{self.argv} exited {self.proc.returncode}:\n{self.log()}"
            assert time.monotonic() < deadline, f"{self.argv}: no '{text}' in time:\n{self.log()}"
            time.sleep(0.1)

    def log(self) -> str:
        return "".join(self.lines[-40:])


def as_run(line: str, subs: dict[str, str]) -> list[str]:
    for old, new in subs.items():
        line = line.replace(old, new)
    argv = shlex.split(line)
    assert argv[0].startswith(".venv/bin/"), line
    return [str(Path(sys.executable).parent / argv[0].removeprefix(".venv/bin/")), *argv[1:]]


def test_tutorial_as_written(tmp_path: Path) -> None:
    start = time.monotonic()
    deadline = start + BUDGET_S
    router, page = free_port(), free_port()
    subs = {"tcp/127.0.0.1:7448": f"tcp/127.0.0.1:{router}", "--port 8080": f"--port {page}"}
    env = {**os.environ, "PYTHONPATH": str(REPO), "PYTHONUNBUFFERED": "1"}
    kinds = [info for info, _ in steps()]
    assert kinds == ["toml my_site.toml", "sh", "sh terminal", "sh terminal", "sh terminal",
                     "python my_feed.py", "sh", "sh"], kinds
    terms: dict[str, Term] = {}
    try:
        for info, body in steps():
            kind, _, name = info.partition(" ")
            if name and kind in ("toml", "python"):
                for old, new in subs.items():
                    body = body.replace(old, new)
                (tmp_path / name).write_text(body)
                continue
            for line in (x for x in body.splitlines() if x.strip()):
                argv = as_run(line, subs)
                if name == "terminal":
                    sub = shlex.split(line)[1]
                    terms[sub] = Term(argv, tmp_path, env)
                    terms[sub].wait_for(READY[sub], deadline)
                else:
                    r = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True,
                                       timeout=max(1.0, deadline - time.monotonic()))
                    assert r.returncode == 0, f"{line}\n{r.stdout}\n{r.stderr}"
                    if "params --check" in line:
                        assert r.stdout.strip() == "my_site.toml: valid"
                    if "status" in line:
                        assert "global_fusion" in r.stdout and "bearing_tracker" in r.stdout, r.stdout
        with urllib.request.urlopen(f"http://127.0.0.1:{page}/", timeout=10) as resp:
            assert resp.status == 200 and b"<html" in resp.read()
        ev = terms["evaluate"]
        ev.proc.wait(timeout=max(1.0, deadline - time.monotonic()))
        ev.reader.join(5)
        assert ev.proc.returncode == 0, ev.log()
        final = "".join(ev.lines)
        steps_scored = re.search(r"^steps (\d+) ", final, re.M)
        assert steps_scored and int(steps_scored.group(1)) >= 60, final  # 90 scans, the first unconfirmed
        assert re.search(r"^\s+1\s+\d+\s+[\d.]+\s+[\d.]+", final, re.M), final
    finally:
        codes = {}
        for sub in ("view", "run", "evaluate"):
            t = terms.get(sub)
            if t is not None:
                if t.proc.poll() is None:
                    t.proc.send_signal(2)  # Ctrl-C, as step 9 says
                try:
                    codes[sub] = t.proc.wait(30)
                except subprocess.TimeoutExpired:
                    t.proc.kill()
                    codes[sub] = None
    assert codes == {"view": 0, "run": 0, "evaluate": 0}, {s: terms[s].log() for s in terms}
    assert any("[run] stopped" in line for line in terms["run"].lines)
    assert time.monotonic() - start < BUDGET_S
