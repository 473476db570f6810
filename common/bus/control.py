"""The services' control queryables (``<root>/control/<service>/<instance>``, answered by
:class:`common.bus.service.Service`): what each one has processed, and a reset that
restarts it with a fresh state.

:func:`states` asks every service at once (one query, every queryable answers);
:func:`ahead` says which of them already processed a message time at or after a
recording's first one (a replay into them would have its inputs rejected as late);
:func:`reset` restarts the named ones and waits until each answers again, fresh.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import zenoh

from common.wire import protocol

Who = tuple[str, str]
QUERY_TIMEOUT_S = 5.0
log = logging.getLogger("control")


def states(session: zenoh.Session, root: str, timeout: float = QUERY_TIMEOUT_S) -> dict[Who, dict[str, Any]]:
    """(service, instance) -> its control reply (counters, ``t``, ``fresh``), of every
    service that answered within ``timeout``; a reply that does not decode is logged."""
    out: dict[Who, dict[str, Any]] = {}
    for r in session.get(f"{root}/control/**", target=zenoh.QueryTarget.ALL, timeout=timeout):
        if r.ok is None:
            log.error("control query: error reply %s", r.err.payload.to_string() if r.err else "?")
            continue
        try:
            m = protocol.unpack(r.ok.payload.to_bytes())
            out[(str(m["service"]), str(m["instance"]))] = m
        except (protocol.DecodeError, KeyError) as e:
            log.error("control query: bad reply on %s: %s", r.ok.key_expr, e)
    return out


def ahead(replies: dict[Who, dict[str, Any]], t_first: float) -> dict[Who, float]:
    """The services that processed a message of time >= ``t_first`` (and their last
    time): a replay starting at t_first would be behind them."""
    return {w: float(m["t"]) for w, m in sorted(replies.items())
            if not m.get("fresh", False) and float(m["t"]) >= t_first}


def reset(session: zenoh.Session, root: str, who: list[Who], timeout: float) -> list[Who]:
    """Reset the services ``who`` and wait until each answers fresh; returns those that
    did not within ``timeout`` s (empty: all restarted)."""
    for service, instance in who:
        key = f"{root}/control/{service}/{instance}?reset"
        if not any(r.ok is not None for r in session.get(key, timeout=QUERY_TIMEOUT_S)):
            log.error("reset of %s/%s: no reply", service, instance)
    deadline = time.monotonic() + timeout
    missing = set(who)
    while missing and time.monotonic() < deadline:
        now = states(session, root, timeout=min(QUERY_TIMEOUT_S, max(deadline - time.monotonic(), 0.1)))
        missing -= {w for w, m in now.items() if m.get("fresh", False)}
        if missing:
            time.sleep(0.1)
    return sorted(missing)
