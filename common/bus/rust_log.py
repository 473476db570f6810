"""Zenoh's own log (``RUST_LOG``, tracing's EnvFilter syntax) without secrets
(docs/security.md, "Credentials in logs").

Zenoh 1.10.2 logs its whole configuration, the client's ``transport/auth/usrpwd/password``
in clear text included, as one DEBUG event of the target ``zenoh::api::session`` when
a session opens; no other event carries a password, and a client's password can only
be given to Zenoh in its configuration. So every process caps that target at ``info``
before Zenoh's logger starts: :func:`sanitise` drops the directives that could enable
it (the same target, a longer one, and span filters, which match events whatever their
target) and appends the cap, which EnvFilter applies as the most specific directive.
Everything else keeps the level asked for.

:func:`enabled` answers, for a parsed specification, whether an event of a target and
level passes it (EnvFilter's rule: the longest directive target that is a prefix of the
event's target, else the bare level): the router's audit (common.bus.audit) raises a few
targets for itself and forwards only what the operator's own ``RUST_LOG`` asked for.
"""

from __future__ import annotations

import os
import re

import zenoh

LEVELS = ("off", "error", "warn", "info", "debug", "trace")
SECRET_TARGETS = ("zenoh::api::session",)  # DEBUG: "Config: Config(...)", passwords included
CAP = "info"
_TARGET = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(::[A-Za-z0-9_]+)*$")

Directive = tuple[str, int]  # (target, "" for every target; level index in LEVELS)


def parse(spec: str | None) -> list[Directive]:
    """The directives of a ``RUST_LOG`` value that name a target or none, with a level
    (a bare target means ``trace``, as in EnvFilter); span filters and unknown forms
    are left out."""
    out: list[Directive] = []
    for part in (spec or "").split(","):
        part = part.strip()
        if not part or "[" in part or "{" in part:
            continue
        target, sep, level = part.partition("=")
        if not sep:
            if target.lower() in LEVELS:
                out.append(("", LEVELS.index(target.lower())))
            elif _TARGET.match(target):
                out.append((target, LEVELS.index("trace")))
            continue
        if _TARGET.match(target) and level.strip().lower() in LEVELS:
            out.append((target, LEVELS.index(level.strip().lower())))
    return out


def render(directives: list[Directive]) -> str:
    return ",".join(f"{t}={LEVELS[n]}" if t else LEVELS[n] for t, n in directives)


def _touches_secret(target: str) -> bool:
    return any(target.startswith(s) for s in SECRET_TARGETS)


def sanitise(spec: str | None, extra: list[Directive] | None = None) -> str:
    """``spec`` without a directive that could log a secret, plus ``extra`` (targets a
    process raises for itself), plus the cap of every secret target; "" when nothing at
    all is asked for."""
    kept = [d for d in parse(spec) if not _touches_secret(d[0])]
    kept += [d for d in (extra or []) if not _touches_secret(d[0])]
    if not kept:
        return ""
    return render(kept + [(s, min(LEVELS.index(CAP), level(kept, s))) for s in SECRET_TARGETS])


def level(directives: list[Directive], target: str) -> int:
    """The most detailed level (index in LEVELS) EnvFilter passes for ``target``: that
    of the longest directive target that is a prefix of it (the last of equals)."""
    best: Directive | None = None
    for d in directives:
        if target.startswith(d[0]) and (best is None or len(d[0]) >= len(best[0])):
            best = d
    return best[1] if best is not None else 0


def enabled(directives: list[Directive], target: str, event_level: str) -> bool:
    """Whether EnvFilter with ``directives`` passes an event of ``target`` at ``event_level``."""
    return LEVELS.index(event_level.lower()) <= level(directives, target)


def init_zenoh_log(extra: list[Directive] | None = None) -> str:
    """Start Zenoh's logger (once per process; later calls change nothing) on the
    sanitised ``RUST_LOG``, which also replaces the variable in this process's
    environment (and so its children's); returns what Zenoh was given."""
    spec = sanitise(os.environ.get("RUST_LOG"), extra)
    if spec:
        os.environ["RUST_LOG"] = spec
        zenoh.try_init_log_from_env()
    else:
        os.environ.pop("RUST_LOG", None)
    return spec
