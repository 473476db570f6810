"""Who is alive and what they count: the liveliness tokens under ``<root>/alive/`` and
the latest counters each service publishes on ``<root>/metrics/**`` (every 2 s).
Read by ``pfusion status`` and ``pfusion view``."""

from __future__ import annotations

import logging
from typing import Any

import zenoh

from common.bus.transport import Inbox
from common.wire import protocol

log = logging.getLogger("liveliness")


def alive(session: zenoh.Session, root: str) -> list[tuple[str, str]]:
    """(service, instance) of every liveliness token under root/alive/."""
    prefix = f"{root}/alive/"
    found = set()
    for reply in session.liveliness().get(f"{root}/alive/**", timeout=2.0):
        if reply.ok is not None:
            service, _, instance = str(reply.ok.key_expr)[len(prefix):].partition("/")
            found.add((service, instance))
    return sorted(found)


def take(inbox: Inbox, metrics: dict[tuple[str, str], dict[str, Any]]) -> None:
    """Keep the latest counters per (service, instance)."""
    while (env := inbox.get(0.0)) is not None:
        try:
            m = protocol.unpack(env.payload)
            metrics[(str(m["service"]), str(m["instance"]))] = m
        except (protocol.DecodeError, KeyError) as e:
            log.error("invalid metrics on %s: %s", env.key, e)
