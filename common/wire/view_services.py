"""The services table of ``pfusion view``: one row per (service, instance) ever seen, from
the liveliness tokens under ``<root>/alive/``, the counters on ``<root>/metrics/**`` and
the simulator's ``sim/status``.

A row's state is ``alive`` (its token is present), ``finished`` (its token went after the
process said it ended normally: a service's last metrics carry ``state = "finished"``, a
simulator publishes ``sim/status`` ``done``) or ``gone`` (the token went without that:
killed, crashed, frozen past its lease). Uptime is the service's own (``up_s`` of its
metrics) when it publishes metrics, else the time since this view saw its token appear
(a lower bound). Restarts are those this view saw: a token that came back after going,
or ``up_s`` that went down between two metrics (a restart faster than the liveliness
poll). Times are passed in (``now``, monotonic seconds): no clock here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

Who = tuple[str, str]


@dataclass
class _Life:
    since: float          # when this view saw the token appear (monotonic s)
    restarts: int = 0
    finished: bool = False
    gone: bool = False
    up_s: float = -1.0    # the latest up_s of its metrics (-1: none)
    up_at: float = 0.0    # when that metrics arrived (monotonic s)


class ServicesTable:
    """Rows of the services table; each ``set_*`` says whether the rows changed."""

    def __init__(self) -> None:
        self._alive: set[Who] = set()
        self._metrics: dict[Who, dict[str, Any]] = {}
        self._lives: dict[Who, _Life] = {}

    def _life(self, who: Who, now: float) -> _Life:
        life = self._lives.get(who)
        if life is None:
            life = self._lives[who] = _Life(since=now)
        return life

    def set_alive(self, live: set[Who], now: float) -> bool:
        """The (service, instance) liveliness tokens present now."""
        if live == self._alive:
            return False
        for who in live - self._alive:
            life = self._life(who, now)
            if life.gone:  # back after going: a restart (or a new run of a tool)
                life.restarts += 1
                life.since, life.gone, life.finished, life.up_s = now, False, False, -1.0
        for who in self._alive - live:
            self._life(who, now).gone = True
        self._alive = set(live)
        return True

    def set_metrics(self, metrics: dict[Who, dict[str, Any]], now: float) -> bool:
        """The latest counters per (service, instance) (``pfusion status``'s)."""
        changed = {k: m for k, m in metrics.items() if self._metrics.get(k) is not m}
        for who, m in changed.items():
            life = self._life(who, now)
            up = float(m.get("up_s", -1.0))
            if 0.0 <= up < life.up_s and not life.gone:  # restarted between two polls
                life.restarts += 1
            life.up_s, life.up_at = up, now
            life.finished = m.get("state") == "finished"
        self._metrics.update(changed)
        return bool(changed)

    def sim_done(self) -> bool:
        """A simulator said it published its last scan: the simulate tokens present now
        end as ``finished`` when they go."""
        sims = [w for w in self._alive if w[0] == "simulate"]
        for who in sims:
            self._lives[who].finished = True
        return bool(sims)

    def rows(self, now: float) -> list[dict[str, Any]]:
        """One row per service ever seen, sorted; ``up`` is the uptime at ``now`` (s),
        ``alive`` kept for readers of the earlier rows."""
        rows = []
        for who in sorted(set(self._lives) | self._alive | set(self._metrics)):
            life = self._life(who, now)
            alive = who in self._alive
            state = "alive" if alive else "finished" if life.finished else "gone"
            up = life.up_s + now - life.up_at if life.up_s >= 0.0 else now - life.since
            row: dict[str, Any] = {"service": who[0], "instance": who[1], "alive": alive,
                                   "state": state, "restarts": life.restarts,
                                   "up": round(up, 1) if alive else None}
            m = self._metrics.get(who)
            if m is not None:
                row |= {"in": m["in"], "out": m["out"], "rejected": sum(m.get("rejected", {}).values()),
                        "reasons": m.get("rejected", {}), "missed": sum(m.get("missed", {}).values()),
                        "p50": round(m["p50_ms"], 2), "p99": round(m["p99_ms"], 2),
                        "queue": m["queue"], "t": round(m["t"], 3)}
            rows.append(row)
        return rows
