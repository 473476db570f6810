"""Parameters of table `[radar.network]`: the network fusion centre of
common.radar.network (docs/networks.md)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import ClassVar

from common.core.params import (
    PROB_OPEN,
    Params,
    Range,
    Rule,
    count,
    non_negative,
    order,
    positive,
    unbounded,
)


@dataclass(frozen=True)
class NetworkParams(Params):
    """Parameters of `[radar.network]`: the fusion centre of a network of receivers.

    The centre serves deployments of several receivers or with range-Doppler bases
    (common.radar.fusion_core); its decorrelation uses [radar.tracker]'s Q [20].

    window: reordering window: a report is processed once a report stamped `window`
        later has arrived (or at `flush`); one older than the last processed time is
        rejected (`too_late`, counted).
    decor_gate: chi-square bound on an equivalent measurement against its prediction.
    clock_sigma: prior sigma of a base's clock offset (common.radar.network.clocks).
    clock_drift: random-walk power of a base's clock offset.
    clock_reference: bases whose clocks are trusted (e.g. GPS-disciplined nodes): offset
        0, not estimated; one anchors the offset common to every base, which the ranges
        cannot observe (docs/networks.md, Limits).
    q, q_z: white-acceleration power of the CV model on (x, y) and on z.
    gate_prob: probability of the chi-square gates of members and assignment.
    member_misses: consecutive out-of-gate reports after which a member is released.
    init_period: time between initiation rounds.
    stale: age beyond which a base's last report is not used for initiation.
    init_bases: bases needed to open a track (capped to the bases with leftovers, never
        below 3).
    init_prob: quantile of the residual chi-square tests of a candidate.
    z_min, z_max: altitude bounds of the surveillance volume.
    volume_margin: horizontal extent of the volume beyond the sites' box.
    seed_z: altitudes of the extra Gauss-Newton seeds of a seed cell.
    cell_coarse, cell_fine: sides of the first and (at least) the last voting cells.
    max_cells: cells refined per level (most voted first; the rest wait, counted).
    max_sigma: worst position sigma beyond which a fix is degenerate.
    cycle: confirmation cycle.
    confirm_cycles: cycles, each with updates from >= 3 bases over >= 2 receivers, to
        confirm.
    coast, coast_tentative: time without update before deletion (confirmed, tentative).
    report_period: period of the global track reports.
    merge_distance: plane distance within which two confirmed tracks with disjoint bases
        are tested as one aircraft's (common.radar.network.duplicates); 0: never.
    partitions: names of the regions global fusion is split into, one instance each
        (`pfusion global-fusion --partition NAME`, common.radar.network.partition), in
        ascending order along partition_axis; empty: one instance, no partition.
    partition_axis: "x" (East) or "y" (North): the ENU axis the regions split.
    partition_splits: the boundaries between consecutive regions along that axis (one
        fewer than partitions, ascending; unused without partitions).
    partition_margin: hysteresis: a confirmed track is handed over to the region it is
        in once it is this far beyond its partition's region.
    handover_timeout: message time after which an unacknowledged handover is given up
        (the track is kept, counted, and handed over again while still outside).
    """

    window: float = 2.0
    decor_gate: float = 30.0
    clock_sigma: float = 0.1
    clock_drift: float = 1e-6
    clock_reference: tuple[str, ...] = ()
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
    max_cells: int = 20000
    max_sigma: float = 10e3
    cycle: float = 1.0
    confirm_cycles: int = 3
    coast: float = 5.0
    coast_tentative: float = 2.0
    report_period: float = 1.0
    merge_distance: float = 10e3
    partitions: tuple[str, ...] = ()
    partition_axis: str = "x"
    partition_splits: tuple[float, ...] = (0.0,)
    partition_margin: float = 5e3
    handover_timeout: float = 5.0

    RANGES: ClassVar[dict[str, Range]] = {
        "window": non_negative("s"), "decor_gate": positive("chi-square"),
        "clock_sigma": non_negative("s"), "clock_drift": non_negative("s^2/s"),
        "q": positive("m^2/s^3"), "q_z": positive("m^2/s^3"),
        "gate_prob": PROB_OPEN, "member_misses": count(1), "init_period": non_negative("s"),
        "stale": positive("s"), "init_bases": count(3), "init_prob": PROB_OPEN,
        "z_min": Range("m", -500.0, 30e3), "z_max": Range("m", 0.0, 30e3, "(]"),
        "volume_margin": non_negative("m"), "seed_z": Range("m", -500.0, 30e3),
        "cell_coarse": positive("m"), "cell_fine": positive("m"), "max_cells": count(1),
        "max_sigma": positive("m"), "cycle": positive("s"), "confirm_cycles": count(1),
        "coast": positive("s"), "coast_tentative": positive("s"), "report_period": positive("s"),
        "merge_distance": non_negative("m"),
        "partition_splits": unbounded("m", "an ENU coordinate"),
        "partition_margin": non_negative("m"), "handover_timeout": positive("s"),
    }
    RULES: ClassVar[tuple[Rule, ...]] = (
        order("z_min", "z_max"), order("cell_fine", "cell_coarse", strict=False),
        order("coast_tentative", "coast", strict=False),
        Rule(("partition_axis",), lambda a: a in ("x", "y"), 'partition_axis "x" or "y"'),
        Rule(("partitions", "partition_splits"),
             lambda n, s: not n or (len(n) >= 2 and len(set(n)) == len(n)
                                                 and len(s) == len(n) - 1
                                                 and all(a < b for a, b in zip(s, s[1:]))),
             "no partitions, or >= 2 distinct partitions and one fewer ascending "
             "partition_splits"),
        Rule(("partitions",), lambda n: all(re.fullmatch(r"[A-Za-z0-9_.-]+", k) for k in n),
             "partition names of letters, digits, '_', '.', '-' (Zenoh key chunks)"),
    )
