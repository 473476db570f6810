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
    clock_sigma: s, prior sigma of a base's clock offset; clock_drift: s^2/s, random-walk
        power of the offset (common.radar.network.clocks).
    q, q_z: m^2/s^3, white-acceleration power of the CV model on (x, y) and on z.
    gate_prob: probability of the chi-square gates of members and assignment.
    member_misses: consecutive out-of-gate reports after which a member is released.
    init_period: s, between initiation rounds; stale: s, age beyond which a base's last
        report is not used for initiation.
    init_bases: bases needed to open a track (capped to the bases with leftovers, never
        below 3); init_prob: quantile of the residual chi-square tests of a candidate.
    z_min, z_max: m, altitude bounds of the surveillance volume; volume_margin: m, its
        horizontal extent beyond the sites' box; seed_z: m, altitudes of the extra
        Gauss-Newton seeds of a seed cell.
    cell_coarse, cell_fine: m, sides of the first and (at least) the last voting cells;
        vote_slack: votes below the best cell's a cell may have and still be refined;
        max_cells: cells refined per level (most voted first; the rest wait, counted).
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
    clock_drift: float = 1e-6
    q: float = 1.0
    q_z: float = 0.25
    gate_prob: float = 0.9999
    member_misses: int = 3
    init_period: float = 1.0
    stale: float = 2.5
    init_bases: int = 6
    init_prob: float = 0.999
    z_min: float = 0.0
    z_max: float = 20e3
    volume_margin: float = 20e3
    seed_z: tuple[float, ...] = (3e3, 10e3)
    cell_coarse: float = 10e3
    cell_fine: float = 300.0
    vote_slack: int = 1
    max_cells: int = 20000
    max_sigma: float = 10e3
    cycle: float = 1.0
    confirm_cycles: int = 3
    coast: float = 5.0
    coast_tentative: float = 2.0
    report_period: float = 1.0
