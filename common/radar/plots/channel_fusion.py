"""Fused plots of one bistatic base (seed 001, step 23, operation 221: modules 31-34).

Scan assembly: a scan at time t is complete when every configured channel has reported
t, or as soon as any channel reports a later time (missing channels count as empty).

Module 31, aggregation: plots p1, p2 of different channels aggregate when their
2-sigma intervals overlap on r_b, v_b and theta (001 [5]; on r_b and v_b only at a
range-Doppler base, whose plots have no theta). Aggregates are the connected
components of that relation, with one constraint: at most one plot per channel in an
aggregate (two plots of one channel are never fused, directly or through a third plot).
Within a component that would violate it, compatible pairs are merged closest pair
first (normalised distance max_c |d_c| / (2 (s1_c + s2_c)), in [0, 1]) while the two
groups share no channel. So a plot compatible with two aggregates bridges them into one
unless they have a channel in common; then it joins the one holding its closest
compatible plot and the other stays separate.

Module 32, fusion: inverse-covariance weighting (001 [6]-[7]); the covariances are
diagonal (001 [4]) so it is per component; azimuths are averaged on the circle.

Module 34: score = number of channels in the aggregate; with n <= 2 configured
channels every fused plot is kept (singles too), with n > 2 only score >= n - p.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from common.core.angles import wrap_2pi, wrap_pi
from common.core.gating import overlap_pairs
from common.core.params import Params, Range, positive
from common.core.rejection import Rejected
from common.radar.plots.stamps import ahead_rule

COLUMNS = ("rb", "vb", "az", "srb", "svb", "saz")


@dataclass(frozen=True)
class PlotterParams(Params):
    """Parameters of table [radar.plotter].

    n_sigma: half-width of the aggregation intervals in sigmas (2, as in 001 [5]).
    max_ahead: a plot stamped more than this ahead of the latest time of its base's other
        channels (or, without one, of its own channel's previous plots) is rejected
        (`ahead`): one far-future stamp must not hold the base's scans back (s).
    """

    n_sigma: float = 2.0
    max_ahead: float = 60.0

    RANGES: ClassVar[dict[str, Range]] = {"n_sigma": positive("sigma"), "max_ahead": positive("s")}


@dataclass
class Plots:
    """Columnar plots y = [rb, vb, az] with sigmas (001 [1]-[4]), plus n_ch per plot
    (number of channels of a fused plot, 1 for a channel plot). A range-Doppler base's
    plots are y = [rb, vb]: az and saz are None (both or neither)."""

    rb: np.ndarray
    vb: np.ndarray
    az: np.ndarray | None
    srb: np.ndarray
    svb: np.ndarray
    saz: np.ndarray | None
    n_ch: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    def __post_init__(self) -> None:
        if (self.az is None) != (self.saz is None):
            raise ValueError("plots carry both az and saz or neither")

    def __len__(self) -> int:
        return int(self.rb.shape[0])

    @property
    def azimuth(self) -> bool:
        """The plots measure theta (false: a range-Doppler base's)."""
        return self.az is not None

    @classmethod
    def empty(cls, azimuth: bool = True) -> "Plots":
        z = np.zeros(0)
        a = z if azimuth else None
        return cls(z, z, a, z, z, a, np.zeros(0, dtype=np.int64))

    @classmethod
    def concat(cls, parts: list["Plots"], azimuth: bool = True) -> "Plots":
        """The plots of parts, one after the other (all of the kind `azimuth`)."""
        if any(p.azimuth != azimuth for p in parts):
            raise ValueError("plots with and without azimuth cannot be concatenated")
        if not parts:
            return cls.empty(azimuth)
        return cls(*(None if getattr(parts[0], c) is None
                     else np.concatenate([getattr(p, c) for p in parts]) for c in COLUMNS + ("n_ch",)))

    def take(self, idx: np.ndarray) -> "Plots":
        return Plots(*(None if getattr(self, c) is None else getattr(self, c)[idx]
                       for c in COLUMNS + ("n_ch",)))

    @property
    def y(self) -> np.ndarray:
        """Measurements (N, 3) = [rb, vb, az], or (N, 2) = [rb, vb] without azimuth."""
        return np.column_stack([self.rb, self.vb] + ([] if self.az is None else [self.az]))

    @property
    def sigma(self) -> np.ndarray:
        """Standard deviations (N, 3), or (N, 2) without azimuth."""
        return np.column_stack([self.srb, self.svb] + ([] if self.saz is None else [self.saz]))


def compatible_pairs(p: Plots, channel: np.ndarray, n_sigma: float = 2.0
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs (a, b) of plots of different channels satisfying 001 [5], and their
    normalised distance max_c |d_c| / (n_sigma (s_a,c + s_b,c)) in [0, 1]."""
    a, b = overlap_pairs(p.rb - n_sigma * p.srb, p.rb + n_sigma * p.srb)  # 001 [5] r_b
    keep = channel[a] != channel[b]
    a, b = a[keep], b[keep]
    d_rb = np.abs(p.rb[a] - p.rb[b]) / (n_sigma * (p.srb[a] + p.srb[b]))
    d_vb = np.abs(p.vb[a] - p.vb[b]) / (n_sigma * (p.svb[a] + p.svb[b]))
    if p.az is None or p.saz is None:  # range-Doppler base: 001 [5] on r_b and v_b only
        ok = d_vb <= 1.0
        return a[ok], b[ok], np.maximum(d_rb, d_vb)[ok]
    d_az = np.abs(wrap_pi(p.az[a] - p.az[b])) / (n_sigma * (p.saz[a] + p.saz[b]))
    # 001 [5]: [y1 - 2s1, y1 + 2s1] and [y2 - 2s2, y2 + 2s2] intersect iff
    # |y1 - y2| <= 2 (s1 + s2); azimuth difference taken on the circle.
    ok = (d_vb <= 1.0) & (d_az <= 1.0)
    dist = np.maximum(np.maximum(d_rb, d_vb), d_az)[ok]
    return a[ok], b[ok], dist


def components(n: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Connected components of the undirected graph of n nodes and edges (a, b): label
    per node, components numbered by their smallest node (as scipy's
    connected_components, without its sparse-matrix set-up: a fifth of a plotter scan).
    Minimum-label propagation with pointer jumping; at the fixed point every node holds
    the smallest node of its component."""
    lab = np.arange(n)
    while True:
        m = np.minimum(lab[a], lab[b])
        new = lab.copy()
        np.minimum.at(new, a, m)
        np.minimum.at(new, b, m)
        new = new[new]
        if np.array_equal(new, lab):
            return np.unique(lab, return_inverse=True)[1]
        lab = new


def _constrained_merge(n: int, a: np.ndarray, b: np.ndarray, dist: np.ndarray,
                       channel: np.ndarray) -> np.ndarray:
    """Closest-pair-first union of the pairs (a, b) while groups share no channel;
    returns a group label per plot. Only run on components with a channel conflict."""
    parent = np.arange(n)
    chans = [{int(c)} for c in channel]

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k in np.lexsort((b, a, dist)):
        ra, rb = find(int(a[k])), find(int(b[k]))
        if ra != rb and not (chans[ra] & chans[rb]):
            parent[rb] = ra
            chans[ra] |= chans[rb]
    return np.array([find(i) for i in range(n)], dtype=np.intp)


def aggregate(p: Plots, channel: np.ndarray, n_sigma: float = 2.0) -> np.ndarray:
    """Module 31: aggregate label per plot (0..K-1), see the module docstring."""
    n = len(p)
    if n == 0:
        return np.zeros(0, dtype=np.intp)
    a, b, dist = compatible_pairs(p, channel, n_sigma)
    labels = components(n, a, b)
    k = int(labels.max()) + 1
    # components holding two plots of one channel need the constrained merge
    pair = labels.astype(np.int64) * (int(channel.max()) + 1) + channel
    uniq, cnt = np.unique(pair, return_counts=True)
    bad = np.unique(uniq[cnt > 1] // (int(channel.max()) + 1))
    if bad.size:
        in_bad = np.isin(labels, bad)
        sub = np.flatnonzero(in_bad)
        local = np.full(n, -1, dtype=np.intp)
        local[sub] = np.arange(sub.size)
        e = in_bad[a]
        groups = _constrained_merge(sub.size, local[a[e]], local[b[e]], dist[e], channel[sub])
        labels = labels.copy()
        labels[sub] = k + groups
    return np.unique(labels, return_inverse=True)[1]


def fuse(p: Plots, labels: np.ndarray) -> Plots:
    """Module 32: inverse-covariance weighted pseudo-measurement per aggregate
    (001 [6]-[7]), n_ch = number of plots (= channels) in the aggregate (module 34)."""
    k = int(labels.max()) + 1 if labels.size else 0
    if k == 0:
        return Plots.empty(p.azimuth)
    n_ch = np.bincount(labels, minlength=k)
    first = np.unique(labels, return_index=True)[1]
    comps = [(p.rb, p.srb), (p.vb, p.svb)]
    if p.az is not None and p.saz is not None:
        ref = p.az[first][labels]  # azimuths averaged as offsets from one member of each aggregate
        comps.append((wrap_pi(p.az - ref), p.saz))
    out = []
    for y, s in comps:
        w = 1.0 / np.square(s)  # R_j^-1, diagonal (001 [4])
        R = 1.0 / np.bincount(labels, weights=w, minlength=k)  # 001 [7]
        out.append((R * np.bincount(labels, weights=w * y, minlength=k), np.sqrt(R)))  # 001 [6]
    (rb, srb), (vb, svb) = out[:2]
    if p.az is None:
        return Plots(rb, vb, None, srb, svb, None, n_ch.astype(np.int64))
    daz, saz = out[2]
    az = wrap_2pi(p.az[first] + daz)
    return Plots(rb, vb, az, srb, svb, saz, n_ch.astype(np.int64))


def accept(fused: Plots, n_channels: int, p: int) -> Plots:
    """Module 34 acceptance: n <= 2 channels keep all; n > 2 keep score >= n - p."""
    if n_channels <= 2:
        return fused
    return fused.take(np.flatnonzero(fused.n_ch >= n_channels - p))


def fuse_scan(per_channel: list[Plots], n_channels: int, p: int, n_sigma: float = 2.0,
              azimuth: bool = True) -> Plots:
    """Modules 31-34 on the channel plots of one scan (one Plots per channel, all with
    azimuth, or all without at a range-Doppler base)."""
    plots = Plots.concat(per_channel, azimuth)
    channel = np.repeat(np.arange(len(per_channel)), [len(q) for q in per_channel])
    return accept(fuse(plots, aggregate(plots, channel, n_sigma)), n_channels, p)


class PlotFusion:
    """Scan assembly + modules 31-34 for one base; driven by message times only.
    azimuth: the base's plots carry theta (false: a range-Doppler base)."""

    def __init__(self, channels: list[str], p: int, params: PlotterParams | None = None,
                 azimuth: bool = True) -> None:
        self.channels = list(channels)
        self.p = p
        self.params = params or PlotterParams()
        self.azimuth = azimuth
        self._last = {c: -np.inf for c in self.channels}
        self._unanchored: set[str] = set()  # last time taken with no reference to test it
        self.evicted: list[tuple[str, float]] = []  # (channel, t) dropped as `ahead` later
        self._ahead: dict[str, float] = {}  # each channel's last time rejected as `ahead`
        self._emitted = -np.inf
        self._newest = -np.inf
        self._pending: dict[float, dict[str, Plots]] = {}

    def push(self, channel: str, t: float, plots: Plots) -> list[tuple[float, Plots]]:
        """Add one channel's plots at time t; returns the scans completed by it, in time
        order, as (t, fused plots). Raises Rejected for an unknown channel, plots of the
        wrong kind (with / without azimuth), a time not after that channel's last, or a
        scan already emitted."""
        if channel not in self._last:
            raise Rejected("unknown_channel", f"channel '{channel}' is not configured")
        if plots.azimuth != self.azimuth:
            raise Rejected("azimuth_mismatch", f"channel {channel}: plots with azimuth = "
                           f"{plots.azimuth} at a base with azimuth = {self.azimuth}")
        self._check_ahead(channel, t)
        if t <= self._last[channel]:
            raise Rejected("time_backwards", f"channel {channel}: t={t} after t={self._last[channel]}")
        if t <= self._emitted:
            raise Rejected("late_scan", f"channel {channel}: scan t={t} already published")
        self._anchor(channel, t)
        self._last[channel] = t
        self._pending.setdefault(t, {})[channel] = plots
        held = {self._last[c] for c in self._unanchored}  # untested times wait for a reference
        self._newest = max([self._emitted] + [v for c, v in self._last.items() if c not in self._unanchored])
        n = len(self.channels)
        done = [s for s in sorted(self._pending)
                if s not in held and (s < self._newest or len(self._pending[s]) == n)]
        out = []
        for s in done:
            got = self._pending.pop(s)
            per_channel = [got.get(c, Plots.empty(self.azimuth)) for c in self.channels]
            out.append((s, fuse_scan(per_channel, len(self.channels), self.p, self.params.n_sigma,
                                     self.azimuth)))
            self._emitted = s
        return out

    def take_evicted(self) -> list[tuple[str, float]]:
        """The (channel, t) evicted as `ahead` since the last call (for the counters)."""
        out, self.evicted = self.evicted, []
        return out

    def _check_ahead(self, channel: str, t: float) -> None:
        """The `max_ahead` rule: reference = the latest time of the other channels whose
        time was itself tested, else this channel's previous time; a plot past it by more
        than max_ahead is rejected, unless a majority of the base's channels (two plots of a
        one-channel base) were rejected within max_ahead of it: the base's clock jumped, and
        the jump is taken. A time taken with no reference (a base's first plots) that a
        tested time later shows to lie more than max_ahead ahead is evicted: its pending
        scan entry is dropped and recorded in `evicted`, its channel starts afresh."""
        lim, n = self.params.max_ahead, len(self.channels)
        others = [v for c, v in self._last.items() if c != channel and v > -np.inf and c not in self._unanchored]
        own = self._last[channel]
        ref = max(others) if others else (own if own > -np.inf and channel not in self._unanchored else None)
        ahead_rule(self._ahead, f"channel {channel}", t, ref, lim, n)
        for c in sorted(self._unanchored):
            if self._last[c] > t + lim:
                self._evict(c)

    def _anchor(self, channel: str, t: float) -> None:
        """Mark the channels whose times are now tested against another: this one when a
        reference existed or another channel lies within max_ahead, and those channels."""
        lim = self.params.max_ahead
        near = [c for c, v in self._last.items() if c != channel and abs(v - t) <= lim]
        own = self._last[channel]
        tested = any(c not in self._unanchored for c in near) or (
            own > -np.inf and (channel not in self._unanchored or t - own <= lim))
        if tested or near:
            self._unanchored.difference_update([channel, *near])
        else:
            self._unanchored.add(channel)

    def _evict(self, channel: str) -> None:
        t = self._last[channel]
        scan = self._pending.get(t, {})
        scan.pop(channel, None)
        if not scan:
            self._pending.pop(t, None)
        self.evicted.append((channel, t))
        self._last[channel] = -np.inf
        self._unanchored.discard(channel)
