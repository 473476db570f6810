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
tests/integration/test_faults.py)."""

from __future__ import annotations

import argparse
import json
import logging

import zenoh

from common.bus.transport import stop_on_signals, zenoh_config
from common.cli import load_config
from common.deploy.acl import access_control
from common.deploy.config import Config, ConfigError

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


def main(args: argparse.Namespace) -> int:
    cfg = load_config(args) if args.config else None
    conf = router_config(args, cfg)
    stop = stop_on_signals()
    with zenoh.open(conf):
        secure = cfg is not None and (cfg.zenoh.auth or cfg.zenoh.tls)
        log.info("router listening on %s%s", ", ".join(args.listen),
                 " (security of the deployment on)" if secure else "")
        while not stop.wait(0.2):
            pass
    log.info("router stopped")
    return 0
