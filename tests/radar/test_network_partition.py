"""Global fusion partitioned by region (common.radar.network.partition): two partitions
split at x = 0 on the synthetic network of tests/radar/network_scene.py, every report
pushed to both, handovers and claims exchanged in process after each report
(tests/radar/partition_run.py), against one NetworkFusion on the same reports."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from common.core.params import ParamError
from common.core.track_table import Status
from common.radar.network.fusion import NetworkFusion, NetworkReport
from common.radar.network.params import NetworkParams
from common.radar.network.partition import Handed, Partition, Regions
from tests.radar import network_scene as ns
from tests.radar import partition_run

PARAMS = NetworkParams(partitions=("west", "east"), partition_splits=(0.0,), partition_margin=3e3)
DURATION = 35.0
WARM_UP = 15.0
# three aircraft cross x = 0 (two west -> east, one east -> west), two stay in their half
P0 = np.array([[-3e3, 20e3, 8e3], [4e3, -25e3, 6e3], [-40e3, 0.0, 9e3], [30e3, 30e3, 7e3],
               [-2e3, -5e3, 10e3]])
V = np.array([[250.0, 0, 0], [-250.0, 30, 0], [0, 200.0, 0], [-50, -200.0, 0], [240, 60, 0]])
CROSSING = (0, 1, 4)


@functools.lru_cache(maxsize=None)
def scene() -> ns.Scene:
    rng = np.random.default_rng(1)
    return ns.simulate(rng, ns.network(rng), P0, V, DURATION)


@functools.lru_cache(maxsize=None)
def run_partitioned() -> tuple[list[NetworkReport], dict[str, Partition]]:
    reports, parts, _ = partition_run.run(scene(), PARAMS)
    return reports, parts


@functools.lru_cache(maxsize=None)
def run_single() -> list[NetworkReport]:
    s = scene()
    f = NetworkFusion(s.bases)
    out: list[NetworkReport] = []
    for b, t, rep in s.reports:
        out += f.push(s.bases[b].id, t, rep)
    return out + f.flush()


def holders(reports: list[NetworkReport], k: int) -> list[int]:
    """Per report after the warm-up, the number of the confirmed track within 2 km of
    aircraft k (0: none)."""
    out = []
    for r in reports:
        if r.t < WARM_UP:
            continue
        pos, _ = scene().truth(r.t)
        d = np.linalg.norm(r.x[:, [0, 2, 4]] - pos[k], axis=1)
        near = (d < 2e3) & (r.status != Status.TENTATIVE)
        out.append(int(r.id[near][0]) if near.sum() == 1 else 0)
    return out


def test_two_partitions_hold_what_one_holds() -> None:
    """The union of the two partitions' reports scores as one centre's: every aircraft
    held, no duplicate, no false track, no number switch, RMSE within 1.3 CRLB."""
    two, _ = run_partitioned()
    one = ns.score(scene(), run_single(), WARM_UP)
    s = ns.score(scene(), two, WARM_UP)
    assert s.scans == one.scans >= 15
    assert (s.missed, s.duplicates, s.false, s.switches) == (0, 0, 0, 0)
    assert (one.missed, one.duplicates, one.false, one.switches) == (0, 0, 0, 0)
    assert np.sqrt(s.err2 / s.crlb2).max() <= 1.3


def test_a_crossing_track_is_handed_over_once_and_keeps_its_number() -> None:
    """Each aircraft crossing x = 0 is handed over once (handed = adopted = acked = 3,
    no timeout, no conflict), by a track of the partition it came from, and is held by
    one number in every report after the warm-up (no gap, no duplicate)."""
    two, parts = run_partitioned()
    w, e = parts["west"].counts, parts["east"].counts
    assert w["handed"] + e["handed"] == len(CROSSING)
    assert w["adopted"] + e["adopted"] == len(CROSSING)
    assert w["acked"] + e["acked"] == len(CROSSING)
    assert w["timeouts"] + e["timeouts"] + w["conflicts"] + e["conflicts"] == 0
    for k in range(P0.shape[0]):
        h = holders(two, k)
        assert len(set(h)) == 1 and h[0] > 0, (k, h)
        came_from = 0 if P0[k, 0] < 0 else 1
        assert (h[0] - 1) % 2 == came_from, (k, h[0])  # numbered by its first partition
    assert not any(p.pending for p in parts.values())


def test_numbers_are_striped_and_initiation_stays_in_the_region() -> None:
    """west numbers 1, 3, 5 ...; east 2, 4, 6 ...: no number held by both, and a
    partition holds the other's numbers only by adoption; at the end each partition
    holds only tracks inside its region widened by the margin."""
    two, parts = run_partitioned()
    for part in parts.values():
        T = part.f.tracks
        xp, _ = T.predicted(part.f.done)
        assert not part.regions.beyond(part.k, xp[T.status != Status.TENTATIVE]).any()
    w, e = parts["west"], parts["east"]
    assert not set(w.f.tracks.id) & set(e.f.tracks.id)
    assert np.sum(w.f.tracks.id % 2 == 0) <= w.counts["adopted"]
    assert np.sum(e.f.tracks.id % 2 == 1) <= e.counts["adopted"]
    assert len(w.f.tracks) and len(e.f.tracks)


def handed(part: Partition, n: int = 0) -> Handed:
    """A Handed copy of row n of `part`'s tracks."""
    T = part.f.tracks
    return Handed(int(T.id[n]), int(T.status[n]), float(T.t[n]), T.x[n], T.P[n],
                  float(T.t_update[n]), float(T.born[n]), int(T.hits[n]),
                  tuple((part.f.ids[b], e) for b, e in T.members[n].items()))


def fresh(name: str) -> Partition:
    return Partition(NetworkFusion(scene().bases, PARAMS), PARAMS, name)


def test_adoption_is_idempotent_and_leaves_out_held_members() -> None:
    """A second copy of a handed track (a lost ack) adds nothing; a member already held
    by a track of the receiver is left out and counted; an unknown base is counted."""
    _, parts = run_partitioned()
    h = handed(parts["west"])
    east = fresh("east")
    east.adopt(h)
    east.adopt(h)
    T = east.f.tracks
    assert list(T.id) == [h.number] and len(T.owner) == len(h.members)
    other = dataclasses.replace(h, number=h.number + 2,
                                members=(h.members[0], ("nowhere", 7)))
    east.adopt(other)
    assert T.members[T.row_of(other.number)] == {}
    assert (east.counts["conflicts"], east.counts["unknown_base"]) == (1, 1)
    assert list(T.id) == sorted(T.id)


def test_an_unacked_handover_is_kept_counted_and_retried() -> None:
    """Handed over and never acked: hidden from the reports while pending, kept and
    counted as a timeout after handover_timeout s, then handed over again."""
    _, parts = run_partitioned()
    east = fresh("east")
    h = handed(parts["west"])
    east.adopt(h)  # east holds a track; move it into the west beyond the margin
    T = east.f.tracks
    T.x[0, 0] = -PARAMS.partition_margin - 1e3
    T.status[0] = Status.CONFIRMED
    t = float(T.t[0])
    first = east.due(t)
    assert [(to, g.number) for to, g in first] == [("west", h.number)]
    assert east.due(t + 1.0) == []
    report = east.f._report(t)[0]
    assert h.number in report.id and h.number not in east.visible(report).id
    again = east.due(t + PARAMS.handover_timeout + 0.1)
    assert east.counts["timeouts"] == 1 and [g.number for _, g in again] == [h.number]
    east.acked(h.number)
    assert len(T) == 0 and east.counts["acked"] == 1


def test_claimed_members_are_not_opened_again() -> None:
    """Over the first 6 s, east, given every elementary track as claimed by west, opens
    no track; without the claims it opens some (on the aircraft in its region)."""
    s = scene()
    claims = sorted({(s.bases[b].id, int(e)) for b, t, rep in s.reports for e in rep.id})
    for claim, opened in ((True, False), (False, True)):
        east = fresh("east")
        if claim:
            east.claim("west", claims)
        for b, t, rep in s.reports:
            if t < 6.0:
                east.f.push(s.bases[b].id, t, rep)
        assert (len(east.f.tracks) > 0) == opened


def test_regions_and_rules() -> None:
    r = Regions(("a", "b", "c"), "y", (-1e3, 1e3), 500.0)
    x = np.zeros((4, 6))
    x[:, 2] = [-2e3, -1e3, 999.0, 1.6e3]
    assert list(r.index(x)) == [0, 1, 1, 2]
    assert list(r.beyond(1, x)) == [True, False, False, True]
    assert list(r.beyond(0, x)) == [False, False, True, True]
    for bad in ({"partitions": ("a", "b"), "partition_splits": ()},
                {"partitions": ("a", "a"), "partition_splits": (0.0,)},
                {"partitions": ("a", "b/c"), "partition_splits": (0.0,)},
                {"partitions": ("a", "b", "c"), "partition_splits": (1.0, 0.0)},
                {"partition_axis": "z"}):
        with pytest.raises(ParamError):
            NetworkParams(**bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="not one of"):
        Partition(NetworkFusion(scene().bases, PARAMS), PARAMS, "north")
