"""Monte Carlo consistency of the global tracks, in one process (common.wire.radar_chain).

Run: .venv/bin/python benchmarks/global_consistency.py [scenario ...] [--runs N]

Per scenario (default two_targets and crossing) and seeds 1..N: per run, switches,
breaks, per target the mean position NEES and the RMSE against the PCRLB after the
settling time; then, over the runs, the average NEES per time against its 95 %
chi-square interval (common.evaluation.pcrlb.monte_carlo_nees: Bar-Shalom, Li, Kirubarajan
5.4.2), per target and in all, and the pooled RMSE / PCRLB. The same numbers as the
multi-process test (tests/integration/test_global_integration.py), which checks that this chain
reproduces the processes.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

import numpy as np

from common.deploy.config import load, section
from common.evaluation.pcrlb import Evaluation, base_information, monte_carlo_nees, score_targets
from common.radar.fusion.params import FusionParams
from common.sim.scenario import load_scenario, radar_scene
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import confirmed_tracks
from common.wire.sim_messages import run_scenario, truth_state

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
SETTLE = 30.0
P0 = np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2])


def one_run(path: Path, seed: int) -> Evaluation:
    """The chain on one seeded run of a scenario, scored as the integration test does."""
    cfg = load(path)
    chain = RadarChain(cfg)
    ev = Evaluation(c=2000.0, gamma=2000.0)
    scn = load_scenario(tomllib.loads(path.read_text()))
    for _, msgs in run_scenario(scn, cfg.bases, cfg.arrays, seed):
        truth = next(m for k, m in msgs if k == "sim/truth/radar")
        for g in chain.step(msgs):
            ev.add(g["t"], np.asarray(truth["id"]), truth_state(truth), *confirmed_tracks(g))
    return ev


def study(name: str, runs: int) -> None:
    path = SCENARIOS / f"{name}.toml"
    cfg = load(path)
    p = section(cfg, "radar.fusion", FusionParams)
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    per_target: dict[int, list[np.ndarray]] = {}
    per_run: list[np.ndarray] = []
    pooled: dict[int, list[tuple[int, float, float]]] = {}
    print(f"{name}: {runs} runs")
    for seed in range(1, runs + 1):
        ev = one_run(path, seed)
        scores = score_targets(ev, tx, rx, base_information(radar_scene(cfg), cfg.bases), p.q, p.q_z, P0, SETTLE)
        after = {tid: rows[:, :2] for tid, rows in ev.after(SETTLE).items()}
        for tid, rows in after.items():
            per_target.setdefault(tid, []).append(rows)
        per_run.append(np.concatenate([*after.values(), np.zeros((0, 2))]))
        for tid, sc in scores.items():
            pooled.setdefault(tid, []).append((sc.n, sc.rmse, sc.bound))
        s = ev.metrics.summary()
        print(f"  seed {seed:2d}: switches {s.switches}, breaks {s.breaks}; " + "; ".join(
            f"target {tid}: NEES {sc.nees_pos:5.2f}, RMSE {sc.rmse:5.0f} m / PCRLB {sc.bound:4.0f} m"
            for tid, sc in sorted(scores.items())))
    for label, rows in [*((f"target {t}", r) for t, r in sorted(per_target.items())),
                        ("all", per_run)]:
        mc = monte_carlo_nees(rows)
        print(f"  {label}: average NEES {mc.anees.mean():.2f} over {mc.times.size} times, "
              f"inside its interval (~[{mc.lo.mean():.2f}, {mc.hi.mean():.2f}]) at "
              f"{100 * mc.inside:.0f} % of them")
    for tid, v in sorted(pooled.items()):
        n, rmse, bound = (np.array(c) for c in zip(*v))
        r, b = np.sqrt((n * rmse**2).sum() / n.sum()), np.sqrt((n * bound**2).sum() / n.sum())
        print(f"  target {tid}: pooled RMSE {r:.0f} m, PCRLB {b:.0f} m, ratio {r / b:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenarios", nargs="*", default=["two_targets", "crossing"])
    ap.add_argument("--runs", type=int, default=16)
    args = ap.parse_args()
    for name in args.scenarios:
        study(name, args.runs)


if __name__ == "__main__":
    main()
