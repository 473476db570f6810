"""Parameters of the network fusion centre (docs/networks.md)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class NetworkParams:
    """Units: m, s, m/s.

    window: s, reordering window; a report is processed once a report stamped `window`
        later has arrived (or at `flush`); one older than the last processed time is
        rejected (`too_late`, counted).
    sigma_gamma, sigma_omega: m/s^3, rad/s^2, Q [20] of the elementary trackers (the
        decorrelation predicts their previous report with it).
    decor_gate: chi-square bound on an equivalent measurement against its prediction.
    clock_sigma: s, sigma of a node's clock offset; R_rr += (v_b clock_sigma)^2.
    q, q_z: m^2/s^3, white-acceleration power of the CV model on (x, y) and on z.
    gate_prob: probability of the chi-square gates of members and assignment.
    member_misses: consecutive out-of-gate reports after which a member is released.
    init_period: s, between initiation rounds; stale: s, age beyond which a base's last
        report is not used for initiation.
    init_bases: bases needed to open a track (capped to the bases with leftovers, never
        below 3); init_prob: quantile of the residual chi-square tests of a candidate.
    pair_sigmas: margin, in sigma_r, of the cheap pair gate; max_triples: triples
        solved per round (the rest wait for the next round, counted).
    z_min, z_max: m, altitude bounds of the surveillance volume; seed_xy: m, offset of
        the horizontal seeds around the anchor receivers; seed_z: m, seed altitudes.
    max_sigma: m, worst position sigma beyond which a fix is degenerate.
    cycle: s, confirmation cycle; confirm_cycles: cycles, each with updates from >= 3
        bases over >= 2 receivers, to confirm.
    coast, coast_tentative: s without update before deletion.
    report_period: s, period of the global track reports.
    """

    window: float = 2.0
    sigma_gamma: float = 5.0
    sigma_omega: float = 1e-3
    decor_gate: float = 30.0
    clock_sigma: float = 0.1
    q: float = 1.0
    q_z: float = 0.25
    gate_prob: float = 0.9999
    member_misses: int = 3
    init_period: float = 1.0
    stale: float = 2.5
    init_bases: int = 6
    init_prob: float = 0.999
    pair_sigmas: float = 5.0
    max_triples: int = 20000
    z_min: float = 0.0
    z_max: float = 20e3
    seed_xy: float = 40e3
    seed_z: tuple[float, ...] = (3e3, 10e3)
    max_sigma: float = 10e3
    cycle: float = 1.0
    confirm_cycles: int = 3
    coast: float = 5.0
    coast_tentative: float = 2.0
    report_period: float = 1.0
