"""[sonar.tracker] parameters of seed 000's bearing tracker (both association modes share
them) and the motion model they set: 000 F and Q of the straight-line-segment model,
broadband x = [brg, brg_rate, level, level_rate] or narrowband with [freq, freq_rate].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np

from common.core.motion import bearing_F, bearing_freq_F, bearing_freq_Q, bearing_Q
from common.core.params import (
    INF,
    PROB_OPEN,
    Params,
    Range,
    Rule,
    ascending_pair,
    count,
    non_negative,
    positive,
    two_values,
    unbounded,
)

# a level in dB on the detector's SNR scale: every real is a level (negative: below the noise)
LEVEL = "any level in dB (negative: below the noise)"


@dataclass(frozen=True)
class TrackerParams(Params):
    """[sonar.tracker] parameters (000 first embodiment).

    mode: "broadband" z = [brg, amp], "narrowband" z = [brg, amp, freq], or "auto"
        (the service picks narrowband when the first detection list carries freq[]).
    q_theta, q_a, q_f: process noise powers of Q (rad^2/s^3, dB^2/s^3, Hz^2/s^3).
    q_theta_quiet: bearing noise power of the quiet model of the bearing-rate IMM, whose
        manoeuvre model has q_theta (common.sonar.bearing.imm); the IMM runs when
        0 < q_theta_quiet < q_theta, a single model with q_theta otherwise.
    imm_sojourn_s: mean sojourn times (s) of the quiet and the manoeuvre model.
    sigma_amp_db, sigma_freq_hz: measurement sigmas of level and frequency (000 R).
    p_d, p_fa: detection / false alarm probabilities per beam and cycle (000 G, dL);
        p_d is P_D_max of the amplitude law when the laws run.
    d_thr: detection threshold D_thr (dB level) of the amplitude laws.
    clutter_level_db: mean level of false detections above d_thr (dB): P_D of a track from
        its predicted amplitude (000 erfc law) and P_FA of a detection from its level
        (bearing.model.false_alarm_probability); 0 (the default): the estimated level
        (clutter_estimate), or both constant (p_d, p_fa) when that is off.
        Off by default (benchmarks/sonar_default.py over 17 sonar scenes, 40 seeds on
        the four sonar_x_* scenes, 10 on the others; docs/decisions/023-sonar-defaults.md):
        on, at the scene's clutter level, it ranks below off on the first criterion,
        runs with an unflagged swap 10 against 6 (sonar_x_three; 0 for both on the 16
        other scenes), though with fewer break runs (9 against 14: sonar_x_amp 0 / 2,
        sonar_x_three 9 / 12) and fewer false tracks (sonar_x_clutter 0.36 against 0.60
        per 100 cycles). With the memory-mode groups of docs/decisions/027-sonar-crossing-groups.md
        (40 seeds on the sonar_x_* scenes, 20 on the 13 others) the reason is gone: on
        ranks first, 0 unflagged swap runs for both, break runs 0 against 3 (sonar_x_amp
        0 / 2, sonar_x_three 0 / 1), false tracks 0.08 against 0.11 per 100 cycles; the
        laws with an estimated level are clutter_estimate (029).
        Earlier, on sonar_cross_4dpm_uneq (50 runs through the processes) the law at
        2 dB gave 4 swap runs with crossing management (0 without it); the hold
        scenes (sonar_hold*) set it.
    clutter_estimate: run the amplitude laws with the clutter level estimated online
        (common.sonar.bearing.clutter_level: the exponentially weighted mean excess over
        d_thr of the detections no confirmed track took, the maximum-likelihood mean of 000's
        exponential false-level density) when clutter_level_db is 0; a clutter_level_db > 0
        is a known level and takes precedence (no estimate).
        Off by default (docs/decisions/029-sonar-clutter-estimate.md): it ranks first in
        benchmarks/sonar_default.py (17 sonar scenes in process, 40 seeds on the sonar_x_*
        scenes, 20 on the others: 0 unflagged swap runs and 0 break runs, as the laws at
        each scene's true level, against 3 break runs with both laws off; false tracks 0.07
        per 100 cycles against 0.08 and 0.11), but through the processes
        (tests/integration/test_crossing_integration.py, sonar_cross_4dpm_uneq, 50 runs with
        crossing management) it gives 3 swap runs against 0 off, above that test's goal
        (< 2.5); the other six cases there pass with it on.
    clutter_prior_db: the estimate's seed (dB), worth 10 false detections.
    clutter_window: cycles of the estimate's forgetting, lam = 1 - 1 / clutter_window.
    clutter_bounds_db: [low, high] bounds of the estimate (dB).
    beam_spacing_deg: Delta Theta between adjacent beams (000 G, dL).
    alpha, beta: P(confirm a false track), P(delete a true track) (000 T1, T2).
    delete_drop: a confirmed track is deleted when L < max(L) - delete_drop.
    endfire_deg: floor of |sin(brg - heading)| in the linear-array sigma law.
    init_*_rate_sigma: P0 of the rates (brg rad/s, amp dB/s, freq Hz/s).
    crossing: run seed 004 crossing management ([sonar.crossing]) on confirmed tracks.
    block_estimator: with crossing, 004's block estimator (eq. 6-10) fits the line of each
        track flagged ambiguous to the crossing's detections, and the track resumes from
        it when its flag clears (common.sonar.bearing.block; single-hypothesis mode).
        Off by default (benchmarks/sonar_default.py, docs/decisions/023-sonar-defaults.md):
        on, runs with an unflagged swap 9 against 6 over the 17 scenes (sonar_x_amp 2
        against 0, sonar_hold_cross_slow 1 against 0, sonar_x_three 6 and 6), break runs
        15 against 14, a larger bearing RMSE on every one of the 17 scenes (sonar_x_amp 0.50
        against 0.45 deg, sonar_hold_cross_turn 0.44 against 0.41, sonar_cross_2dpm_uneq
        0.57 against 0.53), and a slower cycle at 200 contacts.
    block_window_s: seconds of the track's register before the flag rose that start its fit.
    band_hz: narrowband frequency band; with 2 pi it is the volume c of seed 004.
    ml_brg_tol_deg, ml_rate_tol_deg_s: bounds of claims 12-13 (bearing, bearing rate).
    history_keep_deleted: deleted confirmed tracks whose history stays queryable.
    history_as_of_cycles: cycles whose register stays queryable "as of" their time
        (a history query with ``as_of``, docs/protocol.md): the tma service's query names
        the btracks cycle it works on, and a tracker already at a later cycle answers with
        the register as that cycle published it (the multiple-hypothesis mode keeps a copy
        of its retrodiction window per cycle: this x n_retro x tracks rows of 7 floats).
    d_merge: a tentative track within this squared distance of a confirmed track (whole
        state, both covariances) is dropped (000 d_merge; 9.21: the 94 % chi-square
        quantile of 4 degrees of freedom).
    """

    mode: Literal["auto", "broadband", "narrowband"] = "auto"
    q_theta: float = 1e-8
    q_theta_quiet: float = 1e-10
    imm_sojourn_s: list[float] = field(default_factory=lambda: [600.0, 60.0])
    q_a: float = 1e-4
    q_f: float = 1e-6
    sigma_amp_db: float = 3.0
    sigma_freq_hz: float = 0.05
    p_d: float = 0.9
    p_fa: float = 1e-3
    d_thr: float = 3.0
    clutter_level_db: float = 0.0
    clutter_estimate: bool = False
    clutter_prior_db: float = 2.0
    clutter_window: float = 50.0
    clutter_bounds_db: list[float] = field(default_factory=lambda: [0.5, 20.0])
    beam_spacing_deg: float = 2.0
    alpha: float = 1e-4
    beta: float = 1e-2
    delete_drop: float = 12.0
    endfire_deg: float = 10.0
    init_brg_rate_sigma: float = 0.002
    init_amp_rate_sigma: float = 0.05
    init_freq_rate_sigma: float = 0.002
    crossing: bool = True
    block_estimator: bool = False
    block_window_s: float = 120.0
    band_hz: list[float] = field(default_factory=lambda: [10.0, 1000.0])
    ml_brg_tol_deg: float = 2.0
    ml_rate_tol_deg_s: float = 0.1
    history_keep_deleted: int = 64
    history_as_of_cycles: int = 16
    d_merge: float = 9.21

    RANGES: ClassVar[dict[str, Range]] = {
        "q_theta": positive("rad^2/s^3"), "q_theta_quiet": non_negative("rad^2/s^3"),
        "imm_sojourn_s": positive("s"),
        "q_a": non_negative("dB^2/s^3"), "q_f": non_negative("Hz^2/s^3"),
        "sigma_amp_db": positive("dB"), "sigma_freq_hz": positive("Hz"),
        "p_d": PROB_OPEN, "p_fa": PROB_OPEN, "beam_spacing_deg": positive("deg"),
        "d_thr": unbounded("dB", LEVEL), "clutter_level_db": non_negative("dB"),
        "alpha": PROB_OPEN, "beta": PROB_OPEN, "delete_drop": positive("log-likelihood"),
        "endfire_deg": Range("deg", 0.0, 90.0, "(]"),
        "init_brg_rate_sigma": positive("rad/s"), "init_amp_rate_sigma": positive("dB/s"),
        "init_freq_rate_sigma": positive("Hz/s"), "band_hz": non_negative("Hz"),
        "ml_brg_tol_deg": positive("deg"), "ml_rate_tol_deg_s": positive("deg/s"),
        "history_keep_deleted": count(0), "history_as_of_cycles": count(0), "d_merge": non_negative("d^2"),
        "block_window_s": non_negative("s"), "clutter_prior_db": positive("dB"),
        "clutter_window": Range("cycles", 1.0, INF, "()"), "clutter_bounds_db": positive("dB"),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (
        two_values("imm_sojourn_s"), ascending_pair("band_hz"), ascending_pair("clutter_bounds_db"),
        # T1 = ln(beta / (1 - alpha)) < T2 = ln((1 - beta) / alpha)  <=>  alpha + beta < 1
        Rule(("alpha", "beta"), lambda a, b: a + b < 1.0, "alpha + beta < 1 (delete threshold T1 below "
             "confirm threshold T2)"),
    )


def transition(narrowband: bool, T: np.ndarray | float) -> np.ndarray:
    """000 F over T seconds (common.core.motion), broadband or narrowband state."""
    return bearing_freq_F(T) if narrowband else bearing_F(T)


def process_noise(p: TrackerParams, narrowband: bool, T: np.ndarray | float,
                  q_theta: np.ndarray | float | None = None) -> np.ndarray:
    """000 Q over T seconds with the bearing noise power q_theta (default p.q_theta)."""
    q = p.q_theta if q_theta is None else q_theta
    return bearing_freq_Q(T, q, p.q_a, p.q_f) if narrowband else bearing_Q(T, q, p.q_a)
