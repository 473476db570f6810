"""The exit of a pair of frozen bearing tracks by the V of its separations (step 4 of
common.sonar.bearing.tracker; common.core.crossing_groups).

A frozen pair (a group of two tracks of common.sonar.bearing.pairs) coasts on 004's
memory: its difference on the bearing rates it entered with. When those rates are off
(a young track, a third contact in the crossing), the extrapolated pair stays between the
two contacts long after they separated, and the order its prediction gives is not
sure, or wrong. Whether the contacts have crossed follows from their detections:
`common.core.crossing_groups.crossing_time` fits the V of the separations |X_a - X_b| of
the scans where the pair was a group of two with a detection each (and its predicted
separation when it was first frozen); once the V's apex is followed by MIN_AFTER
separations the pair has crossed, and its order is the reverse of its order then. Two
uses (`PairOrders.settle`):
- detections resolved (at least SIGN_SIGMAS sigma apart, var R_a + R_b) that GNN gave the
  tracks in that order release the pair for the scan (alpha = 1, as
  common.sonar.bearing.pairs releases a group whose predicted order is sure);
- a group that common.sonar.bearing.pairs would release in an order against a crossed
  pair's V stays frozen (a prediction that has not crossed, on rates that are off).
Before its apex is sure the V decides nothing: taken as "not crossed yet", it released a
pair in the wrong order on sonar_x_turn (the own-ship turn bends both rates) and withheld
right releases on sonar_x_amp. Deviations, not in 004 (common.core.crossing_groups).
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

    def order(self, uid_a: int, uid_b: int) -> float:
        """The sign of b_a - b_b once the pair has crossed: the reverse of its entry order
        when the apex of its V is followed by MIN_AFTER separations; 0 otherwise (not
        crossed, not yet sure, or no episode)."""
        key = (uid_a, uid_b) if uid_a < uid_b else (uid_b, uid_a)
        ep = self.episodes.get(key)
        if ep is None:
            return 0.0
        tc, _ = crossing_time(ep.t, ep.a)
        if np.isnan(tc) or tc < ep.t[0] or sum(1 for ts in ep.t if ts > tc) < MIN_AFTER:
            return 0.0
        return -ep.sign if key == (uid_a, uid_b) else ep.sign

    def agrees(self, uids: np.ndarray, g: np.ndarray, det_brg: np.ndarray) -> bool:
        """True when the detections of the group g (det_brg (N,)) are in the order of every
        pair's V that has crossed."""
        for x, i in enumerate(g):
            for j in g[x + 1:]:
                s = self.order(int(uids[i]), int(uids[j]))
                if s and np.sign(wrap_pi(det_brg[i] - det_brg[j])) != s:
                    return False
        return True

    def settle(self, uids: np.ndarray, released: np.ndarray, groups: list[np.ndarray],
               det_brg: np.ndarray, det_var: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        """The released mask (N,) and the groups kept frozen after the pairs' V, from the
        mask of common.sonar.bearing.pairs.release, the frozen groups and the bearing and
        variance of each track's GNN detection (N,), NaN for none: a group released whose
        detections are against a crossed pair's V stays frozen; a pair not released whose
        detections are resolved (SIGN_SIGMAS sigma of var R_a + R_b) and in the order of
        its crossed V is released."""
        out, still = released.copy(), []
        for g in groups:
            ok = self.agrees(uids, g, det_brg)
            if out[g].all():
                if not ok:
                    out[g] = False
                    still.append(g)
                continue
            i, j = g[0], g[-1]
            dz = abs(float(wrap_pi(det_brg[i] - det_brg[j])))
            if (g.size == 2 and ok and self.order(int(uids[i]), int(uids[j]))
                    and dz >= SIGN_SIGMAS * np.sqrt(det_var[i] + det_var[j])):
                out[g] = True
            else:
                still.append(g)
        return out, still
