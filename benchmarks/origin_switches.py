"""Number switches by origin (issue 14 diagnostic of benchmarks/dense_scale.py): which
truth feeds each confirmed global track, as opposed to which truth the Euclidean 3-D
GOSPA assignment of the scoring gives it.

Each elementary track is labelled, at its scan, with the truth nearest to it in its
base's measurement space: the truth states projected by g of 001 [47] into
[r_b, v_b, theta], Mahalanobis distance with the elementary covariance R (module 63's
[r_b, v_b, theta] block), unlabelled beyond the chi-square(3) quantile at `prob`. A
global track is labelled with the truth that a strict majority of its contributing
members carries (unlabelled otherwise: a mixed or a clutter track). A truth keeps its
last track while that track is labelled with it, else takes the one labelled with it
that the GOSPA assignment gives it, else the lowest number labelled with it. Switches
of that series (common.evaluation.metrics.count_switches) are association errors:
a track fed by another aircraft's elementary tracks, or replaced by a new one.
A switch of the scoring's series (benchmarks/dense_scale.py passes the joint trajectory
GOSPA assignment, common.evaluation.trajectory_gospa) at which the truth keeps its track
by origin (the same, on both scans) is a crossing of the scoring: the truth's correctly
fed track scored on another truth.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from common.core.angles import wrap_pi
from common.core.gating import chi2_gate, mahalanobis_sq
from common.evaluation.metrics import count_switches
from common.radar.elementary.tracker import ElementaryTracks
from common.radar.fusion.assoc import YR
from common.radar.fusion.report import GlobalTracks
from common.radar.geometry.bistatic import project


class OriginLabels:
    """Truth labels of elementary and confirmed global tracks, scan by scan."""

    def __init__(self, tx: np.ndarray, rx: np.ndarray, prob: float = 0.999) -> None:
        self.tx, self.rx = tx, rx
        self.gate = chi2_gate(prob, 3)
        self.elem: dict[tuple[int, int], int] = {}  # (base index, elementary id) -> truth
        self.series: list[dict[int, int | None]] = []
        self.by_truth: dict[int, int] = {}

    def etracks(self, b: int, tracks: ElementaryTracks, truth_ids: np.ndarray,
                truth_x: np.ndarray) -> None:
        """Label base b's elementary tracks of one scan with the truths (ids, states)."""
        for k in [k for k in self.elem if k[0] == b]:
            del self.elem[k]
        if len(tracks) == 0 or truth_ids.size == 0:
            return
        y = tracks.x[:, YR]
        R = tracks.P[:, YR][:, :, YR]
        g = project(truth_x, self.tx[b], self.rx[b])
        best = np.full(len(tracks), np.inf)
        arg = np.zeros(len(tracks), dtype=np.intp)
        for j0 in range(0, g.shape[0], 256):
            d = g[None, j0:j0 + 256] - y[:, None]
            d[..., 2] = wrap_pi(d[..., 2])
            m = mahalanobis_sq(d, R)
            a = m.argmin(axis=1)
            v = m[np.arange(len(tracks)), a]
            better = v < best
            best[better], arg[better] = v[better], a[better] + j0
        for e in np.flatnonzero(best <= self.gate):
            self.elem[(b, int(tracks.id[e]))] = int(truth_ids[arg[e]])

    def cycle(self, g: GlobalTracks, confirmed: np.ndarray, truth_ids: np.ndarray,
              gospa: dict[int, int | None]) -> None:
        """Label the confirmed tracks (mask over g's rows) of one cycle; the truth ->
        track series by origin (the GOSPA assignment `gospa` breaks ties)."""
        label: dict[int, int] = {}
        for s in np.flatnonzero(confirmed):
            votes = Counter(self.elem.get((b, int(g.member[s, b])))
                            for b in np.flatnonzero(g.has[s]))
            n = sum(votes.values())
            truth, count = max(votes.items(), key=lambda kv: kv[1], default=(None, 0))
            if truth is not None and 2 * count > n:
                label[int(g.id[s])] = truth
        held: dict[int, list[int]] = {}
        for k, truth in sorted(label.items()):
            held.setdefault(truth, []).append(k)
        step: dict[int, int | None] = {}
        for i in truth_ids.tolist():
            ks = held.get(i, [])
            last = self.by_truth.get(i)
            pick = last if last in ks else gospa.get(i) if gospa.get(i) in ks else (
                ks[0] if ks else None)
            step[i] = pick
            if pick is not None:
                self.by_truth[i] = pick
        self.series.append(step)

    def summary(self, gospa_series: list[dict[int, int | None]]) -> tuple[int, int, int]:
        """(switches by origin, switches of the scoring's series, of them crossings)."""
        last: dict[int, int] = {}
        crossing = 0
        before: dict[int, int | None] = {}
        for step, own in zip(gospa_series, self.series):
            for i, k in step.items():
                if k is None:
                    continue
                if i in last and last[i] != k:
                    crossing += before.get(i) is not None and before.get(i) == own.get(i)
                last[i] = k
            before = own
        return (count_switches(self.series).switches, count_switches(gospa_series).switches,
                crossing)
