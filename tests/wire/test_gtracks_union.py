"""common.wire.gtracks_union: the deployment's global tracks from its partitions'."""

from __future__ import annotations

import pytest

from common.core.rejection import Rejected
from common.wire.gtracks_union import GtracksUnion, partition_of


def msg(t: float, *ids: int) -> dict:
    return {"v": 1, "t": t, "tracks": [{"id": i} for i in ids]}


def ids(m: dict) -> list[int]:
    return sorted(k["id"] for k in m["tracks"])


def test_a_union_comes_once_every_partition_reached_its_time() -> None:
    u = GtracksUnion(("west", "east"))
    assert u.push("west", msg(1.0, 1)) == []
    assert u.push("west", msg(2.0, 1, 3)) == []
    out = u.push("east", msg(1.5, 2))  # west at 1 and east at 1.5: both up to 1.5
    assert [(m["t"], ids(m)) for m in out] == [(1.0, [1]), (1.5, [1, 2])]
    out = u.push("east", msg(2.0, 2, 4))
    assert [(m["t"], ids(m)) for m in out] == [(2.0, [1, 2, 3, 4])]
    with pytest.raises(Rejected, match="t=2.0"):
        u.push("east", msg(2.0))
    with pytest.raises(Rejected, match="partition"):
        u.push(None, msg(3.0))


def test_without_partitions_a_message_passes_through() -> None:
    u = GtracksUnion(())
    m = msg(1.0, 5)
    assert u.push(None, m) == [m]


def test_latest_joins_every_key_seen_recently() -> None:
    u = GtracksUnion(())
    assert ids(u.latest("west", msg(1.0, 1))) == [1]
    assert ids(u.latest("east", msg(1.2, 2))) == [1, 2]
    assert ids(u.latest("west", msg(2.0, 3))) == [2, 3]
    assert ids(u.latest("west", msg(20.0, 5))) == [5]  # east silent for 10 s of message time


def test_partition_of_a_key() -> None:
    assert partition_of("pf/v1/radar/gtracks/west", "pf/v1") == "west"
    assert partition_of("pf/v1/radar/gtracks", "pf/v1") is None
