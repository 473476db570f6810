"""The deployment's global tracks from the messages of its partitions (docs/networks.md,
"Partitions"): each partition of `[radar.network] partitions` publishes
`radar/gtracks/<p>` with its own tracks (numbers unique across partitions); the track
set at time t is the union of every partition's latest message at or before t.

`GtracksUnion.push` gives the unions in time order, each once every partition has
published at or after its time (for scoring: `pfusion evaluate`); without partitions a
message passes through; a message of a key that is not a partition's, or not after its
partition's previous one, is refused (`Rejected`). `latest` gives at once the union of
the latest message of every key seen (`radar/gtracks` or a partition's) within
`LATEST_S` of message time before this one (for a live picture: `pfusion view`, which
may not know the deployment's partitions).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from common.core.rejection import Rejected
from common.wire import protocol

Msg = dict[str, Any]
LATEST_S = 10.0  # s of message time after which a silent key's tracks leave `latest`


def partition_of(key: str, root: str) -> str | None:
    """`p` of `<root>/radar/gtracks/<p>`, None for `<root>/radar/gtracks`."""
    rest = key[len(root) + 1:].split("/") if key.startswith(root + "/") else []
    return rest[2] if len(rest) == 3 else None


class GtracksUnion:
    """Latest gtracks message per partition, and their unions (module doc)."""

    def __init__(self, partitions: Sequence[str]) -> None:
        self.parts = tuple(partitions)
        self.kept: dict[str, list[Msg]] = {p: [] for p in self.parts}
        self.done = float("-inf")
        self.last: dict[str | None, Msg] = {}

    def _add(self, partition: str | None, msg: Msg) -> None:
        if partition not in self.kept:
            raise Rejected("partition", f"gtracks of partition {partition!r}; the deployment's "
                                        f"partitions are {list(self.parts)}")
        kept = self.kept[partition]
        if kept and msg["t"] <= kept[-1]["t"]:
            raise Rejected("time_backwards", f"gtracks of {partition} at t={msg['t']} after "
                                             f"t={kept[-1]['t']}")
        kept.append(msg)

    def _union(self, t: float) -> Msg:
        tracks: list[Msg] = []
        for kept in self.kept.values():
            before = [m for m in kept if m["t"] <= t]
            tracks += before[-1]["tracks"] if before else []
        return {"v": protocol.VERSION, "t": t, "tracks": tracks}

    def push(self, partition: str | None, msg: Msg) -> list[Msg]:
        """The unions completed by `msg` of `partition`, in time order."""
        if not self.parts:
            return [msg]
        self._add(partition, msg)
        if not all(self.kept.values()):
            return []
        ready = min(kept[-1]["t"] for kept in self.kept.values())
        times = sorted({m["t"] for kept in self.kept.values() for m in kept
                        if self.done < m["t"] <= ready})
        out = [self._union(t) for t in times]
        self.done = max(self.done, ready)
        for p, kept in self.kept.items():
            old = [i for i, m in enumerate(kept) if m["t"] <= self.done]
            self.kept[p] = kept[old[-1]:] if old else kept
        return out

    def latest(self, partition: str | None, msg: Msg) -> Msg:
        """The union of the latest message of every key seen, `msg` included, at its
        time (module doc)."""
        self.last[partition] = msg
        self.last = {k: m for k, m in self.last.items() if m["t"] >= msg["t"] - LATEST_S}
        return {"v": protocol.VERSION, "t": msg["t"],
                "tracks": [k for m in self.last.values() for k in m["tracks"]]}
