"""Hosts as Linux network namespaces for the multi-host tests (tests/integration/test_multihost.py).

A :class:`Topology` has one hub host ("fusion") and site hosts, each site joined to the
hub by a WAN link: site --veth-- wan namespace --veth-- hub. The wan namespace forwards
the link's frames: a kernel bridge, or, when the link is impaired, netem on the bridge
ports if the kernel has ``sch_netem``, else the userspace netem of ``tests/netem.py``
(the kernel of this CI machine is built without CONFIG_NET_SCH_NETEM). Addresses are
taken from 198.18.0.0/15 (benchmarking range) and exist only inside the namespaces: site i
is 198.18.i.1/30, the hub's end of its link 198.18.i.2/30, and the hub's service address
``HUB_ADDRESS`` (on its ``lo``) is routed through each site's link.

Namespaces and links are named ``pf<pid>...`` (unique per test run) and deleted by
:meth:`Topology.close`, which also stops every process started in them. A test that
needs them calls :func:`require`: it skips where they cannot be made, and fails there
when ``CI`` is set (``.ci/run`` sets ``CI=true``: in CI these tests must run).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from common.bus.procs import Child

REPO = Path(__file__).resolve().parents[1]
HUB_ADDRESS = "198.18.0.1"
NETEM = ("50ms", "10ms", "1%")  # delay, jitter, loss: `tc netem delay 50ms 10ms loss 1%`


def ip(*args: str, ns: str | None = None) -> str:
    """Run ``ip [-n ns] ARGS``; raises RuntimeError with ip's message on failure."""
    argv = ["ip", *(["-n", ns] if ns else []), *args]
    r = subprocess.run(argv, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(f"{' '.join(argv)}: {r.stderr.strip()}")
    return r.stdout


def unavailable() -> str | None:
    """Why namespaces cannot be made here (None if they can): not root, no ``ip``, or
    ``ip netns add`` / veth refused (e.g. an unprivileged container)."""
    if os.geteuid() != 0:
        return "network namespaces need root (euid is %d)" % os.geteuid()
    if shutil.which("ip") is None:
        return "the 'ip' command (iproute2) is not installed"
    probe = f"pf{os.getpid()}probe"
    try:
        ip("netns", "add", probe)
        try:
            ip("link", "add", f"{probe}a", "type", "veth", "peer", "name", f"{probe}b", ns=probe)
        finally:
            ip("netns", "del", probe)
    except RuntimeError as e:
        return f"cannot create a network namespace with a veth pair: {e}"
    return None


def require() -> None:
    """Skip the calling test where namespaces cannot be made (the reason printed), or
    fail it there when the environment variable ``CI`` is set (not empty, not 0/false)."""
    reason = unavailable()
    if reason is None:
        return
    if os.environ.get("CI", "").lower() not in ("", "0", "false", "no"):
        pytest.fail(f"CI is set but {reason}: namespace tests must run in CI", pytrace=False)
    print(f"SKIPPED namespace test: {reason}", file=sys.stderr)
    pytest.skip(reason)


def kernel_netem(ns: str, dev: str) -> bool:
    """True if ``tc netem`` can be put on ``dev`` (then it is, with NETEM)."""
    delay, jitter, loss = NETEM
    r = subprocess.run(["tc", "-n", ns, "qdisc", "add", "dev", dev, "root", "netem",
                        "delay", delay, jitter, "loss", loss], capture_output=True, text=True)
    return r.returncode == 0


class NsProcess(Child):
    """A command run inside a namespace (``ip netns exec`` execs it: same pid); stderr
    goes to ``log``. Stopped like any child (common.bus.procs.Child)."""

    def __init__(self, ns: str, argv: list[str], log: Path, stdout: int | None = None) -> None:
        self._spawn(log.stem, ["ip", "netns", "exec", ns, *argv], log, stdout, cwd=REPO)


class Topology:
    """A hub host and site hosts joined by WAN links (module doc)."""

    def __init__(self, logdir: Path, hub: str = "fusion") -> None:
        self.tag = f"pf{os.getpid()}"
        self.logdir = logdir
        logdir.mkdir(parents=True, exist_ok=True)
        self.hub = hub
        self.ns: dict[str, str] = {}
        self.cut_dev: dict[str, tuple[str, str]] = {}
        self.impairment = "none"
        self.processes: list[NsProcess] = []
        self._add_ns(hub)
        ip("addr", "add", f"{HUB_ADDRESS}/32", "dev", "lo", ns=self.ns[hub])

    def _add_ns(self, name: str) -> str:
        ns = self.ns[name] = f"{self.tag}-{name}"
        ip("netns", "add", ns)
        ip("link", "set", "lo", "up", ns=ns)
        return ns

    def add_site(self, name: str, index: int, impaired: bool = False) -> None:
        """Site host ``name`` on link 198.18.<index>.0/30 to the hub, through its wan
        namespace; ``impaired``: NETEM in both directions of the link."""
        site, wan, hub = self._add_ns(name), self._add_ns(f"wan{index}"), self.ns[self.hub]
        s, ws, wh, h = (f"{self.tag}{c}{index}" for c in "swxh")
        ip("link", "add", s, "type", "veth", "peer", "name", ws)
        ip("link", "add", wh, "type", "veth", "peer", "name", h)
        for dev, ns in ((s, site), (ws, wan), (wh, wan), (h, hub)):
            ip("link", "set", dev, "netns", ns)
            ip("link", "set", dev, "up", ns=ns)
        ip("addr", "add", f"198.18.{index}.1/30", "dev", s, ns=site)
        ip("addr", "add", f"198.18.{index}.2/30", "dev", h, ns=hub)
        ip("route", "add", f"{HUB_ADDRESS}/32", "via", f"198.18.{index}.2", ns=site)
        self.cut_dev[name] = (ws, wan)
        if impaired and not (kernel_netem(wan, ws) and kernel_netem(wan, wh)):
            for dev in (ws, wh):  # frames for other hosts must reach the packet sockets
                ip("link", "set", dev, "promisc", "on", ns=wan)
            self.impairment = "userspace netem (tests/netem.py): the kernel has no sch_netem"
            delay, jitter, loss = NETEM
            self.start(f"wan{index}", [sys.executable, "-m", "tests.netem", ws, wh,
                                       "--delay", delay, "--jitter", jitter, "--loss", loss],
                       f"netem{index}")
            return
        if impaired:
            self.impairment = "kernel tc netem on the wan bridge ports"
        ip("link", "add", "br0", "type", "bridge", ns=wan)
        for dev in (ws, wh):
            ip("link", "set", dev, "master", "br0", ns=wan)
        ip("link", "set", "br0", "up", ns=wan)

    def set_link(self, site: str, up: bool) -> None:
        """``ip link set <the wan's end of the site's veth> up|down``: a cable cut next
        to the site (the site's interface loses its carrier but keeps its address and
        routes; setting the site's own end down would delete the route to the hub)."""
        dev, wan = self.cut_dev[site]
        ip("link", "set", dev, "up" if up else "down", ns=wan)

    def start(self, host: str, argv: list[str], name: str, stdout: int | None = None
              ) -> NsProcess:
        """Start ``argv`` inside ``host``; its stderr goes to <logdir>/<name>.log."""
        p = NsProcess(self.ns[host], argv, self.logdir / f"{name}.log", stdout)
        self.processes.append(p)
        return p

    def check_running(self) -> None:
        """Raise if a process started here has exited."""
        for p in self.processes:
            if not p.alive():
                raise RuntimeError(f"{p.name} exited with {p.proc.returncode}; "
                                   f"see {self.logdir}/{p.name}.log")

    def close(self) -> None:
        """Stop every process (SIGTERM to all, then wait; SIGKILL after 5 s) and delete
        every namespace (their veth ends go with them). Idempotent."""
        for p in self.processes:
            if p.alive():
                p.proc.send_signal(signal.SIGTERM)
        for p in reversed(self.processes):
            p.stop()
        self.processes = []
        for ns in self.ns.values():
            try:
                ip("netns", "del", ns)
            except RuntimeError as e:
                print(f"cleanup: {e}", file=sys.stderr)
        self.ns = {}
