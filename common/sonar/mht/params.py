"""[sonar.tracker] with its association mode and [sonar.tracker.mht]: the parameters of
seed 000's multiple-hypothesis mode."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

from common.core.params import Params, Range, Rule, count, non_negative, order, positive, unbounded
from common.sonar.bearing.params import LEVEL, TrackerParams


@dataclass(frozen=True)
class SonarTrackerParams(TrackerParams):
    """[sonar.tracker] seed 000 bearing tracker, both association modes.

    mode_association: "gnn" the single-hypothesis mode (000 first embodiment, global
        nearest neighbour), "mht" the multiple-hypothesis mode ([sonar.tracker.mht]).
        "gnn" by default (benchmarks/sonar_default.py over 17 sonar scenes,
        docs/decisions/023-sonar-defaults.md): "mht" ranks below it on the first
        criterion, runs with an unflagged swap 34 against 6 and break runs 29 against 12
        on sonar_x_three (three contacts crossing together; 0 swaps for both on the 16
        other scenes), though with fewer false tracks (sonar_x_clutter 0.12 against 0.60
        per 100 cycles) and a lower bearing RMSE on 13 of the 17 scenes.
    """

    mode_association: Literal["gnn", "mht"] = "gnn"


@dataclass(frozen=True)
class MhtParams(Params):
    """[sonar.tracker.mht] seed 000 multiple-hypothesis mode (mode_association = "mht").

    p_d_max, d_thr: P_D = P_D_max / 2 erfc((D_thr - a_pre) / (sigma_a_pre sqrt 2)), D_thr
        in dB on the level scale of the amplitude state.
    rho_f: rho_F of the weight formula, the false-alarm density (1 / (rad dB)).
    gate: lambda of the gate y' S^-1 y <= lambda^2.
    c_krit: new hypotheses lighter than this are pruned.
    d_merge_hyp: hypotheses of a track closer than this (d of d^2) are merged.
    d_split: a track whose two heaviest hypotheses are farther than this is split.
    d_merge: a tentative and a confirmed track closer than this are merged.
    A, B: SPRT limits of LR (ZA - 1 below A, ZA + 1 above B).
    za_krit: ZA above which a track is confirmed.
    za_max: cap of ZA.
    n_delete: a tentative track is deleted after this many cycles in a row as tentative
        without LR > B (a demoted confirmed track too, counted from its demotion).
    sigma_max_deg: a track whose bearing sigma exceeds this is deleted (deg).
    merge_sigma_max_deg: bearing sigmas below which covariances are "not excessive" for
        the track merge (deg).
    res_deg: resolution of P_u and sigma of the fictitious "separation = 0" (deg).
    d_auf: d_Auf of the re-link at the end of a resolution conflict.
    relink_deg: a new confirmed track within this bearing of a coalesced conflicting
        pair is re-linked to one of them (deg).
    n_retro: retrodiction depth (cycles).
    max_hyp_track, max_hyp_cycle: caps on hypotheses per track and per cycle.
    """

    p_d_max: float = 0.9
    d_thr: float = 3.0
    rho_f: float = 0.02
    gate: float = 3.5
    c_krit: float = 1e-3
    d_merge_hyp: float = 2.0
    d_split: float = 3.5
    d_merge: float = 3.0
    A: float = 0.5
    B: float = 2.0
    za_krit: int = 3
    za_max: int = 6
    n_delete: int = 3
    sigma_max_deg: float = 10.0
    merge_sigma_max_deg: float = 3.0
    res_deg: float = 1.5
    d_auf: float = 3.0
    relink_deg: float = 10.0
    n_retro: int = 10
    max_hyp_track: int = 16
    max_hyp_cycle: int = 20000

    RANGES: ClassVar[dict[str, Range]] = {
        "p_d_max": Range("probability", 0.0, 1.0, "(]"), "d_thr": unbounded("dB", LEVEL),
        "rho_f": positive("1/(rad dB)"), "gate": positive("sigma"),
        "c_krit": Range("weight", 0.0, 1.0, "[)"), "d_merge_hyp": non_negative("sigma"),
        "d_split": positive("sigma"), "d_merge": non_negative("sigma"),
        "A": positive("likelihood ratio"), "B": positive("likelihood ratio"),
        "za_krit": count(1), "za_max": count(1), "n_delete": count(1),
        "sigma_max_deg": positive("deg"), "merge_sigma_max_deg": positive("deg"),
        "res_deg": positive("deg"), "d_auf": positive("sigma"), "relink_deg": positive("deg"),
        "n_retro": count(0),
        "max_hyp_track": count(1), "max_hyp_cycle": count(1),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (
        order("A", "B"), order("za_krit", "za_max", strict=False),
        order("d_merge_hyp", "d_split", strict=False),
    )
