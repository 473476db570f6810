"""Who is alive and what they count: the liveliness tokens under ``<root>/alive/`` and
the latest counters each service publishes on ``<root>/metrics/**`` (every 2 s).
Read by ``pfusion status``, ``pfusion view`` and ``pfusion run --exit-after-sim``."""

from __future__ import annotations

import dataclasses
import logging
from collections import Counter
from collections.abc import Iterable, Iterator
from typing import Any

import zenoh

from common.bus.transport import Inbox, open_session
from common.deploy.config import ZenohConfig
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


FORGED: Counter[str] = Counter()  # metrics keys whose payload named another service


def reports(inbox: Inbox) -> Iterator[tuple[tuple[str, str], dict[str, Any]]]:
    """The metrics waiting in ``inbox``, as ((service, instance), counters). The identity
    is the key's (``<root>/metrics/<service>/<instance>``, which the ACL grants to that
    service alone), never the payload's: a payload that names another service is
    ignored, logged and counted in FORGED; an invalid one is logged and skipped."""
    while (env := inbox.get(0.0)) is not None:
        *_, service, instance = env.key.split("/")
        try:
            m = protocol.unpack(env.payload)
            named = (str(m["service"]), str(m["instance"]))
        except (protocol.DecodeError, KeyError, TypeError) as e:
            log.error("invalid metrics on %s: %s", env.key, e)
            continue
        if named != (service, instance):
            FORGED[env.key] += 1
            log.error("metrics on %s name %s/%s: ignored (%d so far on this key)", env.key,
                      *named, FORGED[env.key])
            continue
        yield (service, instance), m


def take(inbox: Inbox, metrics: dict[tuple[str, str], dict[str, Any]]) -> None:
    """Keep the latest counters per (service, instance)."""
    for who, m in reports(inbox):
        metrics[who] = m


class Drain:
    """Whether services have worked through their input: since :meth:`mark`, each expected
    (service, instance) has published two metrics in a row with an empty queue and the
    same input count, i.e. nothing arrived for a whole metrics period (2 s). It holds a
    client session of its own on ``zc``; ``expected`` are the services' liveliness names
    ("service/instance", the instance may be ``*``), each matched by at least one."""

    def __init__(self, zc: ZenohConfig, expected: Iterable[str]) -> None:
        self.expected = [zenoh.KeyExpr(name) for name in expected]
        self.inbox = Inbox()
        self.last_two: dict[zenoh.KeyExpr, list[dict[str, Any]]] = {}
        self.session = open_session(dataclasses.replace(zc, listen=[]))
        self._sub = self.session.declare_subscriber(f"{zc.root}/metrics/**", self.inbox.on_sample)

    def mark(self) -> None:
        """Forget the reports so far: only later ones count."""
        for _ in reports(self.inbox):
            pass
        self.last_two.clear()

    def drained(self) -> bool:
        for (service, instance), m in reports(self.inbox):
            who = zenoh.KeyExpr(f"{service}/{instance}")
            self.last_two[who] = [*self.last_two.get(who, [])[-1:], m]
        quiet = {who: len(two) == 2 and two[0]["in"] == two[1]["in"]
                 and two[0]["queue"] == two[1]["queue"] == 0 for who, two in self.last_two.items()}
        return all(any(who.intersects(name) for who in quiet)
                   and all(q for who, q in quiet.items() if who.intersects(name))
                   for name in self.expected)

    def close(self) -> None:
        self.session.close()
