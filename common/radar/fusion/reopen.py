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
base then fails [48] against it and is never admitted.

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
rebuild from it loses the track), and (2) the track's predicted position lies
outside every band of weight >= 1e-3 at gate_prob (chi-square, 3 dof, on the position
with both covariances). When the bands leave the altitude open (condition 1 fails),
the track keeps its mean but its altitude and vertical-velocity variances are floored at
the mixture's (`floor_vertical`): the information of a lost member may have been a
foreign aircraft's, and the EKF's altitude information from bistatic ranges grows with
the height it is linearised at, so a track started high on a wrong combination credits
itself several times the information its own members give. Floored, a track can admit
its own elementary track of the lost base again. Otherwise nothing changes: a member
lost to a manoeuvre, a crossing or a track's end, with the others agreeing, costs no
information. The rebuilt track is not updated in that cycle (as a new track is not):
its members' estimates already hold the scan.

The watch (`FusionParams.reopen_watch`): the rebuild's test runs every cycle on the
other confirmed tracks too, those that lost no member, without the floor
(`floor=False`: an open evidence says nothing against a track that lost nothing). A
track can be fed by its own elementary tracks only and still sit at a wrong altitude
with a small sigma_z, once the members it lost while its start mixed two aircraft's
elementary tracks are gone and nothing triggers the test. The "resolved" condition
keeps the false rebuilds few: most tracks' members leave the altitude open at any one
scan.

The cases that led to each rule, the figures with and without it, and the commands
that give them: docs/decisions/003-altitude-rebuild.md.
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
