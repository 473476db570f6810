"""Global fusion partitioned by region, with handover (docs/networks.md, "Partitions").

The plane is cut along one ENU axis (`partition_axis`) at `partition_splits` into
regions, one per partition, each run by its own `NetworkFusion` over every base's
elementary tracks. A partition (`Partition`, k of n):

- numbers its tracks k+1, k+1+n, k+1+2n, ...: unique across partitions;
- opens a track only on a fix inside its region (the `region` hook of NetworkFusion);
- leaves out of its initiation the (base, elementary id) members that the other
  partitions' tracks hold (`claim`, from their published tracks; the `excluded` hook),
  so that an aircraft near a border is not opened twice;
- hands a confirmed (or coasting) track over once its position is more than
  `partition_margin` beyond its region (hysteresis): `due` exports it as `Handed`
  (number, status, state and covariance at t, update and birth times, confirmation
  cycles, members by base id) to the partition whose region holds it, leaves it out
  of its reports (`visible`) and keeps updating it until the receiver's ack (`acked`
  drops it); after `handover_timeout` s of message time without an ack it keeps it,
  counts a timeout and hands it over again while it is still outside;
- adopts a handed track (`adopt`) with its number, members held by one of its own
  tracks left out (counted), and acks it (again, if it already holds the number: a
  lost ack).

Pure: no I/O, message time only.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from common.core.track_table import Status
from common.radar.network.fusion import NetworkFusion, NetworkReport
from common.radar.network.params import NetworkParams

AXES = {"x": 0, "y": 2}  # column of [x vx y vy z vz]


@dataclass(frozen=True)
class Handed:
    """A track handed over at t: its number, status (Status code), x (6,) and P (6, 6)
    predicted to t, last update and birth times, confirmation cycles (hits), members
    (base id, elementary id)."""

    number: int
    status: int
    t: float
    x: np.ndarray
    P: np.ndarray
    t_update: float
    born: float
    hits: int
    members: tuple[tuple[str, int], ...]


class Regions:
    """Intervals of one ENU axis: region k is [splits[k-1], splits[k]) (unbounded at
    both ends)."""

    def __init__(self, names: Sequence[str], axis: str, splits: Sequence[float],
                 margin: float) -> None:
        self.names = tuple(names)
        self.col = AXES[axis]
        self.splits = np.asarray(splits, dtype=float)
        self.margin = margin
        self.lo = np.concatenate([[-np.inf], self.splits])
        self.hi = np.concatenate([self.splits, [np.inf]])

    def index(self, x: np.ndarray) -> np.ndarray:
        """Region of each state (..., 6)."""
        return np.searchsorted(self.splits, x[..., self.col], side="right")

    def beyond(self, k: int, x: np.ndarray) -> np.ndarray:
        """States (..., 6) more than the margin outside region k."""
        c = x[..., self.col]
        return (c < self.lo[k] - self.margin) | (c >= self.hi[k] + self.margin)


class Partition:
    """Partition `name` of `params.partitions` around its fusion centre (module doc);
    `counts`: handed, acked, timeouts, adopted, conflicts (members left out on
    adoption), unknown_base (members of bases not configured here)."""

    def __init__(self, fusion: NetworkFusion, params: NetworkParams, name: str) -> None:
        if name not in params.partitions:
            raise ValueError(f"partition {name!r} is not one of [radar.network] partitions "
                             f"{list(params.partitions)}")
        self.f = fusion
        self.name = name
        self.regions = Regions(params.partitions, params.partition_axis,
                               params.partition_splits, params.partition_margin)
        self.k = params.partitions.index(name)
        self.timeout = params.handover_timeout
        fusion.tracks.striped(self.k + 1, len(params.partitions))
        fusion.region = lambda x: bool(self.regions.index(x) == self.k)
        self.pending: dict[int, float] = {}  # number -> message time handed over
        self.claims: dict[str, set[tuple[int, int]]] = {}
        self.counts: Counter[str] = Counter()

    def due(self, t: float) -> list[tuple[str, Handed]]:
        """Handovers at t: (receiving partition, track) for each live confirmed or
        coasting track more than the margin outside the region, not already pending."""
        for n, sent in list(self.pending.items()):
            if t - sent > self.timeout:
                del self.pending[n]
                self.counts["timeouts"] += 1
        T = self.f.tracks
        if not len(T) or not np.isfinite(t):
            return []
        xp, Pp = T.predicted(t)
        out = []
        rows = (T.status != Status.TENTATIVE) & self.regions.beyond(self.k, xp)
        for r in np.flatnonzero(rows).tolist():
            n = int(T.id[r])
            if n in self.pending:
                continue
            members = tuple((self.f.ids[b], int(e)) for b, e in sorted(T.members[r].items()))
            h = Handed(n, int(T.status[r]), t, xp[r], Pp[r], float(T.t_update[r]),
                       float(T.born[r]), int(T.hits[r]), members)
            self.pending[n] = t
            self.counts["handed"] += 1
            out.append((self.regions.names[int(self.regions.index(xp[r]))], h))
        return out

    def adopt(self, h: Handed) -> None:
        """Take track h with its number (nothing if already held)."""
        T = self.f.tracks
        self.pending.pop(h.number, None)
        if T.row_of(h.number) >= 0:
            return
        known = [(self.f.ids.index(b), e) for b, e in h.members if b in self.f.ids]
        self.counts["unknown_base"] += len(h.members) - len(known)
        free = [(b, e) for b, e in known if (b, e) not in T.owner]
        self.counts["conflicts"] += len(known) - len(free)
        T.insert(h.number, h.status, h.t, h.x, h.P, h.t_update, h.born, h.hits, free)
        self.counts["adopted"] += 1

    def acked(self, number: int) -> None:
        """The receiver holds track `number`: drop it here (also after a timeout)."""
        self.pending.pop(number, None)
        T = self.f.tracks
        r = T.row_of(number)
        if r >= 0:
            T.remove(np.arange(len(T)) == r)
            self.counts["acked"] += 1

    def claim(self, partition: str, members: Sequence[tuple[str, int]]) -> None:
        """The members of every track of another partition (its latest report)."""
        if partition == self.name:
            return
        ids = self.f.ids
        self.claims[partition] = {(ids.index(b), int(e)) for b, e in members if b in ids}
        self.f.excluded = set().union(*self.claims.values())

    def visible(self, r: NetworkReport) -> NetworkReport:
        """Report r without the tracks handed over and not yet acked."""
        if not self.pending:
            return r
        keep = ~np.isin(r.id, list(self.pending))
        return dataclasses.replace(r, id=r.id[keep], status=r.status[keep], x=r.x[keep],
                                   P=r.P[keep], n_bases=r.n_bases[keep],
                                   member=r.member[keep], has=r.has[keep])
