"""Unit and admissible interval of every numeric parameter of the deployment file.

``RANGES[section][field]`` is a ``Range``; a section name may be a pattern
(``sonar.tma.bounds.*``). ``common.deploy.config.section`` rejects an out-of-range value
with the key's name (``radar.tracker.gate_prob = 1.5`` -> ``ConfigError``), and
docs/configuration.md shows unit and interval beside each default. A list parameter has
the range of each of its elements. tests/deploy/test_ranges.py fails when a numeric field
of a parameter class has no range here, or a default lies outside its own.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass

INF = math.inf


@dataclass(frozen=True)
class Range:
    """An interval lo..hi of a parameter in ``unit``; ``closed`` says which ends belong
    to it ("[]", "[)", "(]" or "()")."""

    unit: str
    lo: float
    hi: float
    closed: str = "[]"

    def contains(self, v: float) -> bool:
        """Whether v lies in the interval."""
        lo_ok = v >= self.lo if self.closed[0] == "[" else v > self.lo
        hi_ok = v <= self.hi if self.closed[1] == "]" else v < self.hi
        return lo_ok and hi_ok

    def __str__(self) -> str:
        def num(x: float) -> str:
            return "inf" if x == INF else f"{x:g}"
        return f"{self.closed[0]}{num(self.lo)}, {num(self.hi)}{self.closed[1]}"


def positive(unit: str = "") -> Range:
    """(0, inf)."""
    return Range(unit, 0.0, INF, "()")


def non_negative(unit: str = "") -> Range:
    """[0, inf)."""
    return Range(unit, 0.0, INF, "[)")


def count(lo: int = 1) -> Range:
    """Integers lo, lo + 1, ..."""
    return Range("count", lo, INF, "[)")


PROB_OPEN = Range("probability", 0.0, 1.0, "()")
ANGLE = Range("rad", 0.0, 2.0 * math.pi, "[]")
SCORE = Range("score", -INF, INF, "()")

_CROSSING = {
    "S": positive("sigma"),
    "epsilon": positive(),
    "volume": positive("units of z^m"),
    "max_duration": positive("s"),
    "q_prior": PROB_OPEN,
    "q_prior_weight": non_negative("pseudo-counts"),
    "q_max": PROB_OPEN,
}
_BOUNDS = {
    "r_min": non_negative("m"), "r_max": positive("m"),
    "course_min": ANGLE, "course_max": ANGLE,
    "speed_min": non_negative("m/s"), "speed_max": positive("m/s"),
}

RANGES: dict[str, dict[str, Range]] = {
    "radar.plotter": {"n_sigma": positive("sigma")},
    "radar.tracker": {
        "sigma_gamma": positive("m/s^3 (jerk sigma)"), "sigma_omega": positive("rad/s^2"),
        "gate_prob": PROB_OPEN, "delta_vb": positive("m/s"),
        "sigma_gamma_init": positive("m/s^2"), "sigma_omega_init": positive("rad/s"),
        "score_per_channel": non_negative("score"), "ambiguity_penalty": non_negative("score"),
        "miss_penalty": non_negative("score"), "score_max": positive("score"),
        "confirm_score": SCORE, "score_delete": SCORE,
        "max_coast": count(0), "max_coast_tentative": count(0),
    },
    "radar.crossing": _CROSSING,
    "radar.fusion": {
        "az_gate_deg": Range("deg", 0.0, 180.0, "(]"), "cos_tol": non_negative(),
        "max_elevation_deg": Range("deg", 0.0, 90.0, "(]"), "k_sigma": positive("sigma"),
        "init_block_levels": count(0), "init_box_sigma": positive("sigma"),
        "z_min": Range("m", -INF, INF, "()"), "z_max": Range("m", -INF, INF, "()"),
        "v_max": positive("m/s"), "sigma_vz": positive("m/s"),
        "z_prior_mean": Range("m", -INF, INF, "()"), "z_prior_sigma": positive("m"),
        "alt_bands": count(1), "alt_band_low": positive("m"),
        "alt_band_ratio": Range("", 1.0, INF, "()"), "gate_prob": PROB_OPEN,
        "q": positive("m^2/s^3"), "q_manoeuvre": positive("m^2/s^3"), "q_z": positive("m^2/s^3"),
        "sojourn_quiet": positive("s"), "sojourn_manoeuvre": positive("s"),
        "band_prune": Range("weight", 0.0, 1.0, "[)"),
        "band_prune_init": Range("weight", 0.0, 1.0, "[)"),
        "band_merge": non_negative("sigma"), "band_linear": non_negative(),
        "meas_inflation": positive(), "confirm_cycles": count(1), "confirm_bases": count(2),
        "max_coast": count(0), "coast_cycles": count(1), "max_wait": positive("s"),
        "max_lead": positive("s"),
        "eq_gate_prob": PROB_OPEN, "segment_accel": non_negative("m/s^2"),
    },
    "radar.fusion_crossing": _CROSSING,
    "sonar.crossing": _CROSSING,
    "sonar.tracker": {
        "q_theta": positive("rad^2/s^3"), "q_theta_quiet": non_negative("rad^2/s^3"),
        "imm_sojourn_s": positive("s"),
        "q_a": non_negative("dB^2/s^3"), "q_f": non_negative("Hz^2/s^3"),
        "sigma_amp_db": positive("dB"), "sigma_freq_hz": positive("Hz"),
        "p_d": PROB_OPEN, "p_fa": PROB_OPEN, "beam_spacing_deg": positive("deg"),
        "d_thr": Range("dB", -INF, INF, "()"), "clutter_level_db": non_negative("dB"),
        "alpha": PROB_OPEN, "beta": PROB_OPEN, "delete_drop": positive("log-likelihood"),
        "endfire_deg": Range("deg", 0.0, 90.0, "(]"),
        "init_brg_rate_sigma": positive("rad/s"), "init_amp_rate_sigma": positive("dB/s"),
        "init_freq_rate_sigma": positive("Hz/s"), "band_hz": non_negative("Hz"),
        "ml_brg_tol_deg": positive("deg"), "ml_rate_tol_deg_s": positive("deg/s"),
        "history_keep_deleted": count(0), "d_merge": non_negative("d^2"),
    },
    "sonar.tracker.mht": {
        "p_d_max": Range("probability", 0.0, 1.0, "(]"), "d_thr": Range("dB", -INF, INF, "()"),
        "rho_f": positive("1/(rad dB)"), "gate": positive("sigma"),
        "c_krit": Range("weight", 0.0, 1.0, "[)"), "d_merge_hyp": non_negative("sigma"),
        "d_split": positive("sigma"), "d_merge": non_negative("sigma"),
        "A": positive("likelihood ratio"), "B": positive("likelihood ratio"),
        "za_krit": count(1), "za_max": count(1), "n_delete": count(1),
        "sigma_max_deg": positive("deg"), "merge_sigma_max_deg": positive("deg"),
        "res_deg": positive("deg"), "d_auf": positive("sigma"), "relink_deg": positive("deg"),
        "n_retro": count(0),
        "max_hyp_track": count(1), "max_hyp_cycle": count(1),
    },
    "sonar.tma": {
        "cycle_dt": positive("s"), "sample_dt": non_negative("s"),
        "own_keep": count(1), "max_pending": count(0),
    },
    "sonar.tma.ctma": {
        "q1": Range("", 1.0, INF, "()"), "q2": Range("", 1.0, INF, "()"),
        "q3": Range("", 1.0, INF, "()"), "q_minimal": Range("", 1.0, INF, "()"),
        "edge_tol": Range("fraction", 0.0, 0.5, "[)"), "edge_cycles": count(1),
        "max_corrections": count(0), "roc_window": count(2),
        "roc_threshold": positive("fraction"), "tma_tol": positive("m"), "max_iter": count(1),
        "manoeuvre_p_false": PROB_OPEN,
    },
    "sonar.tma.support": {
        "course": Range("rad", 0.0, 2.0 * math.pi), "course_sigma": non_negative("rad"),
        "speed": non_negative("m/s"), "speed_sigma": non_negative("m/s"),
    },
    "sonar.tma.bounds": _BOUNDS,
    "sonar.tma.bounds.*": _BOUNDS,
}


def ranges_of(section: str) -> dict[str, Range]:
    """The ranges of a section (exact name first, then patterns); {} if none."""
    if section in RANGES:
        return RANGES[section]
    for pattern, table in RANGES.items():
        if fnmatch.fnmatchcase(section, pattern):
            return table
    return {}


def out_of_range(section: str, values: dict[str, object]) -> tuple[str, str] | None:
    """The first (field, message) whose value (or one element of a list value) lies
    outside its range, or None."""
    table = ranges_of(section)
    for name, value in values.items():
        r = table.get(name)
        if r is None or isinstance(value, bool):
            continue
        for v in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(v, (int, float)) and not r.contains(float(v)):
                unit = f" {r.unit}" if r.unit else ""
                return name, f"{v!r} is outside {r}{unit}"
    return None
