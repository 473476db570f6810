"""A track rebuilt from its sound members when they contradict it, or its vertical
variances floored at theirs when they leave the altitude open (complement of 001 module
63, stated).

001's module 63 dissociates an elementary track that fails [48] and goes on with the
global track's estimate. With one receiver the altitude is the weakest coordinate: a
track initialised on a wrong combination (the elementary tracks of two aircraft a
kilometre apart in plan at different altitudes, one base's tracks exchanged) settles at
a compromise altitude with a small variance. When the foreign elementary track is
finally dropped, the remaining ones pull the altitude back slowly while the variance,
built on the wrong combination, stays small; the track's own elementary track of that
base then fails [48] against it and is never admitted (measured, dense1000 seed 7:
aircraft 931 tracked at 2.0-3.9 km, truth 5.0 km, sigma_z 200-360 m, for 60 s, and its
neighbour 336 at 6.3 km, truth 3.9 km; per-target mean NEES 21 000 and 49 000).

Here a confirmed track that lost a member this cycle (dissociated by module 63, or by
module 64's v_b test the cycle before) and holds at least MIN_SOUND sound members
(confirmed elementary tracks updated this scan: three bases can give an altitude, two a
curve) is tested against them: their altitude bands are built as module 62 builds a new
track's (common.radar.fusion.initiation.altitude_bands: Gauss-Newton per band, velocity [42]
by least squares), weighted by their evidence (mature estimates, unlike module 62's two
young ones). The track takes that mixture (its number, status and memberships stay) if
(1) the mixture resolves the altitude: its sigma_z below band_linear times the height
above the receiver, the linear regime of common.radar.fusion.mixture (three bases of
poor vertical geometry, or two aircraft's elementary tracks, give a flat evidence: a
rebuild from it loses the track; measured, dense1000 seed 2: a track rebuilt with
sigma_z 1.8 km lost its members and left a ghost at 20 km holding a neighbour's
elementary tracks, mean NEES 3.67 -> 5.40), and (2) the track's predicted position lies
outside every band of weight >= 1e-3 at gate_prob (chi-square, 3 dof, on the position
with both covariances). When the bands leave the altitude open (condition 1 fails),
the track keeps its mean but its altitude and vertical-velocity variances are floored at
the mixture's (`floor_vertical`): the information of a lost member may have been a
foreign aircraft's, and the EKF's altitude information from bistatic ranges grows with
the height it is linearised at, so a track started high on a wrong combination credits
itself several times the information its own members give (measured, dense1000 seed 7:
aircraft 915 tracked at 3.2-4.0 km, truth 5.8 km, sigma_z 170-260 m, after dropping the
foreign elementary track of base b1, its bases b0, b2 and b3 giving a flat evidence;
seed 2: aircraft 671 at 7.2 km, truth 1.3 km, descending through the truth and below
ground on a vertical velocity of -70 m/s that the dropped members had given it; per-target
mean NEES 2186 and 617). Floored, a track can admit its own elementary track of the lost
base again: in seed 7, 840's track (3.5 km, truth 2.4 km) was floored at t = 14 s and
took its own b1 track at t = 17 s (2.5 km from then on); 915's rose to 4.6-5.0 km and
took its own at t = 70 s. Seeds 1-14: 150-215 floors per run, mean NEES 2.9-3.7 (seed 7
5.19 -> 3.15, seed 2 3.65 -> 3.04), no switch count higher (docs/radar_at_scale.md,
session 14). Otherwise nothing changes: a member lost to a manoeuvre, a
crossing or a track's end, with the others agreeing, costs no information. The rebuilt
track is not updated in that cycle (as a new track is not): its members' estimates
already hold the scan. Measured (benchmarks/dense_scale.py, dense1000 seeds 1-10): 0-9
rebuilds per run; seed 7's mean NEES 81.9 -> 6.7 (per-step pairing; both aircraft above), the other
seeds' NEES, missed and false tracks unchanged within 0.1; switches per 100 targets
+0.1 on seed 1, +0.2 on seed 7, -0.1 on seeds 8 and 9 (docs/radar_at_scale.md).

The watch (`FusionParams.reopen_watch`, since session 16): the rebuild's test runs every
cycle on the other confirmed tracks too, those that lost no member, without the floor
(`floor=False`: an open evidence says nothing against a track that lost nothing). A
track can be fed by its own elementary tracks only and still sit at a wrong altitude
with a small sigma_z, once the members it lost while its start mixed two aircraft's
elementary tracks are gone and nothing triggers the test (measured, dense1000 seed 34:
aircraft 931 and 336, 1.2 km apart in plan on one course at 5.0 and 3.9 km; 931's track
#580, tentative from t = 3 to 25 s while both aircraft's elementary tracks came and
went, held its four own from t = 30 s, 1.7 km low with sigma_z 196 m, 336's #897 1.8 km
high; the scoring paired each aircraft with the other's track, 336's per-target
NEES 12636 and the run's mean NEES 15.62). With the watch, seed 34's mean NEES is
3.05, with 16 rebuilds in the run (23 on seed 9). The "resolved" condition keeps the
false rebuilds few: most tracks' members leave the altitude open at any one scan. Cost:
global fusion 115 -> 155-162 ms per scan in process at 1000 targets
(benchmarks/dense_scale.py; seeds 1-40 in docs/radar_at_scale.md, session 16).
"""

from __future__ import annotations

import numpy as np

from common.core import imm
from common.core.gating import chi2_gate, quadratic_form
from common.radar.fusion.assoc import ETrackSet
from common.radar.fusion.initiation import InitParams, altitude_bands
from common.radar.fusion.track_filter import MixtureFilter
from common.radar.geometry.bistatic import POS

MIN_SOUND = 3


def sound_members(row: np.ndarray, E: ETrackSet) -> np.ndarray:
    """Rows of E (n, B) of the memberships whose elementary track is confirmed and was
    updated this scan (an estimate to rebuild from), -1 elsewhere."""
    ok = np.append(E.updated & E.confirmed, False)[row]
    return np.where(ok, row, -1)


def contradicted(x: np.ndarray, P: np.ndarray, xb: np.ndarray, Pb: np.ndarray, wb: np.ndarray,
                 gate: float, w_min: float = 1e-3) -> np.ndarray:
    """Tracks (n,) whose predicted position (x (n, 6), P (n, 6, 6)) lies outside every
    band of weight >= w_min of their rebuilt mixture (xb (n, A, 6), Pb, wb (n, A)):
    d^2 = (p - p_a)' (P_pos + P_a,pos)^-1 (p - p_a) > gate for each."""
    e = x[:, None, POS] - xb[..., POS]
    S = P[:, None][..., POS, :][..., POS] + Pb[..., POS, :][..., POS]
    d2 = quadratic_form(e, S)
    return np.all((d2 > gate) | (wb < w_min), axis=1)


def floor_vertical(P: np.ndarray, Pm: np.ndarray, slots: np.ndarray, Pmix: np.ndarray) -> None:
    """Altitude and vertical-velocity variances of `slots`, in the moments P and in every
    component of Pm, raised to at least those of the sound members' mixture Pmix (n, 6, 6)
    (module doc: the track holds no more vertical information than its evidence)."""
    for i in (4, 5):
        v = Pmix[:, i, i]
        Pm[slots, :, i, i] += np.maximum(0.0, v[:, None] - Pm[slots, :, i, i])
        P[slots, i, i] += np.maximum(0.0, v - P[slots, i, i])


def reopen(candidates: np.ndarray, filt: MixtureFilter, predicted: tuple[np.ndarray, ...],
           row: np.ndarray, E: ETrackSet, tx: np.ndarray, rx: np.ndarray, p: InitParams,
           gate_prob: float, floor: np.ndarray | bool = True) -> np.ndarray:
    """In place in the predicted (x, P, xm, Pm, c) (MixtureFilter.predict) of each of
    `candidates` (confirmed tracks) with at least MIN_SOUND sound members: rebuild the
    mixture when their evidence-weighted altitude bands resolve the altitude and
    contradict its prediction, floor its vertical variances when the bands leave the
    altitude open and `floor` (per candidate, or all: those that lost a member this
    cycle; module doc) is set; returns the rebuilt slots."""
    x, P, xm, Pm, c = predicted
    rows = sound_members(row[candidates], E)
    enough = (rows >= 0).sum(axis=1) >= MIN_SOUND
    s, rows = candidates[enough], rows[enough]
    floor = np.broadcast_to(floor, candidates.shape)[enough]
    if s.size == 0:
        return s
    xb, Pb, wb = altitude_bands(x[s][:, POS], E.y, E.R, E.base, rows, tx, rx, p, evidence=True)
    nx, nP, nc = filt.initial(xb, Pb, wb)
    cx, cP = imm.combine(nc, nx, nP)
    ok = np.sqrt(cP[:, 4, 4]) < filt.p.band_linear * (cx[:, 4] - filt.rx[0, 2])  # resolved
    floor_vertical(P, Pm, s[~ok & floor], cP[~ok & floor])
    k = ok & contradicted(x[s], P[s], xb, Pb, wb, chi2_gate(gate_prob, 3))
    s = s[k]
    xm[s], Pm[s], c[s], x[s], P[s] = nx[k], nP[k], nc[k], cx[k], cP[k]
    return s
