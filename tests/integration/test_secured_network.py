"""Issue 33: the secured multi-host deployment end to end, as docs/security.md gives it.

Three hosts as network namespaces (tests/netns.py): the fusion host and two receiver
sites, each with its own router; site1's link impaired (50 ms delay, 10 ms jitter, 1 %
loss each way: tests/netem.py where the kernel has no sch_netem). One test, in order:

1. **The docs' steps.** Every ``sh`` block of docs/security.md's "Secure deployment,
   step by step" runs as written on the host its info string names (``ca``: the test
   host, in the CA's working directory; ``service`` blocks: one process per line, left
   running), with ``/etc/pfusion`` of each host, ``~/passive-fusion`` and 192.0.2.10
   replaced by temporary directories, this tree and the hub's address; each step's
   outcome is checked (certificate names, files and modes, the rules, the routers
   listening, every service listed by ``pfusion status``).
2. **Load.** A simulator per site as its feed (identity ``simulator``, which the test
   adds to the site hosts: the docs say never in production) publishes
   scenarios/two_targets.toml at SPEED x real time; global tracks flow at the fusion
   host.
3. **Nothing forged gets through.** From site2's host: site1's stolen password with
   site2's certificate, site2's own identity, and site2's router password with the
   host's certificate put forged samples on b1's plots, global and elementary tracks;
   none reaches an analyst at the fusion host, and b1's plotter rejects nothing.
4. **A cut link.** site2's link down for CUT_S: global tracks keep flowing (b1, b2),
   ``pfusion status`` at the fusion host no longer lists b3's services; after the
   restore it lists them again and b3's elementary tracks are fused again.
5. **Rotation under load.** The blocks of "Removing an identity" retire site2's analyst
   console (its line in [zenoh.tls.hosts], its password); a rolling restart of the
   three routers (fusion first, each when the previous one's clients are back) while
   the simulators run. Afterwards site2's analyst session, connected before, receives
   nothing, and a new one with the old password is refused; every other process goes
   on without a restart; the elementary tracks lost during the roll are counted and
   bounded (ROLL_LOSS_MAX scans per base), and none is lost outside the cut (b3) and
   the restarts (the impaired link loses nothing).

The numbers go to out/secured_network.json (and docs/security.md, "Tested end to end").
"""

from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from common.bus.procs import pfusion_argv
from tests.harness import REPO, SCENARIOS
from tests.integration.test_multihost import Collector
from tests.netns import HUB_ADDRESS, NsProcess, Topology, require

SECURITY = REPO / "docs" / "security.md"
SCENARIO = SCENARIOS / "two_targets.toml"
EXAMPLE_HUB = "192.0.2.10"
HOSTS = ("fusion", "site1", "site2")
SITE_BASES = {"site1": ("b1", "b2"), "site2": ("b3",)}
SERVICES = [f"{svc}/{b}" for bases in SITE_BASES.values() for b in bases
            for svc in ("channel_plotter", "elementary_tracker")] + ["global_fusion/main"]
SPEED = 4.0  # scans of 1 s per wall second
CUT_S = 6.0
ROLL_LOSS_MAX = 80  # scans (20 s at SPEED) of elementary tracks lost per base in the roll
SLACK = 2  # scans in flight when a window opens or closes
WAIT_S = 120.0  # generous: a loaded 2-core machine


@dataclass(frozen=True)
class Step:
    """One ``sh`` block of docs/security.md: its host, whether it is a service block,
    the part of the page it belongs to, its body (dedented)."""

    host: str
    service: bool
    part: str
    body: str


def doc_steps() -> list[Step]:
    """The ``sh`` blocks of the deployment steps and of the rotation, in page order."""
    text = SECURITY.read_text()
    deploy = text[text.index("## Secure deployment, step by step"):]
    deploy = deploy[:deploy.index("\n## ")]
    rotate = text[text.index("**Removing an identity or a host**"):]
    rotate = rotate[:rotate.index("\n## ")] if "\n## " in rotate else rotate
    steps = []
    for part, chunk in (("deploy", deploy), ("rotate", rotate)):
        for m in re.finditer(r"^( *)```([^\n`]*)\n(.*?)^\1```\s*$", chunk, re.M | re.S):
            info = m.group(2).split()
            if not info or info[0] != "sh":
                continue
            assert len(info) >= 2 and info[1] in ("ca", *HOSTS), f"sh block without a host: {info}"
            body = textwrap.dedent(m.group(3))
            assert body.startswith(f"# {info[1]}"), f"the first line must name the host: {body}"
            steps.append(Step(info[1], info[2:] == ["service"], part, body))
    return steps


class Secured:
    """The hosts, their directories (``/etc/pfusion`` of each, the CA's), the processes."""

    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self.ca = tmp / "ca"
        self.ca.mkdir()
        self.net = Topology(tmp / "logs")
        try:
            self.net.add_site("site1", 1, impaired=True)
            self.net.add_site("site2", 2)
        except BaseException:
            self.net.close()
            raise
        self.routers: dict[str, tuple[list[str], NsProcess]] = {}
        self.services: list[str] = []  # their log names
        self.collectors: dict[str, Collector] = {}
        self.sims: list[NsProcess] = []
        self.retired: list[NsProcess] = []  # stopped on purpose, or refused on purpose

    def etc(self, host: str) -> Path:
        return self.ca / host

    def subs(self, text: str, host: str) -> str:
        text = text.replace("~/passive-fusion", str(REPO)).replace(EXAMPLE_HUB, HUB_ADDRESS)
        return text.replace("/etc/pfusion", str(self.etc(host))) if host != "ca" else text

    def shell(self, host: str, body: str, check: bool = True) -> subprocess.CompletedProcess[str]:
        """Run a block with bash -eu (``pfusion`` = this tree's CLI) on ``host``."""
        script = (f'pfusion() {{ {shlex.quote(sys.executable)} -m common "$@"; }}\n'
                  + self.subs(body, host))
        argv = ["bash", "-euo", "pipefail", "-c", script]
        if host != "ca":
            argv = ["ip", "netns", "exec", self.net.ns[host], *argv]
        r = subprocess.run(argv, cwd=self.ca, capture_output=True, text=True, timeout=WAIT_S,
                           env={"PATH": "/usr/sbin:/usr/bin:/sbin:/bin", "HOME": str(self.tmp),
                                "PYTHONPATH": str(REPO), "OMP_NUM_THREADS": "1"})
        if check:
            assert r.returncode == 0, f"{host}: {body}\n{r.stdout}\n{r.stderr}"
        return r

    def service(self, host: str, line: str) -> NsProcess:
        argv = shlex.split(self.subs(line, host))
        assert argv[0] == "pfusion", line
        inst = next((argv[i + 1] for i, a in enumerate(argv) if a == "--base"), "")
        name = "-".join(x for x in (host, argv[1], inst) if x)
        if argv[1] != "router":  # the routers start together; a client gives up after 10 s
            self.wait(lambda: all("router listening" in self.log(f"{h}-router") for h in self.routers),
                      "routers listening")
        p = self.net.start(host, pfusion_argv(*argv[1:]), name)
        if argv[1] == "router":
            self.routers[host] = (argv[1:], p)
        else:
            self.services.append(name)
        return p

    def log(self, name: str) -> str:
        f = self.net.logdir / f"{name}.log"
        return f.read_text(errors="replace") if f.exists() else ""

    def wait(self, predicate: Callable[[], bool], what: str, timeout: float = WAIT_S) -> None:
        deadline = time.monotonic() + timeout
        while not predicate():
            for p in self.net.processes:
                if not p.alive() and p not in self.sims + self.retired and p.proc.returncode:
                    raise AssertionError(f"{p.name} exited with {p.proc.returncode}:\n"
                                         f"{self.log(p.name)[-3000:]}")
            assert time.monotonic() < deadline, f"{what}: not within {timeout} s"
            time.sleep(0.1)

    def status(self, body: str = "pfusion status --config /etc/pfusion/pfusion.toml") -> set[str]:
        """``pfusion status`` at the fusion host (as viewer): the services it lists."""
        r = self.shell("fusion", body)
        return {"/".join(line.split()[:2]) for line in r.stdout.splitlines()[1:] if line.split()}

    def close(self) -> None:
        self.net.close()


def add_test_feed(s: Secured) -> None:
    """The test's feed: identity ``simulator`` on both site hosts ([zenoh.tls.hosts] of
    every copy of the file, a password in each site's credentials and dictionary)."""
    line = "simulator:feed-of-the-test-only\n"
    for host in HOSTS:
        f = s.etc(host) / "pfusion.toml"
        text = f.read_text()
        for site in SITE_BASES:
            text = text.replace(f"host-{site} = [", f'host-{site} = ["simulator", ')
        f.write_text(text)
    for site in SITE_BASES:
        for name in ("credentials.txt", "dictionary.txt"):
            with (s.etc(site) / name).open("a") as fh:
                fh.write(line)


def pw_users(path: Path) -> list[str]:
    return [line.partition(":")[0] for line in path.read_text().splitlines() if line]


def check_files(s: Secured) -> None:
    """Step 2's outcome: each host's files, modes, and whose passwords they hold."""
    hosts = {}
    for line in (REPO / "deploy" / "secured" / "pfusion.toml").read_text().splitlines():
        if m := re.match(r'^host-(\w+) = (\[.*\])$', line):
            hosts[m.group(1)] = json.loads(m.group(2))
    assert set(hosts) == set(HOSTS)
    for h in HOSTS:
        d = s.etc(h)
        for f in ("ca.pem", "host.pem", "host.key", "router.pem", "router.key",
                  "credentials.txt", "dictionary.txt", "pfusion.toml"):
            assert (d / f).is_file(), d / f
        for f in ("host.key", "router.key", "credentials.txt", "dictionary.txt"):
            assert (d / f).stat().st_mode & 0o077 == 0, d / f
        routers = [f"router-{h}"] if h != "fusion" else []
        assert pw_users(d / "credentials.txt") == hosts[h] + routers, h
        upstream = [f"router-{x}" for x in SITE_BASES] if h == "fusion" else []
        assert pw_users(d / "dictionary.txt") == hosts[h] + upstream, h


def start_load(s: Secured) -> None:
    """Collectors (analyst) at the fusion host and at site2, a simulator per site."""
    keys = {"fusion": ["radar/gtracks", "radar/etracks/*", "radar/plots/b1/*", "metrics/**"],
            "site2": ["radar/gtracks"]}
    for host, keyexprs in keys.items():
        argv = [sys.executable, "-m", "tests.remote_collector", "--connect", "tls/127.0.0.1:7447",
                "--config", str(s.etc(host) / "pfusion.toml"), "--identity", "analyst",
                "--name", host, "--token", f"alive/record/{host}", *keyexprs]
        s.collectors[host] = Collector(s.net.start(host, argv, f"{host}-collector",
                                                   stdout=subprocess.PIPE))
    alive = [*SERVICES, "record/fusion", "record/site2"]
    for site in SITE_BASES:
        cfg = s.tmp / f"sim-{site}.toml"  # the site's bases only (deploy/multisite), secured
        text = (REPO / "deploy" / "multisite" / f"{site}.toml").read_text()
        cfg.write_text(text.replace("tcp/127.0.0.1:7447", "tls/127.0.0.1:7447") + (
            f'\n[zenoh.auth]\ncredentials = "{s.etc(site)}/credentials.txt"\n'
            f'[zenoh.tls]\nroot_ca = "{s.etc(site)}/ca.pem"\ncert = "{s.etc(site)}/host.pem"\n'
            f'key = "{s.etc(site)}/host.key"\nmtls = true\n'))
        argv = ["simulate", "--config", str(cfg), "--scenario", str(SCENARIO), "--seed", "1",
                "--speed", str(SPEED), "--scans", "600", "--wait-timeout", str(WAIT_S)]
        for name in alive:
            argv += ["--wait-alive", name]
        s.sims.append(s.net.start(site, pfusion_argv(*argv), f"{site}-simulate"))


FORGED = ["radar/plots/b1/c1", "radar/gtracks", "radar/etracks/b1"]


def try_as(s: Secured, identity: str, password_line: str, endpoint: str) -> dict[str, object]:
    """tests/forger.py on site2's host, with site2's certificate, as ``identity`` (its
    ``user:password`` line), at ``endpoint``: puts b"forged" on FORGED."""
    site2 = s.etc("site2")
    creds = s.tmp / f"stolen-{identity}.txt"
    creds.write_text(password_line + "\n")
    creds.chmod(0o600)
    (s.tmp / "ca.pem").write_bytes((site2 / "ca.pem").read_bytes())
    cfg = s.tmp / f"forger-{identity}.toml"
    cfg.write_text((site2 / "pfusion.toml").read_text().replace(
        'credentials = "credentials.txt"', f'credentials = "{creds}"'))
    argv = ["ip", "netns", "exec", s.net.ns["site2"], sys.executable, "-m", "tests.forger",
            "--config", str(cfg), "--identity", identity, "--cert", str(site2 / "host.pem"),
            "--key", str(site2 / "host.key"), "--connect", endpoint, *FORGED]
    r = subprocess.run(argv, capture_output=True, text=True, timeout=WAIT_S, cwd=REPO)
    assert r.returncode == 0, r.stderr
    return {"identity": identity, "at": endpoint, **json.loads(r.stdout.splitlines()[-1])}


def password_line(s: Secured, host: str, identity: str) -> str:
    return next(line for line in (s.etc(host) / "credentials.txt").read_text().splitlines()
                if line.startswith(f"{identity}:"))


def forge(s: Secured) -> list[dict[str, object]]:
    """From site2's host, with site2's certificate: (a) router-site1's stolen password at
    the fusion router; site2's own identity at its router; (b) router-site2's password
    (in the host's credentials file) at the fusion router. Each session is let in (the
    passwords are right)."""
    hub = f"tls/{HUB_ADDRESS}:7447"
    out = [try_as(s, "router-site1", password_line(s, "site1", "router-site1"), hub),
           try_as(s, "site-site2", password_line(s, "site2", "site-site2"), "tls/127.0.0.1:7447"),
           try_as(s, "router-site2", password_line(s, "site2", "router-site2"), hub)]
    assert all(f["opened"] and f["put"] == 15 for f in out), out
    return out


def arrivals(c: Collector, suffix: str) -> list[tuple[float, float]]:
    """(arrival time, message t) of every sample of key ``suffix``."""
    return [(r.at, r.msg["t"]) for r in c.of(suffix)]


def missing(c: Collector, base: str, lo: float, hi: float) -> list[float]:
    """Scan times in [lo, hi] without an elementary tracks message of ``base``."""
    got = {t for _, t in arrivals(c, f"radar/etracks/{base}")}
    return [float(t) for t in range(int(lo), int(hi) + 1) if t not in got]


def latest_t(c: Collector) -> float:
    g = arrivals(c, "radar/gtracks")
    return g[-1][1] if g else 0.0


def report(numbers: dict[str, object]) -> None:
    print(f"\n[secured_network] {json.dumps(numbers)}")
    out = REPO / "out" / "secured_network.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(numbers, indent=2) + "\n")


@pytest.mark.timeout(600)
def test_secured_deployment_from_the_docs_under_impairment_cut_forgery_and_rotation(
        tmp_path: Path) -> None:
    require()
    t_start = time.monotonic()
    steps = doc_steps()
    assert [st.host for st in steps] == ["ca", "ca", "fusion", "fusion", "site1", "site2",
                                         "fusion", "site1", "site2", "fusion", "ca", "fusion"]
    s = Secured(tmp_path)
    numbers: dict[str, object] = {}
    phases: dict[str, float] = {}
    numbers["phases_s"] = phases

    def phase(name: str) -> None:
        phases[name] = round(time.monotonic() - t_start, 1)

    try:
        fed = False
        for i, st in enumerate(x for x in steps if x.part == "deploy"):
            phase(f"step {i} ({st.host})")
            if st.service:
                first, *lines = st.body.splitlines()
                assert first == f"# {st.host}: services", first
                for line in (x for x in lines if x.strip()):
                    s.service(st.host, line)
                continue
            if st.host != "ca" and not fed:
                check_files(s)
                add_test_feed(s)
                fed = True
            if "pfusion status" in st.body:  # step 7: every service listed once running
                start_load(s)  # the collectors and simulators start meanwhile
                s.wait(lambda: all("running" in s.log(n) for n in s.services), "services running")
                s.wait(lambda: set(SERVICES) <= s.status(st.body), "status lists every service")
                continue
            r = s.shell(st.host, st.body)
            if "-ext subjectAltName" in st.body:
                assert f"IP Address:{HUB_ADDRESS}" in r.stdout and "IP Address:127.0.0.1" in r.stdout
            if "params --check" in st.body:
                assert "valid" in r.stdout and int(r.stdout.split()[-1]) > 0, r.stdout
        phase("deployed")
        fusion, site2 = s.collectors["fusion"], s.collectors["site2"]
        s.wait(lambda: latest_t(fusion) >= 4 and bool(arrivals(site2, "radar/gtracks")),
               "global tracks at the fusion host and at site2")
        phase("flowing")
        numbers["forgery"] = forge(s)
        time.sleep(1.0)
        assert not fusion.errors, f"forged samples got through: {fusion.errors[:5]}"
        phase("forged")

        s.net.set_link("site2", up=False)
        t_cut, t_scan_cut = time.time(), latest_t(fusion)
        time.sleep(2.5)  # > the 2 s router lease: the site2 session is gone
        during = s.status()
        time.sleep(max(0.0, t_cut + CUT_S - time.time()))
        flowing = [t for at, t in arrivals(fusion, "radar/gtracks") if t_cut + 3.5 < at]
        s.net.set_link("site2", up=True)
        t_restore = time.time()
        assert not {"channel_plotter/b3", "elementary_tracker/b3"} & during, during
        assert {"channel_plotter/b1", "global_fusion/main"} <= during, during
        assert len(flowing) >= 4, f"global tracks stopped during the cut: {flowing}"
        s.wait(lambda: any(at > t_restore for at, _ in arrivals(fusion, "radar/etracks/b3")),
               "b3 back at the fusion host", 30.0)
        s.wait(lambda: set(SERVICES) <= s.status(), "status lists b3 again", 30.0)
        numbers["cut"] = {"cut_s": round(t_restore - t_cut, 1),
                          "b3_back_s": round(min(at for at, _ in arrivals(fusion, "radar/etracks/b3")
                                                 if at > t_restore) - t_restore, 2),
                          "gtracks_during_cut": len(flowing),
                          "b3_lost": len(missing(fusion, "b3", t_scan_cut, latest_t(fusion)))}

        windows = [(t_scan_cut, latest_t(fusion))]  # b3's
        phase("recovered")
        retired = password_line(s, "site2", "analyst")
        for st in (x for x in steps if x.part == "rotate"):
            r = s.shell(st.host, st.body)
            if "pfusion acl" in st.body:
                assert "host-fusion" in r.stdout and "host-site2" not in r.stdout, r.stdout
        assert "analyst" not in pw_users(s.etc("site2") / "dictionary.txt")
        s.retired.append(site2.proc)
        t_scan_roll, t_roll = latest_t(fusion), time.time()
        restarts, per_router = {}, {}
        for host in HOSTS:
            argv, proc = s.routers[host]
            s.retired.append(proc)
            t_scan_down = latest_t(fusion)
            proc.stop()
            t_down = restarts[host] = time.time()
            p = s.net.start(host, pfusion_argv(*argv), f"{host}-router-2")
            s.routers[host] = (argv, p)
            s.wait(lambda: "router listening" in s.log(f"{host}-router-2"), f"{host} router back")
            t_up = time.time()  # what arrives from now on went through the new router
            s.wait(lambda: all(any(at > t_up for at, _ in arrivals(fusion, f"radar/etracks/{b}"))
                               for b in ("b1", "b2", "b3")), f"every base back after {host}", 60.0)
            windows.append((t_scan_down, latest_t(fusion)))
            per_router[host] = {"back_s": round(time.time() - t_down, 1), "etracks_lost": {
                b: len(missing(fusion, b, *windows[-1])) for b in ("b1", "b2", "b3")}}
        t_rolled, t_scan_rolled = time.time(), latest_t(fusion)
        phase("rolled")
        assert set(SERVICES) <= s.status()  # and 4 s or more pass
        after = [at for at, _ in arrivals(fusion, "radar/gtracks") if at > t_rolled]
        refused = [t for at, t in arrivals(site2, "radar/gtracks") if at > restarts["site2"] + 0.5]
        assert len(after) >= 8, "global tracks did not go on after the roll"
        assert not refused, f"site2's retired analyst still receives: {refused[:5]}"
        numbers["retired_analyst"] = try_as(s, "analyst", retired, "tls/127.0.0.1:7447")
        assert not numbers["retired_analyst"]["opened"], numbers["retired_analyst"]
        lost = {b: missing(fusion, b, t_scan_roll, t_scan_rolled) for b in ("b1", "b2", "b3")}
        cycles = {t for _, t in arrivals(fusion, "radar/gtracks")}
        numbers["roll"] = {
            "roll_s": round(t_rolled - t_roll, 1),
            "scans_in_roll": int(t_scan_rolled - t_scan_roll),
            "etracks_lost": {b: len(v) for b, v in lost.items()},
            "per_router": per_router,
            "gtracks_cycles_lost": sum(1 for t in range(int(t_scan_roll), int(t_scan_rolled) + 1)
                                       if t not in cycles)}
        for b, v in lost.items():
            assert len(v) <= ROLL_LOSS_MAX, (b, v, numbers)
        for b in ("b1", "b2", "b3"):  # nothing lost but in the cut (b3) and the restarts
            outside = [t for t in missing(fusion, b, 0, t_scan_rolled)
                       if not any(lo - SLACK <= t <= hi + SLACK
                                  for lo, hi in windows[b != "b3":])]
            assert not outside, (b, outside, windows)
        assert not fusion.errors, fusion.errors[:5]
        plotter = [r.msg for r in fusion.of("metrics/channel_plotter/b1")]
        assert plotter and not plotter[-1]["rejected"], plotter[-1:]
    finally:
        numbers["impairment"] = s.net.impairment
        for sim in s.sims:
            sim.stop()
        s.close()
        numbers["runtime_s"] = round(time.monotonic() - t_start, 1)
        report(numbers)
