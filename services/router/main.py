"""``pfusion router``: a Zenoh router in a Python process (the Rust core routes).

With ``--config F`` whose deployment has [zenoh.tls] / [zenoh.auth], the router listens
with its certificate, checks every client's user/password against the dictionary and,
unless ``access_control = false``, applies the access control generated from the
deployment (common.deploy.acl, ``pfusion acl``): deny by default (docs/security.md).

A session that stops reading (an operator's tool whose subscriber blocks) is closed
after STALLED_CLOSE_US of back-pressure, well inside the lease of every link (2 s
between routers, 10 s for clients: transport.ROUTER_LEASE_MS, CLIENT_LEASE_MS): each
of the router's receive threads that routes a sample to the stalled session waits that
long, one after the other (seen: 2 threads, 2 waits), and a link that no free thread
read for a whole lease is closed as expired, losing its samples in flight. With 1 s,
the two waits came to 2 s and a loaded CI machine lost 3 plots of one base that way;
with Zenoh's default of 5 s, the publishers' own sessions gave up (a normal subscriber
lost 1517 of 3000 samples). With 250 ms the waits span 0.5 s (docs/faults.md,
tests/integration/test_faults.py).

A secured router audits (unless ``--no-audit``): its own Zenoh log goes through
common.bus.audit (common.bus.log_tap), which writes access-control denials and failed
logins as rate-limited WARNING lines with identity, key and cause, and the router
answers queries on ``<root>/audit/router/<identity>`` with their counts (``rejected``
of a service's metrics). A queryable, not samples on ``metrics/**``: those would reach
every root subscriber and show the router in the view as a service without liveliness
(docs/security.md, "Audit")."""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import time
from collections.abc import Callable
from typing import Any

import zenoh

from common.bus.audit import AUDIT_TARGETS, Audit
from common.bus.log_tap import LogTap
from common.bus.rust_log import init_zenoh_log, parse
from common.bus.transport import Inbox, stop_on_signals, zenoh_config
from common.cli import load_config
from common.deploy.acl import access_control
from common.deploy.config import Config, ConfigError
from common.wire import protocol

log = logging.getLogger("router")
STALLED_CLOSE_US = 250_000  # 8x under the shortest lease (transport.ROUTER_LEASE_MS)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--listen", action="append", required=True,
                   help="endpoint to listen on, e.g. tcp/127.0.0.1:7447 (repeatable)")
    p.add_argument("--connect", action="append", default=[],
                   help="another router to connect to (repeatable)")
    p.add_argument("--config", help="deployment TOML file: its [zenoh.tls], [zenoh.auth] and "
                                    "access control apply to this router")
    p.add_argument("--identity", help="this router's username towards --connect routers "
                                      "(router-<site>, docs/security.md)")
    p.add_argument("--no-audit", dest="audit", action="store_false",
                   help="a secured router without its audit of denials and failed logins")


def router_config(args: argparse.Namespace, cfg: Config | None) -> zenoh.Config:
    """The router's Zenoh config: endpoints, and the deployment's security if any."""
    c = zenoh_config(args.connect, args.listen, mode="router",
                     security=cfg.zenoh if cfg is not None else None)
    c.insert_json5("transport/link/tx/queue/congestion_control/block/wait_before_close",
                   str(STALLED_CLOSE_US))
    auth = cfg.zenoh.auth if cfg is not None else None
    if auth is not None and auth.access_control:
        tls = cfg.zenoh.tls  # type: ignore[union-attr]
        if args.connect and (tls is None or not tls.mtls):
            raise ConfigError("zenoh.tls.mtls", "a router that connects to another router "
                              "applies access control only under mutual TLS (it knows the "
                              "upstream router by its certificate); set mtls = true, or "
                              "access_control = false for this router")
        c.insert_json5("access_control", json.dumps(access_control(cfg)))  # type: ignore[arg-type]
    return c


def audit_metrics(counters: dict[str, int], instance: str, started: float) -> dict[str, Any]:
    """The audit's counters in the shape of a service's metrics (common.bus.service)."""
    return {"v": protocol.VERSION, "t": 0.0, "service": "router", "instance": instance,
            "in": 0, "out": 0, "rejected": counters, "missed": {},
            "p50_ms": 0.0, "p99_ms": 0.0, "queue": 0, "up_s": time.monotonic() - started}


def may_use(acl: dict[str, Any]) -> Callable[[str, str], bool]:
    """Whether the access control ``acl`` gives a user some ingress right (to send or
    declare) on a key or below it."""
    rules = {r["id"]: r["key_exprs"] if "ingress" in r["flows"] else [] for r in acl.get("rules", [])}
    keys: dict[str, list[zenoh.KeyExpr]] = {}
    for p in acl.get("policies", []):
        for subject in p["subjects"]:
            keys.setdefault(subject, []).extend(zenoh.KeyExpr(k) for r in p["rules"] for k in rules[r])

    def check(user: str, key: str) -> bool:
        try:
            here, below = zenoh.KeyExpr(key), zenoh.KeyExpr(f"{key}/**")
        except zenoh.ZError:
            return False
        return any(k.intersects(here) or k.intersects(below) for k in keys.get(user, []))

    return check


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args) if args.config else None
    secure = cfg is not None and (cfg.zenoh.auth is not None or cfg.zenoh.tls is not None)
    acl = access_control(cfg) if cfg is not None and cfg.zenoh.auth is not None \
        and cfg.zenoh.auth.access_control else {}
    tap = LogTap(Audit(may_use=may_use(acl)), parse(os.environ.get("RUST_LOG"))) \
        if secure and args.audit else None  # RUST_LOG read before the audit adds its targets
    with tap if tap is not None else contextlib.nullcontext():
        if tap is not None:
            init_zenoh_log(AUDIT_TARGETS)
        conf = router_config(args, cfg)
        stop = stop_on_signals()
        started = time.monotonic()
        with zenoh.open(conf) as session:
            log.info("router listening on %s%s", ", ".join(args.listen),
                     " (security of the deployment on)" if secure else "")
            queries, instance = Inbox(), args.identity or "main"
            counts = session.declare_queryable(f"{cfg.zenoh.root}/audit/router/{instance}",
                                               queries.on_query) if tap and cfg else None
            while not stop.wait(0.2):
                while tap is not None and (env := queries.get(0.0)) is not None:
                    env.query.reply(env.key, protocol.encode(
                        audit_metrics(tap.counters(), instance, started)))
            if counts is not None:
                counts.undeclare()
    log.info("router stopped")
    return 0
