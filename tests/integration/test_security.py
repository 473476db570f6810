"""Security with Zenoh's own mechanisms (docs/security.md), on real processes over
loopback: a throw-away CA and certificates made with the openssl CLI, a ``pfusion
router --config`` with mutual TLS, user/password authentication and the access control
generated from the deployment (common.deploy.acl).

Shown: a client without credentials, with a wrong password, or with a certificate of
another CA cannot connect; a site's identity cannot publish another base's plots nor
global tracks (the samples never reach a subscriber, while its own base's plots do),
also through a site router; the read roles cannot publish; a stolen password does nothing
with the certificate of a host that does not run its identity, and a site router's
password does nothing without the router's certificate (no reads, no forged history
replies, no liveliness of a stopped service: issue 33); the read roles see only their
scope (a viewer tracks and status, an analyst everything), only operator-tma sets TMA
bounds, ``pfusion run`` on a site host runs with the site's identity and credentials;
a certificate expiring within 7 days is warned about, an expired one refused (exit 2);
the radar chain of two_targets.toml with all of it on gives the global tracks of the
in-process chain."""

from __future__ import annotations

import argparse
import dataclasses
import fnmatch
import json
import secrets
import subprocess
import time
import tomllib
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import zenoh

from common.bus import transport
from common.bus.procs import Child, pfusion_argv
from common.bus.transport import Inbox, free_port, open_session, wait_port
from common.cli import COMMANDS, load_config
from common.cli import main as cli_main
from common.deploy.acl import access_control, grants, identity_of, router_identity, site_identity
from common.deploy.config import Config, ConfigError, ZenohConfig, load
from common.deploy.deployment import plan
from common.sim.scenario import load_scenario
from common.wire import protocol
from common.wire.radar_chain import RadarChain
from common.wire.sim_messages import run_scenario
from services.router.main import router_config
from tests.harness import SCENARIOS

ROOT = "pf/v1"
ATTEMPT_S = 6
WAIT_S = 60.0  # generous: the machine may be loaded (load average 25-35 seen)
BLOCK = zenoh.CongestionControl.BLOCK
SCANS = 60
SCENARIO = SCENARIOS / "two_targets.toml"
SECURITY = """
[[sonar.array]]
id = "a1"
sigma0 = 0.02

[[site]]
id = "rx1"
bases = ["b1"]
arrays = ["a1"]

[[site]]
id = "rx2"
bases = ["b2", "b3"]

[zenoh.auth]
credentials = "credentials.txt"
dictionary = "dictionary.txt"

[zenoh.tls]
root_ca = "ca.pem"
cert = "host.pem"
key = "host.key"
router_cert = "{router}.pem"
router_key = "{router}.key"
mtls = true

[zenoh.tls.hosts]
host = ["site-rx1", "channel-plotter-b1", "elementary-tracker-b1", "channel-plotter-b2",
        "elementary-tracker-b2", "channel-plotter-b3", "elementary-tracker-b3",
        "bearing-tracker-a1", "tma-a1", "global-fusion", "evaluate", "analyst",
        "viewer", "operator-tma", "simulator"]
host-rx2 = ["site-rx2"]
"""


def openssl(*args: str, cwd: Path) -> None:
    subprocess.run(["openssl", *args], cwd=cwd, check=True, capture_output=True, timeout=60)


def make_ca(d: Path, name: str) -> None:
    """A self-signed EC CA: <name>.pem, <name>.key."""
    openssl("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
            "-nodes", "-keyout", f"{name}.key", "-out", f"{name}.pem", "-days", "2",
            "-subj", f"/CN={name}", cwd=d)


def make_cert(d: Path, ca: str, name: str, days: int = 30) -> None:
    """<name>.pem / .key signed by CA <ca>, common name <name>, valid for 127.0.0.1 from
    now for ``days`` days (30: the documented default)."""
    openssl("req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
            "-keyout", f"{name}.key", "-out", f"{name}.csr", "-subj", f"/CN={name}", cwd=d)
    (d / "san.cnf").write_text("subjectAltName=IP:127.0.0.1,DNS:localhost\n")
    openssl("x509", "-req", "-in", f"{name}.csr", "-CA", f"{ca}.pem", "-CAkey", f"{ca}.key",
            "-CAcreateserial", "-out", f"{name}.pem", "-days", str(days), "-extfile", "san.cnf",
            cwd=d)


def make_expired_cert(d: Path, ca: str, name: str) -> None:
    """<name>.pem / .key signed by CA <ca>, valid on 1 and 2 January 2026 only (``openssl
    ca`` sets past dates, ``x509 -days`` cannot)."""
    openssl("req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
            "-keyout", f"{name}.key", "-out", f"{name}.csr", "-subj", f"/CN={name}", cwd=d)
    (d / "index.txt").write_text("")
    (d / "serial").write_text("01\n")
    (d / "ca.cnf").write_text("[ca]\ndefault_ca = d\n[d]\ndatabase = index.txt\n"
                              "new_certs_dir = .\nserial = serial\ndefault_md = sha256\n"
                              "policy = p\n[p]\ncommonName = supplied\n")
    openssl("ca", "-batch", "-config", "ca.cnf", "-cert", f"{ca}.pem", "-keyfile", f"{ca}.key",
            "-in", f"{name}.csr", "-out", f"{name}.pem", "-notext",
            "-startdate", "20260101000000Z", "-enddate", "20260102000000Z", cwd=d)


MIXED = """
[[radar.base]]
id = "b1"
tx = [30000.0, 0.0, 100.0]
rx = [0.0, 0.0, 10.0]
channels = ["c1", "c2"]

[[radar.base]]
id = "b2"
tx = [0.0, 30000.0, 100.0]
rx = [0.0, 0.0, 10.0]
channels = ["c1"]

[[sonar.array]]
id = "a1"
sigma0 = 0.02

[[sonar.array]]
id = "a2"
sigma0 = 0.02

[[site]]
id = "north"
bases = ["b1"]
arrays = ["a1"]

[[site]]
id = "south"
bases = ["b2"]
arrays = ["a2"]
"""


def allowed(acl: dict, user: str, flow: str, message: str, key: str) -> bool:
    """Whether the generated section lets ``user`` send ``message`` on ``key``."""
    policies = [p for p in acl["policies"] if user in p["subjects"]]
    rules = {r["id"]: r for r in acl["rules"]}
    return any(flow in r["flows"] and message in r["messages"]
               and any(zenoh.KeyExpr(k).includes(zenoh.KeyExpr(key)) for k in r["key_exprs"])
               for p in policies for r in (rules[i] for i in p["rules"]))


def test_generated_access_control(tmp_path: Path) -> None:
    """Deny by default; each site publishes its own bases' plots and arrays' detections
    only; only global-fusion publishes global tracks; each service publishes exactly
    its outputs and metrics and declares its own token; the read roles never publish."""
    (tmp_path / "d.toml").write_text(MIXED)
    cfg = load(tmp_path / "d.toml")
    acl = access_control(cfg)
    assert acl["enabled"] and acl["default_permission"] == "deny"
    users = [s["id"] for s in acl["subjects"]]
    assert sorted(users) == sorted([*grants(cfg), "router-north", "router-south"])
    put = {u: {k for k in KEYS if allowed(acl, u, "ingress", "put", f"{ROOT}/{k}")} for u in users}
    assert put["site-north"] == {"radar/plots/b1/c1", "radar/plots/b1/c2", "sonar/detections/a1"}
    assert put["site-south"] == {"radar/plots/b2/c1", "sonar/detections/a2"}
    assert [u for u in users if "radar/gtracks" in put[u]] == ["global-fusion"]
    assert put["channel-plotter-b1"] == {"radar/fused/b1", "metrics/channel_plotter/b1"}
    assert put["elementary-tracker-b2"] == {"radar/etracks/b2", "metrics/elementary_tracker/b2"}
    assert put["bearing-tracker-a1"] == {"sonar/btracks/a1", "metrics/bearing_tracker/a1"}
    assert put["tma-a2"] == {"sonar/tma/a2", "sonar/tma/ack/a2", "metrics/tma/a2"}
    assert put["analyst"] == put["viewer"] == set()
    assert put["tma-a1"] == {"sonar/tma/a1", "sonar/tma/ack/a1", "metrics/tma/a1"}
    assert put["operator-tma"] == {"sonar/tma/bounds/a1", "sonar/tma/bounds/a2",
                                   "sonar/tma/support/a1", "sonar/tma/clear/a1"}
    assert [u for u in users if "sonar/tma/clear/a1" in put[u]] == ["operator-tma", "router-north", "router-south"]
    assert put["router-north"] == put["site-north"] | put["channel-plotter-b1"] \
        | put["elementary-tracker-b1"] | put["bearing-tracker-a1"] | put["tma-a1"] \
        | put["operator-tma"]
    get = {u: {k for k in KEYS if allowed(acl, u, "egress", "put", f"{ROOT}/{k}")} for u in users}
    assert get["viewer"] == {"radar/gtracks", "sonar/btracks/a1", "sonar/btracks/a2",
                             "sonar/tma/a1", "sonar/tma/a2", *(k for k in KEYS if "metrics" in k)}
    assert get["analyst"] == set(KEYS)
    # pfusion tma-input (identity operator-tma) reads the births of the tma messages and the acks
    assert identity_of("tma-input", array="a1") == "operator-tma"
    assert get["operator-tma"] == {"sonar/tma/a1", "sonar/tma/a2", "sonar/tma/ack/a1", "sonar/tma/ack/a2"}
    assert allowed(acl, "tma-a1", "egress", "put", f"{ROOT}/sonar/tma/clear/a1")
    assert not allowed(acl, "tma-a1", "egress", "put", f"{ROOT}/sonar/tma/clear/a2")
    for u, svc, inst in (("tma-a1", "tma", "a1"), ("global-fusion", "global_fusion", "main")):
        assert allowed(acl, u, "ingress", "liveliness_token", f"{ROOT}/alive/{svc}/{inst}")
        assert not allowed(acl, u, "ingress", "liveliness_token", f"{ROOT}/alive/tma/a2")
    assert allowed(acl, "analyst", "ingress", "declare_subscriber", f"{ROOT}/**")
    assert allowed(acl, "tma-a1", "ingress", "query", f"{ROOT}/sonar/history/a1/3")
    assert not allowed(acl, "tma-a1", "ingress", "query", f"{ROOT}/sonar/history/a2/3")
    assert all(s.get("usernames") == [s["id"]] for s in acl["subjects"])  # no mTLS here


BOUND = MIXED + """
[zenoh.tls]
root_ca = "ca.pem"
mtls = true

[zenoh.tls.hosts]
host-north = ["site-north", "channel-plotter-b1", "elementary-tracker-b1", "analyst"]
host-fusion = ["global-fusion", "analyst"]
"""


def test_identities_are_bound_to_their_hosts_certificates(tmp_path: Path) -> None:
    """Under mutual TLS a subject is a username AND the common names of the hosts that
    run it ([zenoh.tls.hosts]); router-<site> needs its own common name, router-fusion
    is known by its common name alone; an identity that no host runs has no subject
    (denied everything). A site router may serve and declare tokens of its own site only.
    A table naming a router, a router's common name or an unknown identity, a table
    without mutual TLS and mutual TLS without the table are ConfigErrors."""
    (tmp_path / "d.toml").write_text(BOUND)
    acl = access_control(load(tmp_path / "d.toml"))
    subjects = {s["id"]: {k: v for k, v in s.items() if k != "id"} for s in acl["subjects"]}
    assert subjects["site-north"] == {"usernames": ["site-north"],
                                      "cert_common_names": ["host-north"]}
    assert subjects["analyst"] == {"usernames": ["analyst"],
                                    "cert_common_names": ["host-north", "host-fusion"]}
    assert subjects["router-south"] == {"usernames": ["router-south"],
                                        "cert_common_names": ["router-south"]}
    assert subjects["router-fusion"] == {"cert_common_names": ["router-fusion"]}
    assert "site-south" not in subjects and "tma-a1" not in subjects
    history, token = f"{ROOT}/sonar/history/a1/1", f"{ROOT}/alive/tma/a1"
    for router, ok in (("router-north", True), ("router-south", False)):
        assert allowed(acl, router, "ingress", "declare_queryable", history) is ok
        assert allowed(acl, router, "egress", "query", history) is ok
        assert allowed(acl, router, "ingress", "liveliness_token", token) is ok
    for hosts, key in (('host-north = ["router-north"]', "zenoh.tls.hosts.host-north"),
                       ('router-fusion = ["analyst"]', "zenoh.tls.hosts"),
                       ('host-north = ["tma-a9"]', "zenoh.tls.hosts.host-north")):
        (tmp_path / "d.toml").write_text(BOUND.split("[zenoh.tls.hosts]")[0]
                                         + f"[zenoh.tls.hosts]\n{hosts}\n")
        with pytest.raises(ConfigError) as e:
            access_control(load(tmp_path / "d.toml"))
        assert e.value.key == key, hosts
    for text in (BOUND.split("[zenoh.tls.hosts]")[0], BOUND.replace("mtls = true", "")):
        (tmp_path / "d.toml").write_text(text)
        with pytest.raises(ConfigError) as e:
            access_control(load(tmp_path / "d.toml"))
        assert e.value.key == "zenoh.tls.hosts"


KEYS = ["radar/plots/b1/c1", "radar/plots/b1/c2", "radar/plots/b2/c1", "radar/plots/b1",
        "radar/fused/b1", "radar/fused/b2", "radar/etracks/b1", "radar/etracks/b2",
        "radar/gtracks", "sonar/detections/a1", "sonar/detections/a2", "sonar/btracks/a1",
        "sonar/btracks/a2", "sonar/tma/a1", "sonar/tma/a2", "sonar/tma/bounds/a1",
        "sonar/tma/bounds/a2", "sonar/tma/support/a1", "sonar/tma/clear/a1", "sonar/tma/ack/a1",
        "sonar/tma/ack/a2", "sim/truth/radar", "metrics/channel_plotter/b1",
        "metrics/elementary_tracker/b2", "metrics/bearing_tracker/a1", "metrics/tma/a2",
        "metrics/tma/a1", "metrics/global_fusion/main", "metrics/channel_plotter/b2"]


def test_pfusion_acl_prints_what_the_router_applies(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "d.toml").write_text(MIXED)
    assert cli_main(["acl", "--config", str(tmp_path / "d.toml")]) == 0
    out = capsys.readouterr().out
    assert json.loads(out) == {"access_control": access_control(load(tmp_path / "d.toml"))}


def test_secret_files_readable_by_others_are_refused_with_exit_2(tmp_path: Path) -> None:
    """Attacker model (b): a credentials, dictionary or private-key file that group or
    others may read is refused (ConfigError naming the key: exit 2, which run does not
    restart); the same file with mode 600 is accepted."""
    users = tmp_path / "users"
    users.write_text("global-fusion:pw\n")
    (tmp_path / "d.toml").write_text(MIXED + '[zenoh.auth]\ncredentials = "users"\n')
    zc = dataclasses.replace(load(tmp_path / "d.toml").zenoh, identity="global-fusion")
    for mode in (0o644, 0o640, 0o604):
        users.chmod(mode)
        with pytest.raises(ConfigError) as e:
            transport.zenoh_config(zc.connect, [], "client", security=zc)
        assert e.value.key == "zenoh.auth.credentials" and "chmod 600" in str(e.value)
    out = subprocess.run(pfusion_argv("global-fusion", "--config", str(tmp_path / "d.toml"),
                                      "--identity", "global-fusion"),
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "zenoh.auth.credentials" in out.stderr, out.stderr
    users.chmod(0o600)
    transport.zenoh_config(zc.connect, [], "client", security=zc)


def test_router_needs_mutual_tls_to_apply_access_control_upstream(tmp_path: Path) -> None:
    """A site router knows its upstream router only by its certificate: without mutual
    TLS its deny-by-default rules would drop everything from upstream, so it refuses."""
    (tmp_path / "users").write_text("router-north:pw\n")
    (tmp_path / "users").chmod(0o600)
    (tmp_path / "d.toml").write_text(MIXED + '[zenoh.auth]\ncredentials = "users"\n'
                                             'dictionary = "users"\n')
    args = argparse.Namespace(listen=["tcp/127.0.0.1:1"], connect=["tcp/127.0.0.1:2"],
                              config=str(tmp_path / "d.toml"), identity="router-north")
    with pytest.raises(ConfigError) as e:
        router_config(args, load_config(args))
    assert e.value.key == "zenoh.tls.mtls"
    args.connect = []
    router_config(args, load_config(args))


@dataclass
class Secure:
    """A secured deployment: its file (fusion host), a site router's file, the router."""

    dir: Path
    config: Path
    site_config: Path
    cfg: Config
    endpoint: str


def deployment_files(d: Path) -> tuple[Path, Path]:
    """The PKI (CA 'ca' and a foreign CA 'other'), every identity's password, and the
    deployment with [[site]], [zenoh.auth], [zenoh.tls] for the fusion host and for the
    site host rx1 (whose router certificate is router-rx1's). Every identity runs on the
    host of certificate 'host' but site-rx2, which runs on 'host-rx2'."""
    make_ca(d, "ca")
    make_ca(d, "other")
    for name in ("router-fusion", "router-rx1", "host", "host-rx2"):
        make_cert(d, "ca", name)
    make_cert(d, "other", "intruder")
    text = SCENARIO.read_text()
    fusion = d / "fusion.toml"
    fusion.write_text(text + SECURITY.format(router="router-fusion"))
    site = d / "site-rx1.toml"
    site.write_text(text + SECURITY.format(router="router-rx1"))
    names = [*grants(load(fusion)), *(router_identity(s) for s in ("rx1", "rx2"))]
    lines = [f"{n}:{secrets.token_hex(12)}" for n in names]
    for name in ("dictionary.txt", "credentials.txt"):
        (d / name).write_text("\n".join(lines) + "\n")
        (d / name).chmod(0o600)  # group- or world-readable secrets are refused
    return fusion, site


@pytest.fixture(scope="module")
def secure(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Secure]:
    d = tmp_path_factory.mktemp("security")
    fusion, site = deployment_files(d)
    port = free_port()
    endpoint = f"tls/127.0.0.1:{port}"
    router = Child("router", "router", "--config", str(fusion), "--listen", endpoint,
                   log=d / "router.log")
    try:
        wait_port(port, timeout=60.0)
        yield Secure(d, fusion, site, load(fusion), endpoint)
    finally:
        router.stop()


def zc(s: Secure, identity: str | None, endpoint: str | None = None) -> ZenohConfig:
    return dataclasses.replace(s.cfg.zenoh, connect=[endpoint or s.endpoint], identity=identity)


def connects(z: ZenohConfig) -> bool:
    try:
        open_session(z).close()
    except zenoh.ZError:
        return False
    return True


def test_wrong_or_missing_credentials_and_foreign_ca_cannot_connect(
        secure: Secure, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each bad client tries for ATTEMPT_S (in parallel); the good one, tried before and
    after with the same limit, shows that this was long enough on this machine."""
    good = zc(secure, "analyst")
    assert connects(good)
    monkeypatch.setattr(transport, "CONNECT_TIMEOUT_S", ATTEMPT_S)
    wrong = secure.dir / "wrong.txt"
    wrong.write_text("analyst:not-the-password\n")
    wrong.chmod(0o600)
    tls = good.tls
    assert tls is not None and good.auth is not None
    bad = {
        "no credentials": dataclasses.replace(good, auth=None),
        "wrong password": dataclasses.replace(
            good, auth=dataclasses.replace(good.auth, credentials=str(wrong))),
        "client certificate of another CA": dataclasses.replace(good, tls=dataclasses.replace(
            tls, cert=str(secure.dir / "intruder.pem"), key=str(secure.dir / "intruder.key"))),
        "router certificate not trusted (other CA)": dataclasses.replace(
            good, tls=dataclasses.replace(tls, root_ca=str(secure.dir / "other.pem"))),
        "plain TCP on the TLS port": dataclasses.replace(
            good, tls=None, connect=[secure.endpoint.replace("tls/", "tcp/")]),
    }
    with ThreadPoolExecutor(len(bad)) as pool:
        result = dict(zip(bad, pool.map(connects, bad.values())))
    assert not any(result.values()), result
    assert connects(good)


class Listener:
    """An analyst session subscribed to root/** that keeps every received key."""

    def __init__(self, z: ZenohConfig) -> None:
        self.session = open_session(z)
        self.inbox = Inbox()
        self.sub = self.session.declare_subscriber(f"{ROOT}/**", self.inbox.on_sample)
        self.keys: list[str] = []

    def until(self, key: str, timeout: float = WAIT_S) -> list[str]:
        """Keys received up to and including ``key`` (the end marker of a test)."""
        deadline = time.monotonic() + timeout
        while key not in self.keys:
            env = self.inbox.get(0.1)
            if env is not None:
                self.keys.append(env.key)
            assert time.monotonic() < deadline, f"{key} never arrived; got {self.keys}"
        return self.keys

    def close(self) -> None:
        self.sub.undeclare()
        self.session.close()


def put_all(z: ZenohConfig, suffixes: list[str], declared: bool = True) -> None:
    """Publish one sample on each key, in order, as services do (a declared, reliable,
    blocking publisher), once each publisher knows of a subscriber (the listener's).
    ``declared=False``: plain session puts, which a client sends to its router
    whether or not it knows of a subscriber (an identity that may publish nothing is
    never told of subscribers, so its declared publishers would not even send)."""
    with open_session(z) as s:
        if not declared:
            for suffix in suffixes:
                s.put(f"{ROOT}/{suffix}", b"x", congestion_control=BLOCK)
            transport.linger()
            return
        pubs = [s.declare_publisher(f"{ROOT}/{suffix}", congestion_control=BLOCK,
                                    reliability=zenoh.Reliability.RELIABLE) for suffix in suffixes]
        deadline = time.monotonic() + WAIT_S
        while not all(p.matching_status.matching for p in pubs):
            assert time.monotonic() < deadline, "publishers never matched the listener"
            time.sleep(0.05)
        for pub in pubs:
            pub.put(b"x")
        transport.linger()


DENIED = ["radar/plots/b2/c1", "radar/plots/b3/c1", "radar/gtracks", "radar/etracks/b1",
          "sim/status", "radar/plots/b1", "radar/plots/b1/c1/x"]


def test_identities_publish_only_their_keys(secure: Secure) -> None:
    """Site rx1 (base b1) directly on the fusion router: its b1 plots arrive, b2 and b3
    plots, global tracks and other keys never do; global-fusion's tracks arrive, an
    analyst's put never does. Each publisher ends with an allowed marker, so the denied
    samples would have arrived before it."""
    listener = Listener(zc(secure, "analyst"))
    try:
        time.sleep(0.5)
        put_all(zc(secure, "analyst"), ["radar/gtracks", "radar/plots/b1/c9"], declared=False)
        put_all(zc(secure, site_identity("rx1")), ["radar/plots/b1/c1", *DENIED,
                                                   "radar/plots/b1/c2"])
        put_all(zc(secure, "global-fusion"), ["radar/plots/b1/c3", "radar/gtracks"])
        keys = listener.until(f"{ROOT}/radar/gtracks")
    finally:
        listener.close()
    assert keys == [f"{ROOT}/radar/plots/b1/c1", f"{ROOT}/radar/plots/b1/c2",
                    f"{ROOT}/radar/gtracks"]


def test_site_router_forwards_only_its_site(secure: Secure) -> None:
    """Site rx1's router (its own certificate, identity router-rx1, mutual TLS, the same
    generated access control) between the site and the fusion router: the site's b1
    plots reach an analyst at the fusion router, another base's plots and global
    tracks do not; the fusion router's global tracks reach an analyst at the site."""
    port = free_port()
    site_ep = f"tls/127.0.0.1:{port}"
    router = Child("router-rx1", "router", "--config", str(secure.site_config), "--identity",
                   router_identity("rx1"), "--listen", site_ep, "--connect", secure.endpoint,
                   log=secure.dir / "router-rx1.log")
    central = Listener(zc(secure, "analyst"))
    try:
        wait_port(port, timeout=60.0)
        local = Listener(zc(secure, "analyst", site_ep))
        try:
            time.sleep(1.0)
            put_all(zc(secure, site_identity("rx1"), site_ep),
                    ["radar/plots/b1/c1", *DENIED, "radar/plots/b1/c2"])
            put_all(zc(secure, "global-fusion"), ["radar/gtracks"])
            far = central.until(f"{ROOT}/radar/gtracks")
            near = local.until(f"{ROOT}/radar/gtracks")
        finally:
            local.close()
    finally:
        central.close()
        router.stop()
    expected = [f"{ROOT}/radar/plots/b1/c1", f"{ROOT}/radar/plots/b1/c2", f"{ROOT}/radar/gtracks"]
    assert far == expected
    assert near == expected


def history_replies(z: ZenohConfig, key: str) -> list[bytes]:
    """Every reply from every queryable (target ALL, no consolidation), sorted."""
    with open_session(z) as s:
        replies = s.get(f"{ROOT}/{key}", target=zenoh.QueryTarget.ALL,
                        consolidation=zenoh.ConsolidationMode.NONE, timeout=5.0)
        return sorted(r.ok.payload.to_bytes() for r in replies if r.ok)


def test_only_the_bearing_tracker_answers_history_queries(secure: Secure) -> None:
    """A TMA of array a1 and the analyst get the history that bearing-tracker-a1
    serves; a site cannot query it; a queryable declared by another identity on the same
    keys is never asked."""
    with open_session(zc(secure, "bearing-tracker-a1")) as bt, \
            open_session(zc(secure, "tma-a1")) as rogue:
        real = bt.declare_queryable(f"{ROOT}/sonar/history/a1/*",
                                    lambda q: q.reply(q.key_expr, b"real"))
        fake = rogue.declare_queryable(f"{ROOT}/sonar/history/a1/*",
                                       lambda q: q.reply(q.key_expr, b"fake"))
        time.sleep(0.5)
        try:
            assert history_replies(zc(secure, "tma-a1"), "sonar/history/a1/7") == [b"real"]
            assert history_replies(zc(secure, "analyst"), "sonar/history/a1/7") == [b"real"]
            assert history_replies(zc(secure, site_identity("rx1")), "sonar/history/a1/7") == []
        finally:
            real.undeclare()
            fake.undeclare()


def on_host(s: Secure, identity: str, cn: str) -> ZenohConfig:
    """A client of the fusion router as ``identity`` (its password) presenting the
    certificate of common name ``cn`` (a certificate of the deployment's CA)."""
    z = zc(s, identity)
    assert z.tls is not None
    return dataclasses.replace(z, tls=dataclasses.replace(
        z.tls, cert=str(s.dir / f"{cn}.pem"), key=str(s.dir / f"{cn}.key")))


def test_stolen_password_is_useless_with_another_hosts_certificate(secure: Secure) -> None:
    """Attacker model (a): on host rx2 (its certificate host-rx2, not rx1's key) with
    site rx1's stolen password: its b1 plots never arrive, while the same certificate
    with its own identity site-rx2 publishes b2's plots (the end marker)."""
    listener = Listener(zc(secure, "analyst"))
    try:
        time.sleep(0.5)
        put_all(on_host(secure, site_identity("rx1"), "host-rx2"), ["radar/plots/b1/c1"],
                declared=False)
        put_all(on_host(secure, site_identity("rx2"), "host-rx2"), ["radar/plots/b2/c1"])
        keys = listener.until(f"{ROOT}/radar/plots/b2/c1")
    finally:
        listener.close()
    assert keys == [f"{ROOT}/radar/plots/b2/c1"]


def router_thief(s: Secure) -> ZenohConfig:
    """Attacker model (b): a plain client on site rx1's host with router-rx1's password
    from that host's credentials file and the host's certificate, not the router's."""
    return on_host(s, router_identity("rx1"), "host")


def test_router_password_reads_nothing(secure: Secure) -> None:
    """The thief subscribes to the whole root: global-fusion's tracks reach the analyst,
    not the thief."""
    stolen = Inbox()
    listener = Listener(zc(secure, "analyst"))
    try:
        with open_session(router_thief(secure)) as thief:
            thief.declare_subscriber(f"{ROOT}/**", stolen.on_sample)
            time.sleep(0.5)
            put_all(zc(secure, "global-fusion"), ["radar/gtracks"])
            listener.until(f"{ROOT}/radar/gtracks")
            time.sleep(0.5)
    finally:
        listener.close()
    got = stolen.get(0.1)
    assert got is None, f"the router's password read {got.key}"


def test_router_password_cannot_answer_history_queries(secure: Secure) -> None:
    """The thief's queryable on array a1's history (a1 is site rx1's) is never asked:
    tma-a1 gets the bearing tracker's reply only."""
    with open_session(zc(secure, "bearing-tracker-a1")) as bt, \
            open_session(router_thief(secure)) as thief:
        real = bt.declare_queryable(f"{ROOT}/sonar/history/a1/*",
                                    lambda q: q.reply(q.key_expr, b"real"))
        fake = thief.declare_queryable(f"{ROOT}/sonar/history/a1/*",
                                       lambda q: q.reply(q.key_expr, b"forged"))
        time.sleep(0.5)
        try:
            assert history_replies(zc(secure, "tma-a1"), "sonar/history/a1/7") == [b"real"]
        finally:
            real.undeclare()
            fake.undeclare()


def alive_keys(z: ZenohConfig) -> list[str]:
    """The liveliness tokens under root/alive/** that ``z`` sees, sorted."""
    with open_session(z) as s:
        return sorted(str(r.ok.key_expr) for r in s.liveliness().get(f"{ROOT}/alive/**",
                                                                       timeout=5.0) if r.ok)


def test_router_password_cannot_declare_liveliness_of_a_stopped_service(secure: Secure) -> None:
    """The thief declares the token of elementary-tracker-b1 (a site rx1 service, not
    running): the analyst sees global-fusion's token, not the thief's."""
    with open_session(zc(secure, "global-fusion")) as gf, \
            open_session(router_thief(secure)) as thief:
        real = gf.liveliness().declare_token(f"{ROOT}/alive/global_fusion/main")
        fake = thief.liveliness().declare_token(f"{ROOT}/alive/elementary_tracker/b1")
        time.sleep(0.5)
        try:
            assert alive_keys(zc(secure, "analyst")) == [f"{ROOT}/alive/global_fusion/main"]
        finally:
            real.undeclare()
            fake.undeclare()


def test_secure_chain_gives_the_in_process_tracks(secure: Secure) -> None:
    """The radar chain of two_targets.toml (SCANS scans), every process authenticated
    under mutual TLS and the access control: the global tracks (numbers, states,
    covariances to 1e-9) of common.wire.radar_chain on the same plots; ``pfusion
    status`` (viewer) lists every service with its counters."""
    d = secure.dir / "chain"
    d.mkdir()
    listener = open_session(zc(secure, "analyst"))
    inbox = Inbox()
    sub = listener.declare_subscriber(f"{ROOT}/radar/gtracks", inbox.on_sample)
    children: list[Child] = []
    connect = ("--connect", secure.endpoint)
    try:
        specs = [s for s in plan(secure.cfg, str(secure.config), COMMANDS)
                 if s.argv[0] in ("channel-plotter", "elementary-tracker", "global-fusion")]
        for spec in specs:
            children.append(Child(spec.name, *spec.argv, *connect,
                                  log=d / f"{spec.name.replace('/', '-')}.log"))
        sim = Child("simulate", "simulate", "--config", str(secure.config), "--scenario",
                    str(SCENARIO), "--scans", str(SCANS), *connect, "--wait-timeout", "120",
                    *(a for s in specs for a in ("--wait-alive", s.alive)), log=d / "simulate.log")
        children.append(sim)
        assert sim.wait(240) == 0, (d / "simulate.log").read_text()[-2000:]
        cfg = load(SCENARIO)
        scn = load_scenario(tomllib.loads(SCENARIO.read_text()))
        rc = RadarChain(cfg)
        ours = [g for _, msgs in run_scenario(scn, cfg.bases, cfg.arrays, 1, SCANS)
                for g in rc.step(msgs)]
        theirs: dict[float, dict] = {}
        deadline = time.monotonic() + 300  # the fusion may lag far behind under load
        while len(theirs) < len(ours) and time.monotonic() < deadline:
            env = inbox.get(0.2)
            if env is not None:
                msg = protocol.decode("gtracks", env.payload)
                theirs[msg["t"]] = msg
        status = subprocess.run(pfusion_argv("status", "--config", str(secure.config), *connect),
                                capture_output=True, text=True, timeout=120)
    finally:
        for c in reversed(children):
            c.stop()
        sub.undeclare()
        listener.close()
    assert len(ours) == SCANS and [g["t"] for g in ours] == sorted(theirs)
    confirmed = 0
    for g in ours:
        h = theirs[g["t"]]["tracks"]
        assert [k["id"] for k in g["tracks"]] == [k["id"] for k in h], g["t"]
        for a, b in zip(g["tracks"], h):
            np.testing.assert_allclose(a["x"], b["x"], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(np.ravel(a["P"]), b["P"], rtol=1e-9, atol=1e-9)
            confirmed += a["status"] == "confirmed"
    assert confirmed > 0
    rows = {"/".join(line.split()[:2]): line.split()[2] for line in status.stdout.splitlines()
            if len(line.split()) > 2}
    for spec in specs:  # the viewer sees every service, with its counters
        seen = [n for name, n in rows.items() if fnmatch.fnmatchcase(name, spec.alive)]
        assert seen and seen[0] != "-", (spec.alive, status.stdout, status.stderr)


def receiver(z: ZenohConfig, keys: list[str]) -> tuple[zenoh.Session, Inbox]:
    """A session subscribed to each of ``keys`` (under the root) into one inbox."""
    session = open_session(z)
    inbox = Inbox()
    for k in keys:
        session.declare_subscriber(f"{ROOT}/{k}", inbox.on_sample)
    return session, inbox


def test_viewer_reads_tracks_not_plots_nor_etracks_analyst_reads_everything(
        secure: Secure) -> None:
    """Read scopes: site rx1's plots, elementary-tracker-b1's etracks, then global-fusion's
    tracks. The analyst (root/**) receives all three; the viewer, subscribed to each key,
    only the global tracks, and nothing more half a second after them."""
    analyst = Listener(zc(secure, "analyst"))
    viewer, seen = receiver(zc(secure, "viewer"),
                            ["radar/plots/b1/*", "radar/etracks/b1", "radar/gtracks"])
    try:
        time.sleep(0.5)
        put_all(zc(secure, site_identity("rx1")), ["radar/plots/b1/c1"])
        put_all(zc(secure, "elementary-tracker-b1"), ["radar/etracks/b1"])
        put_all(zc(secure, "global-fusion"), ["radar/gtracks"])
        keys = analyst.until(f"{ROOT}/radar/gtracks")
        got: list[str] = []
        deadline = time.monotonic() + WAIT_S
        while f"{ROOT}/radar/gtracks" not in got:
            env = seen.get(0.1)
            if env is not None:
                got.append(env.key)
            assert time.monotonic() < deadline, f"the viewer never got the tracks; got {got}"
        time.sleep(0.5)
        while (env := seen.get(0.0)) is not None:
            got.append(env.key)
    finally:
        analyst.close()
        viewer.close()
    assert keys == [f"{ROOT}/radar/plots/b1/c1", f"{ROOT}/radar/etracks/b1", f"{ROOT}/radar/gtracks"]
    assert got == [f"{ROOT}/radar/gtracks"]


def test_operator_tma_sets_bounds_a_viewer_cannot(secure: Secure) -> None:
    """The viewer's bounds and support (plain puts) never reach the analyst; operator-tma's
    do (support first, bounds as the end marker)."""
    listener = Listener(zc(secure, "analyst"))
    try:
        time.sleep(0.5)
        put_all(zc(secure, "viewer"), ["sonar/tma/bounds/a1", "sonar/tma/support/a1"],
                declared=False)
        put_all(zc(secure, "operator-tma"), ["sonar/tma/support/a1", "sonar/tma/bounds/a1"])
        keys = listener.until(f"{ROOT}/sonar/tma/bounds/a1")
    finally:
        listener.close()
    assert keys == [f"{ROOT}/sonar/tma/support/a1", f"{ROOT}/sonar/tma/bounds/a1"]


def test_tma_input_acked_for_operator_tma_not_for_a_viewer(secure: Secure) -> None:
    """``pfusion tma-input`` against a real tma service (identity tma-a1) fed one btracks
    cycle by bearing-tracker-a1 and site-rx1: as operator-tma the input is acked (exit
    0); as viewer its put never reaches the tma service (not in its log; no ack: exit 1)."""
    log = secure.dir / "tma-a1.log"
    tma = Child("tma-a1", "tma", "--config", str(secure.config), "--array", "a1",
                "--connect", secure.endpoint, log=log)
    viewer, seen = receiver(zc(secure, "viewer"), ["sonar/tma/a1"])
    try:
        with open_session(zc(secure, "site-rx1")) as site, \
                open_session(zc(secure, "bearing-tracker-a1")) as bt:
            deadline = time.monotonic() + WAIT_S
            t = 0.0
            while seen.get(0.2) is None:  # until the tma service publishes (once it runs)
                assert time.monotonic() < deadline and tma.alive(), log.read_text()
                t += 20.0
                site.put(f"{ROOT}/sonar/detections/a1", protocol.encode(
                    {"v": 1, "t": t, "seq": int(t), "array": "a1", "brg": [], "amp": [],
                     "own": {"x": 0.0, "y": 0.0, "heading": 0.0, "speed": 3.0}}), congestion_control=BLOCK)
                bt.put(f"{ROOT}/sonar/btracks/a1", protocol.encode(
                    {"v": 1, "t": t, "array": "a1", "tracks": [
                        {"id": 4, "status": "tentative", "x": [1.0, 0.0], "P": [1e-4, 0.0, 0.0, 1e-4],
                         "quality": 1.0, "ambiguous": False}]}), congestion_control=BLOCK)
        runs = {}
        for who, timeout in (("operator-tma", "30"), ("viewer", "3")):
            out = secure.dir / f"tma-input-{who}.log"
            c = Child(f"tma-input-{who}", "tma-input", "clear", "--config", str(secure.config),
                      "--array", "a1", "--track", "4", "--birth", "20.0", "--timeout", timeout,
                      "--identity", who, "--connect", secure.endpoint, log=out)
            runs[who] = (c.wait(60), out.read_text())
    finally:
        viewer.close()
        tma.stop()
    assert runs["operator-tma"][0] == 0, runs["operator-tma"][1]
    assert "accepted by tma/a1: clear of track 4 born at t=20.0" in runs["operator-tma"][1]
    assert runs["viewer"][0] == 1 and "no answer from tma/a1" in runs["viewer"][1], runs["viewer"][1]
    assert log.read_text().count("tma_clear") == 1, log.read_text()


SITE_HOST = """
[zenoh]
root = "pf/v1"

[[radar.base]]
id = "b1"
tx = [-35000.0, 20000.0, 300.0]
rx = [0.0, 0.0, 30.0]
channels = ["c1", "c2", "c3"]

[[site]]
id = "rx1"
bases = ["b1"]

[zenoh.auth]
credentials = "credentials.txt"

[zenoh.tls]
root_ca = "{d}/ca.pem"
cert = "{d}/host.pem"
key = "{d}/host.key"
mtls = true
"""


def test_run_on_a_site_host_with_the_sites_identity(secure: Secure) -> None:
    """Site rx1's host: its file lists base b1 only and its credentials hold only the
    identities it runs (site-rx1 and b1's services; no read role). ``pfusion run`` with
    its default identity (viewer) is refused at once (exit 2, no password); with
    ``--identity site-rx1`` it starts b1's plotter and tracker, whose liveliness a viewer
    at the fusion router sees."""
    d = secure.dir / "site-host"
    d.mkdir()
    (d / "site.toml").write_text(SITE_HOST.format(d=secure.dir))
    mine = ("site-rx1", "channel-plotter-b1", "elementary-tracker-b1")
    lines = [line for line in (secure.dir / "credentials.txt").read_text().splitlines()
             if line.partition(":")[0] in mine]
    (d / "credentials.txt").write_text("\n".join(lines) + "\n")
    (d / "credentials.txt").chmod(0o600)
    argv = ("run", "--config", str(d / "site.toml"), "--connect", secure.endpoint)
    refused = subprocess.run(pfusion_argv(*argv), capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "'viewer'" in refused.stderr, refused.stderr
    run = Child("run-rx1", *argv, "--identity", "site-rx1", log=d / "run.log")
    want = [f"{ROOT}/alive/channel_plotter/b1", f"{ROOT}/alive/elementary_tracker/b1"]
    try:
        deadline = time.monotonic() + 120
        while (seen := alive_keys(zc(secure, "viewer"))) != want:
            assert run.alive() and time.monotonic() < deadline, (seen, (d / "run.log").read_text())
            time.sleep(0.5)
    finally:
        assert run.stop() == 0, (d / "run.log").read_text()


def cert_config(d: Path, name: str) -> ZenohConfig:
    """The [zenoh] table of a deployment (no auth) whose client certificate is <name>."""
    (d / "d.toml").write_text(MIXED + f'[zenoh.tls]\nroot_ca = "ca.pem"\ncert = "{name}.pem"\n'
                                      f'key = "{name}.key"\nmtls = true\n')
    return load(d / "d.toml").zenoh


def test_certificate_expiring_within_7_days_warns_once(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    make_ca(tmp_path, "ca")
    make_cert(tmp_path, "ca", "soon", days=3)
    z = cert_config(tmp_path, "soon")
    with caplog.at_level("WARNING"):
        transport.zenoh_config(["tls/127.0.0.1:1"], [], "client", security=z)
        transport.zenoh_config(["tls/127.0.0.1:1"], [], "client", security=z)
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert len(warned) == 1 and "zenoh.tls.cert" in warned[0] and "in 3.0 days" in warned[0], warned
    caplog.clear()
    make_cert(tmp_path, "ca", "fine")
    with caplog.at_level("WARNING"):
        transport.zenoh_config(["tls/127.0.0.1:1"], [], "client", security=cert_config(tmp_path, "fine"))
    assert not caplog.records


def test_expired_certificate_is_refused_with_exit_2(tmp_path: Path) -> None:
    """In-process: ConfigError naming the key; a service given it exits with code 2 (not
    restarted by run)."""
    make_ca(tmp_path, "ca")
    make_expired_cert(tmp_path, "ca", "old")
    with pytest.raises(ConfigError) as e:
        transport.zenoh_config(["tls/127.0.0.1:1"], [], "client",
                               security=cert_config(tmp_path, "old"))
    assert e.value.key == "zenoh.tls.cert" and "expired on 2026-01-02" in str(e.value)
    out = subprocess.run(pfusion_argv("global-fusion", "--config", str(tmp_path / "d.toml"),
                                      "--connect", "tls/127.0.0.1:1"),
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "zenoh.tls.cert" in out.stderr and "expired" in out.stderr, \
        out.stderr
