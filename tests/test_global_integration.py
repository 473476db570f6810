"""Multi-process tests of the whole radar chain: router + simulator + a channel-plotter
and an elementary-tracker per base + global-fusion, each a real process."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from common.bistatic import POS
from common.config import load, section
from common.global_fusion import FusionParams
from common.pcrlb import Evaluation, mean_nees_interval, score_targets
from services.evaluate.main import base_information
from tests.harness import SCENARIOS, Deployment

SETTLE = 30.0  # s after a target's first global track before RMSE / NEES count


def run_chain(tmp_path: Path, scn: Path) -> tuple[list[dict], list[dict]]:
    """Run the chain on a scenario; (gtracks messages, truth messages) by time."""
    cfg = load(scn)
    bases = [b.id for b in cfg.bases]
    with Deployment(tmp_path) as d:
        d.collect("radar/gtracks")
        d.collect("sim/truth/radar")
        d.collect("radar/etracks/*")
        alive = d.start_services(scn, ("channel-plotter", "elementary-tracker", "global-fusion"))
        d.wait_alive(alive)
        d.simulate(scn, seed=1, wait_alive=alive)
        truth = sorted(d.of("sim/truth/radar"), key=lambda m: m["t"])
        t_last = truth[-1]["t"]
        d.wait_for(lambda: any(m["t"] == t_last for m in d.of("radar/gtracks")))
        etracks = {b: d.of(f"radar/etracks/{b}") for b in bases}
    return d.of("radar/gtracks"), truth, etracks


def first_seen_by_two(etracks: dict[str, list[dict]], truth: list[dict], cfg) -> dict[int, float]:
    """Per truth id, the first time at which two bases hold a confirmed elementary track
    within 1 km of its bistatic range (the time the global chain can start it)."""
    from common.bistatic import bistatic_range

    seen: dict[int, dict[str, float]] = {}
    by_t = {m["t"]: m for m in truth}
    for base in cfg.bases:
        for msg in etracks[base.id]:
            m = by_t[msg["t"]]
            pos = np.column_stack([m["x"], m["y"], m["z"]])
            rb = bistatic_range(pos, base.tx, base.rx)
            conf = np.array([k["x"][0] for k in msg["tracks"] if k["status"] == "confirmed"])
            for tid, r in zip(m["id"].tolist(), rb):
                if conf.size and np.min(np.abs(conf - r)) < 1000.0:
                    seen.setdefault(tid, {}).setdefault(base.id, msg["t"])
    return {tid: sorted(v.values())[1] for tid, v in seen.items() if len(v) >= 2}


@dataclass
class ChainRun:
    """One chain run on a scenario, scored against its truth."""

    name: str
    truth: list[dict]
    by_t: dict[float, dict]
    start: dict[int, float]
    summary: Any
    scores: dict[int, Any]


@pytest.fixture(scope="module", params=["two_targets", "crossing"])
def chain(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> ChainRun:
    name = request.param
    scn = SCENARIOS / f"{name}.toml"
    cfg = load(scn)
    gtracks, truth, etracks = run_chain(tmp_path_factory.mktemp(name), scn)
    by_t = {m["t"]: m for m in gtracks}
    ev = Evaluation(c=2000.0, gamma=2000.0)
    for m in truth:
        g = by_t.get(m["t"], {"tracks": []})
        conf = [k for k in g["tracks"] if k["status"] == "confirmed"]
        state = np.column_stack([m["x"], m["vx"], m["y"], m["vy"], m["z"], m["vz"]])
        ev.add(m["t"], m["id"], state, np.array([k["id"] for k in conf], dtype=np.int64),
               np.array([k["x"] for k in conf]).reshape(-1, 6),
               np.array([k["P"] for k in conf]).reshape(-1, 6, 6))
    p = section(cfg, "radar.fusion", FusionParams)
    tx = np.array([b.tx for b in cfg.bases])
    rx = np.array([b.rx for b in cfg.bases])
    P0 = np.diag([1e6, 1e4, 1e6, 1e4, 1e6, 1e2])
    scores = score_targets(ev, tx, rx, base_information(cfg), p.q, p.q_z, P0, SETTLE)
    return ChainRun(name, truth, by_t, first_seen_by_two(etracks, truth, cfg),
                    ev.metrics.summary(), scores)


def test_one_cycle_per_scan(chain: ChainRun) -> None:
    assert sorted(chain.by_t) == [m["t"] for m in chain.truth]


def test_one_confirmed_track_per_target_no_switch(chain: ChainRun) -> None:
    """Each true target: exactly one confirmed global track within 15 scans of being seen
    by two bases, and no false confirmed track near it; no number switch, no break."""
    assert set(chain.start) == {1, 2}
    for tid, t0 in chain.start.items():
        for m in chain.truth:
            if m["t"] < t0 + 15.0:
                continue
            i = m["id"].tolist().index(tid)
            p = np.array([m["x"][i], m["y"][i], m["z"][i]])
            near = [k for k in chain.by_t[m["t"]]["tracks"] if k["status"] == "confirmed"
                    and np.linalg.norm(np.array(k["x"])[POS] - p) < 2000.0]
            assert len(near) == 1, (chain.name, tid, m["t"], len(near))
    assert chain.summary.switches == 0 and chain.summary.breaks == 0, chain.summary


def test_rmse_within_twice_the_pcrlb(chain: ChainRun) -> None:
    assert set(chain.scores) == {1, 2}
    for tid, sc in chain.scores.items():
        assert sc.rmse <= 2.0 * sc.bound, (chain.name, tid, sc)


@pytest.mark.xfail(reason="issue 4 open: covariance over-confident where altitude is poorly "
                          "observed (target 2 mean NEES ~10 over 12 seeds); see the issue note",
                   strict=False)
def test_mean_nees_inside_its_95_percent_interval(chain: ChainRun) -> None:
    n = sum(sc.n for sc in chain.scores.values())
    lo, hi = mean_nees_interval(3, n)
    mean_nees = sum(sc.nees_pos * sc.n for sc in chain.scores.values()) / n
    assert lo <= mean_nees <= hi, (chain.name, mean_nees, lo, hi)
