"""No password in any output, and the router's audit (docs/security.md, "Credentials in
logs" and "Audit"), on real processes of the secured deployment of test_security.py
(mutual TLS, passwords, the generated access control) over loopback.

Under RUST_LOG=trace (Zenoh's most verbose log, which prints the whole configuration
at debug) the fusion router, a site router (which has a password of its own towards
the fusion router), ``pfusion run`` on site rx1's host (its identity; its children
b1's plotter and elementary tracker log through it), global fusion, the simulator and
``pfusion status`` run; every log file, every process's output, and the
/proc/<pid>/cmdline and /proc/<pid>/environ of each process and its children while
they run hold no password of the dictionary, while the logs do hold Zenoh's trace lines
(the level was in force).
tests/bus/test_rust_log.py shows that the same check finds the password without the cap.

A router under the default RUST_LOG (warn) writes one WARNING per refusal, naming the
identity, the key and the cause: a wrong password (whose client's error names the
likely causes), an unknown user, a denied put
(200 of them: one line, all counted), a stolen password with another host's
certificate, a subscriber on a key the identity has no right to; not the routine
permission blocks of keys a session declares; its counters answer a query on
audit/router/main; Zenoh's debug and trace lines it reads for the audit do not reach
its log. Time: about 20 s for the first, 10 s
for the second on an idle machine."""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from common.bus import transport
from common.bus.procs import Child, pfusion_argv
from common.bus.transport import RouterUnreachable, free_port, open_session, wait_port
from common.cli import COMMANDS
from common.deploy.acl import access_control, router_identity, site_identity
from common.deploy.config import load
from common.deploy.deployment import plan
from common.wire import protocol
from services.router.main import may_use
from tests.integration.test_security import (
    SCENARIO,
    SITE_HOST,
    Secure,
    connects,
    deployment_files,
    on_host,
    put_all,
    zc,
)

ROOT = "pf/v1"
SCANS = 5


def passwords(d: Path) -> list[str]:
    return [line.partition(":")[2] for line in (d / "dictionary.txt").read_text().splitlines()
            if line.strip()]


@pytest.fixture
def trace_env() -> Iterator[None]:
    """RUST_LOG=trace for every child started meanwhile (children inherit os.environ)."""
    before = os.environ.get("RUST_LOG")
    os.environ["RUST_LOG"] = "trace"
    try:
        yield
    finally:
        if before is None:
            del os.environ["RUST_LOG"]
        else:
            os.environ["RUST_LOG"] = before


def family(pids: list[int]) -> set[int]:
    """``pids`` and all their descendants that run now."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    found, todo = set(), list(pids)
    while todo:
        pid = todo.pop()
        if pid not in found:
            found.add(pid)
            todo += parents.get(pid, [])
    return found


def proc_texts(pids: set[int]) -> dict[str, str]:
    """The command line and initial environment of each process of ``pids`` that still runs."""
    out = {}
    for pid in pids:
        try:
            out[f"/proc/{pid}"] = "".join(
                Path(f"/proc/{pid}/{f}").read_bytes().replace(b"\0", b" ").decode(errors="replace")
                for f in ("cmdline", "environ"))
        except OSError:  # it ended meanwhile
            pass
    return out


def test_no_password_in_any_output_under_rust_log_trace(tmp_path: Path, trace_env: None) -> None:
    fusion, site = deployment_files(tmp_path)
    logs = tmp_path / "logs"
    logs.mkdir()
    port, site_port = free_port(), free_port()
    ep, site_ep = f"tls/127.0.0.1:{port}", f"tls/127.0.0.1:{site_port}"
    children = [Child("router", "router", "--config", str(fusion), "--listen", ep,
                      log=logs / "router.log")]
    seen: dict[str, str] = {}
    try:
        wait_port(port, timeout=60.0)
        children.append(Child("router-rx1", "router", "--config", str(site), "--identity",
                              router_identity("rx1"), "--listen", site_ep, "--connect", ep,
                              log=logs / "router-rx1.log"))
        wait_port(site_port, timeout=60.0)
        specs = [s for s in plan(load(fusion), str(fusion), COMMANDS)
                 if s.name in ("channel-plotter/b1", "elementary-tracker/b1", "global-fusion")]
        # site rx1's host: pfusion run (its own identity) starts b1's plotter and tracker
        site_host = tmp_path / "site-host"
        site_host.mkdir()
        (site_host / "site.toml").write_text(SITE_HOST.format(d=tmp_path))
        mine = ("site-rx1", "channel-plotter-b1", "elementary-tracker-b1")
        (site_host / "credentials.txt").write_text("".join(
            f"{line}\n" for line in (tmp_path / "credentials.txt").read_text().splitlines()
            if line.partition(":")[0] in mine))
        (site_host / "credentials.txt").chmod(0o600)
        children.append(Child("run-rx1", "run", "--config", str(site_host / "site.toml"),
                              "--identity", "site-rx1", "--connect", site_ep, log=logs / "run-rx1.log"))
        children.append(Child("global-fusion", "global-fusion", "--config", str(fusion),
                              "--connect", ep, log=logs / "global-fusion.log"))
        sim = Child("simulate", "simulate", "--config", str(fusion), "--scenario", str(SCENARIO),
                    "--scans", str(SCANS), "--connect", ep, "--wait-timeout", "120",
                    *(a for s in specs for a in ("--wait-alive", s.alive)), log=logs / "simulate.log")
        children.append(sim)
        time.sleep(1.0)
        seen |= proc_texts(family([c.proc.pid for c in children]))  # the simulator while it waits
        assert sim.wait(240) == 0, (logs / "simulate.log").read_text()[-2000:]
        seen |= proc_texts(family([c.proc.pid for c in children]))  # run's children are alive now
        status = subprocess.run(pfusion_argv("status", "--config", str(fusion), "--connect", ep),
                                capture_output=True, text=True, timeout=120)
        seen["status"] = status.stdout + status.stderr
    finally:
        for c in reversed(children):
            c.stop()
    for f in logs.glob("*.log"):
        seen[f.name] = f.read_text(errors="replace")
    assert len([n for n in seen if n.endswith(".log")]) == 5
    assert len([n for n in seen if n.startswith("/proc/")]) >= 8, sorted(seen)  # run's children too
    assert "[channel-plotter/b1]" in seen["run-rx1.log"]  # its children log through it
    seen = {name: re.sub(r"\x1b\[[0-9;]*m", "", text) for name, text in seen.items()}
    for name, text in seen.items():
        leaked = [pw for pw in passwords(tmp_path) if pw in text]
        assert not leaked, f"a password in {name}"
    for name in ("router.log", "router-rx1.log", "global-fusion.log", "simulate.log", "run-rx1.log"):
        assert " TRACE " in seen[name], f"RUST_LOG=trace was not in force in {name}"
    assert " TRACE " in seen["status"]


@pytest.fixture
def audited(tmp_path: Path) -> Iterator[Secure]:
    """The fusion router under the children's default RUST_LOG (warn)."""
    fusion, site = deployment_files(tmp_path)
    port = free_port()
    ep = f"tls/127.0.0.1:{port}"
    env = os.environ.pop("RUST_LOG", None)
    try:
        router = Child("router", "router", "--config", str(fusion), "--listen", ep,
                       log=tmp_path / "router.log")
    finally:
        if env is not None:
            os.environ["RUST_LOG"] = env
    try:
        wait_port(port, timeout=60.0)
        yield Secure(tmp_path, fusion, site, load(fusion), ep)
    finally:
        router.stop()


def test_router_audits_denials_and_failed_logins(audited: Secure,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    s = audited
    monkeypatch.setattr(transport, "CONNECT_TIMEOUT_S", 3)
    wrong = s.dir / "wrong.txt"
    wrong.write_text("analyst:not-the-password\nnobody:x\n")
    wrong.chmod(0o600)
    good = zc(s, "analyst")
    assert good.auth is not None
    bad_auth = dataclasses.replace(good.auth, credentials=str(wrong))
    with pytest.raises(RouterUnreachable) as refused:
        open_session(dataclasses.replace(good, auth=bad_auth)).close()
    for cause in (f"wrong password for identity 'analyst' in {wrong}",
                  "the router's certificate is not signed by", "this host's certificate",
                  "the router is not running at that address", "'audit login_failed'"):
        assert cause in str(refused.value), str(refused.value)  # the client names the causes
    assert not connects(dataclasses.replace(good, identity="nobody", auth=bad_auth))
    with open_session(good) as session:
        put_all(zc(s, site_identity("rx1")), ["radar/gtracks"] * 200, declared=False)
        put_all(on_host(s, site_identity("rx1"), "host-rx2"), ["radar/plots/b1/c1"], declared=False)
        with open_session(zc(s, "viewer")) as viewer:  # a key the viewer may not use at all
            viewer.declare_subscriber(f"{ROOT}/radar/plots/b1/c1", lambda _: None)
            time.sleep(0.5)
        deadline = time.monotonic() + 60
        counts: dict[str, int] = {}
        while not (counts.get("denied", 0) >= 201 and counts.get("no_subject", 0) >= 1):
            assert time.monotonic() < deadline, counts
            time.sleep(0.2)
            replies = [r.ok for r in session.get(f"{ROOT}/audit/router/main", timeout=5.0) if r.ok]
            counts = protocol.unpack(replies[0].payload.to_bytes())["rejected"] if replies else {}
    assert counts["login_failed"] >= 2, counts
    log = (s.dir / "router.log").read_text()
    audit = [line.split("audit ", 2)[-1] for line in log.splitlines() if " WARNING audit: " in line]
    assert "login_failed: identity analyst@host from 127.0.0.1:" in "\n".join(audit), log
    assert any(a.startswith("login_failed: identity analyst@host") and a.endswith("(wrong password)")
               for a in audit), audit
    assert any(a.startswith("login_failed: identity nobody@host") and a.endswith("(unknown user)")
               for a in audit), audit
    denied = [a for a in audit if a.startswith("denied: identity site-rx1@host from ? key "
                                               f"{ROOT}/radar/gtracks (Put ingress)")]
    assert len(denied) == 1, audit  # 200 denials, one line in the period
    assert any(a.startswith("no_subject: identity site-rx1@host-rx2 from 127.0.0.1:") for a in audit)
    assert any(a == f"denied: identity viewer@host from ? key {ROOT}/radar/plots/b1/c1 (no right "
                    "at all on this key, ingress)" for a in audit), audit
    # the analyst's subscription to the router's metrics: a routine permission block
    assert not [a for a in audit if "analyst@host" in a and "login_failed" not in a], audit
    assert counts.get("key_denied", 0) >= 1
    assert " TRACE " not in log and " DEBUG " not in log  # read for the audit, not written


def test_a_declared_prefix_of_allowed_keys_is_no_attempt(tmp_path: Path) -> None:
    """A plotter subscribed to radar/plots/b1/* declares the prefix radar/plots/b1 too, on
    which Zenoh denies every kind of message: the audit asks the access control whether
    the identity has some right on or below a key before calling it an attempt."""
    fusion, _ = deployment_files(tmp_path)
    check = may_use(access_control(load(fusion)))
    assert check("channel-plotter-b1", f"{ROOT}/radar/plots/b1")
    assert check("global-fusion", f"{ROOT}/radar/etracks")
    assert not check("viewer", f"{ROOT}/radar/plots/b1/c1")
    assert not check("site-rx1", f"{ROOT}/radar/gtracks") and not check("nobody", ROOT)
