"""The exit of a pair of frozen bearing tracks by the V of its separations (step 4 of
common.sonar.bearing.tracker; common.core.crossing_groups).

A frozen pair (a group of two tracks of common.sonar.bearing.pairs) coasts on 004's
memory: its difference on the bearing rates it entered with. When those rates are off
(a young track, a third contact in the crossing), the extrapolated pair stays between the
two contacts long after they separated, and the order of its tracks is not sure. Its
detections, once resolved (at least SIGN_SIGMAS sigma apart: var R_a + R_b), are either
in the pair's order or exchanged; which, follows from whether the pair has crossed:
`common.core.crossing_groups.crossing_time` fits the V of the separations |X_a - X_b| of
every scan since the pair was first frozen (and its predicted separation then), and the
pair's order at t is its entry order if t_c > t, the reverse otherwise. When GNN gave
the tracks their detections in that order, both are released for the scan (alpha = 1,
as common.sonar.bearing.pairs releases a pair whose predicted order is sure).
Deviation (not in 004; stated in common.core.crossing_groups).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from common.core.angles import wrap_pi
from common.core.crossing_groups import crossing_time
from common.sonar.bearing.pairs import SIGN_SIGMAS

MIN_AFTER = 3  # separations after the V's apex before the pair counts as crossed
RETAIN_S = 60.0  # s: a pair's episode outlives a gap of its 004 flag (a slow crossing's edges)


@dataclass
class PairEpisode:
    """A frozen pair (uids a < b): its order d = b_a - b_b before the ambiguity (sign) and
    the separation samples (t, |X_a - X_b|)."""

    sign: float
    t: list[float] = field(default_factory=list)
    a: list[float] = field(default_factory=list)
    seen: float = 0.0  # the last time the pair was frozen in one group


class PairOrders:
    """Episodes of the pairs of tracks frozen in one group, keyed by (uid a, uid b), a < b."""

    def __init__(self) -> None:
        self.episodes: dict[tuple[int, int], PairEpisode] = {}

    def observe(self, t: float, uids: np.ndarray, groups: list[np.ndarray], brg: np.ndarray,
                det_brg: np.ndarray) -> None:
        """Open an episode for every pair of tracks of a frozen group (its order from the
        predicted bearings brg (N,), its predicted separation the first sample), add the
        separation of the detections (det_brg (N,), NaN for none) of each group of two,
        and drop the episodes of a deleted track (uids (N,) are the live tracks) or of a
        pair not frozen together for RETAIN_S."""
        for g in groups:
            for x, i in enumerate(g):
                for j in g[x + 1:]:
                    a, b = (i, j) if uids[i] < uids[j] else (j, i)
                    key = (int(uids[a]), int(uids[b]))
                    if key not in self.episodes:
                        d = float(wrap_pi(brg[a] - brg[b]))
                        self.episodes[key] = PairEpisode(float(np.sign(d)) or 1.0, [t], [abs(d)])
                    ep = self.episodes[key]
                    ep.seen = t
                    dz = float(wrap_pi(det_brg[a] - det_brg[b]))
                    if g.size == 2 and not np.isnan(dz):
                        ep.t.append(t)
                        ep.a.append(abs(dz))
        alive = set(uids.tolist())
        self.episodes = {k: v for k, v in self.episodes.items()
                         if k[0] in alive and k[1] in alive and t - v.seen <= RETAIN_S}

    def order(self, t: float, uid_a: int, uid_b: int, crossed_only: bool = False) -> float:
        """The sign of b_a - b_b at t from the pair's V (+-1): reversed when its apex is
        followed by MIN_AFTER samples, kept when the apex is after the last sample (unless
        crossed_only), else 0 (unknown; also without an episode)."""
        key = (uid_a, uid_b) if uid_a < uid_b else (uid_b, uid_a)
        ep = self.episodes.get(key)
        if ep is None:
            return 0.0
        tc, _ = crossing_time(ep.t, ep.a)
        after = sum(1 for ts in ep.t if ts > tc)
        if np.isnan(tc) or (after and after < MIN_AFTER) or tc < ep.t[0] or (crossed_only and not after):
            return 0.0
        s = -ep.sign if after else ep.sign
        return s if key == (uid_a, uid_b) else -s

    def agrees(self, t: float, uids: np.ndarray, g: np.ndarray, det_brg: np.ndarray) -> bool:
        """True when the detections of the group g (det_brg (N,)) are in the order of every
        pair's V that has crossed."""
        for x, i in enumerate(g):
            for j in g[x + 1:]:
                s = self.order(t, int(uids[i]), int(uids[j]), crossed_only=True)
                if s and np.sign(wrap_pi(det_brg[i] - det_brg[j])) != s:
                    return False
        return True

    def settle(self, t: float, uids: np.ndarray, released: np.ndarray, kept: list[np.ndarray],
               groups: list[np.ndarray], det_brg: np.ndarray, det_var: np.ndarray
               ) -> tuple[np.ndarray, list[np.ndarray]]:
        """The released mask (N,) and the groups kept frozen after the pairs' V: a group
        released by common.sonar.bearing.pairs whose detections are against a pair's V
        stays frozen; a kept pair whose detections are resolved (SIGN_SIGMAS sigma of
        var R_a + R_b) and in the order of its V is released."""
        out, still = released.copy(), []
        for g in groups:
            ok = self.agrees(t, uids, g, det_brg)
            if out[g].all():
                if not ok:
                    out[g] = False
                    still.append(g)
                continue
            i, j = g[0], g[-1]
            dz = abs(float(wrap_pi(det_brg[i] - det_brg[j])))
            if (g.size == 2 and ok and self.order(t, int(uids[i]), int(uids[j]))
                    and dz >= SIGN_SIGMAS * np.sqrt(det_var[i] + det_var[j])):
                out[g] = True
            else:
                still.append(g)
        return out, still
