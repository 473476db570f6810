"""Parameters of table `[radar.fusion]`: the global fusion of common.radar.fusion.cycle
(001 modules 61-65), its initialisation (module 62, common.radar.fusion.initiation) and
its arrival rule (common.radar.fusion.arrival)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

from common.core.crossing import CrossingParams
from common.core.params import PROB_OPEN, Range, count, non_negative, positive
from common.radar.fusion.initiation import InitParams


@dataclass(frozen=True)
class FusionParams(InitParams):
    """Parameters of `[radar.fusion]` (module 62 thresholds inherited from InitParams).

    gate_prob: chi-square(3) probability of the gate gamma_max on [48], and probability
        of the consistency test of module 64 (chi-square, 2 x contributing bases).
    q, q_manoeuvre, q_z: process noise powers (m^2/s^3) of [51]: sigma_vxy^2 of the
        quiet and of the manoeuvre model of the IMM (module doc), sigma_vz^2 of both;
        q is also the PCRLB's model.
    sojourn_quiet, sojourn_manoeuvre: mean time (s) spent in each model (IMM Markov
        chain, common.core.imm.transition).
    band_prune, band_prune_init, band_merge, band_linear: an altitude band of less mass
        is dropped (band_prune_init at initialisation, where the two elementary
        estimates can be biased: the weights then rest on one scan); two
        bands whose altitudes differ by less than band_merge sigma are merged once
        sigma_z < band_linear * height above the receiver (common.radar.fusion.mixture).
    meas_inflation: factor on R of [50] (1 = as the elementary tracks give it).
    confirm_cycles, confirm_bases: a track is confirmed after this many cycles with
        at least this many contributing updated elementary tracks, located together
        (module 64's test passed: a track of two targets' elementary tracks fails it);
        confirm_bases is capped at all the deployment's bases but one, and at least 2
        (three of four; two of two or three): two bases give a curve, on which the
        elementary tracks of two neighbouring aircraft locate as well as one's (stated;
        figures: docs/decisions/013-dense-scenes.md). A tentative track that loses a
        member (dissociated by [48] or module 64's v_b test) counts again from zero: its
        cycles so far were located with an elementary track of another aircraft (stated;
        dense1000: tracks confirmed 5 km off in altitude on a wrong combination).
    max_coast: deletion after this many cycles without contributors (module 61).
    coast_cycles: a confirmed track none of whose contributors was updated for this
        many cycles is reported coasting (common.radar.fusion.status).
    max_wait: seconds of wall time without a message after which global fusion declares
        a base stale (common.radar.fusion.arrival, the arrival rule).
    max_lead: seconds of message time after the latest cycle beyond which global fusion
        rejects a message and declares its base stale (a clock jumped forward; above
        the lag between bases of a fast replay, common.radar.fusion.cycle and
        docs/decisions/010-global-fusion-wall-time.md).
    init_confirmed_only: module 62 uses confirmed, updated elementary tracks only.
    eq_gate_prob: chi-square(3) probability of the consistency test of an equivalent
        measurement against the elementary track's prediction (common.radar.fusion.decorrelation).
    filter: "mixture" (default): the altitude bands x IMM mixture (module doc of
        common.radar.fusion.cycle); "seed": 001's single EKF, for comparison (same
        doc, "Seed path"): module 62's blocks [36]-[41] without altitude prior,
        [44]-[46] as written, one component with the fixed Q of [51] (q, q_z); the band
        and IMM parameters are then unused.
    reopen_altitude: rebuild a contradicted track, floor an open one (fusion.reopen; "mixture").
    reopen_watch: the rebuild's test also on every other confirmed track, every cycle
        (fusion.reopen: tracks fed by their own elementary tracks at a wrong altitude).
    segment_accel: standard deviation (m/s^2, per plan axis) of the constant acceleration
        a coasting track's aircraft may have held since its last update, in the test of
        the track segment association (common.radar.fusion.segments); 0 turns it off.
    """

    gate_prob: float = 0.999
    q: float = 1.0
    q_manoeuvre: float = 50.0
    q_z: float = 1.0
    sojourn_quiet: float = 60.0
    sojourn_manoeuvre: float = 10.0
    band_prune: float = 1e-3
    band_prune_init: float = 1e-6
    band_merge: float = 0.5
    band_linear: float = 0.2
    meas_inflation: float = 1.0
    confirm_cycles: int = 3
    confirm_bases: int = 3
    max_coast: int = 10
    coast_cycles: int = 2
    max_wait: float = 3.0
    max_lead: float = 600.0
    init_confirmed_only: bool = True
    eq_gate_prob: float = 0.99999
    filter: Literal["mixture", "seed"] = "mixture"
    reopen_altitude: bool = True
    reopen_watch: bool = True
    segment_accel: float = 10.0

    RANGES: ClassVar[dict[str, Range]] = {
        **InitParams.RANGES,
        "gate_prob": PROB_OPEN,
        "q": positive("m^2/s^3"), "q_manoeuvre": positive("m^2/s^3"), "q_z": positive("m^2/s^3"),
        "sojourn_quiet": positive("s"), "sojourn_manoeuvre": positive("s"),
        "band_prune": Range("weight", 0.0, 1.0, "[)"),
        "band_prune_init": Range("weight", 0.0, 1.0, "[)"),
        "band_merge": non_negative("sigma"), "band_linear": non_negative(),
        "meas_inflation": positive(), "confirm_cycles": count(1), "confirm_bases": count(2),
        "max_coast": count(0), "coast_cycles": count(1), "max_wait": positive("s"),
        "max_lead": positive("s"),
        "eq_gate_prob": PROB_OPEN, "segment_accel": non_negative("m/s^2"),
    }


@dataclass(frozen=True)
class FusionCrossingParams(CrossingParams):
    """[radar.fusion_crossing] seed 004 crossing management of the global tracks.

    The fields of CrossingParams; without the table, global fusion runs the sup-norm test.

    Radar default: max_duration is 60 s (the sonar's is 600 s: a bearing crossing lasts
    minutes, a global track is extrapolated in 1 s cycles).
    """

    max_duration: float = 60.0
