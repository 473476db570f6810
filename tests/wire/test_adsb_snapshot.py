"""The simulator's truth as aircraft.json snapshots (common.wire.adsb_snapshot): scoring a
simulated geodetic run against them (common.evaluation.adsb) gives the scores of the
simulator truth path, within the rounding of the snapshot (6 decimals of a degree,
whole feet); aircraft left out of the snapshots make their tracks unverified."""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from common.bus.recording import RecordWriter
from common.cli import main as cli_main
from common.deploy.config import load
from common.evaluation.adsb import AdsbScoring, AdsbTruth, parse_snapshot
from common.evaluation.metrics import count_switches
from common.evaluation.pcrlb import Evaluation
from common.sim.scenario import load_scenario
from common.wire import protocol
from common.wire.adsb_snapshot import aircraft_json
from common.wire.radar_chain import RadarChain
from common.wire.radar_messages import confirmed_tracks
from common.wire.sim_messages import run_scenario, truth_state

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "geodetic_two_targets.toml"


@pytest.fixture(scope="module")
def run() -> tuple[list[dict[str, Any]], dict[float, dict[str, Any]], list[str]]:
    """(gtracks messages as decoded, truth by time, the aircraft.json texts)."""
    cfg = load(SCENARIO)
    assert cfg.origin is not None
    chain, gtracks, truth, snaps = RadarChain(cfg), [], {}, []
    for t, msgs in run_scenario(load_scenario(cfg.doc), cfg.bases, cfg.arrays, 1):
        m = next(m for k, m in msgs if k == "sim/truth/radar")
        truth[t] = m
        snaps.append(json.dumps(aircraft_json(m, cfg.origin)))
        gtracks += [protocol.decode("gtracks", protocol.encode(g)) for g in chain.step(msgs)]
    return gtracks, truth, snaps


def _adsb(snaps: list[str], drop: set[str] = frozenset()) -> AdsbScoring:  # type: ignore[assignment]
    cfg = load(SCENARIO)
    assert cfg.origin is not None
    rejects: Counter[str] = Counter()
    truth = AdsbTruth(cfg.origin)
    truth.add(f for s in snaps for f in parse_snapshot(json.loads(s), rejects) if f.hex not in drop)
    assert not rejects
    return AdsbScoring(truth, Evaluation(keep_steps=True))


def test_adsb_truth_scores_as_the_simulator_truth(run: Any) -> None:
    gtracks, truth, snaps = run
    sim, adsb = Evaluation(keep_steps=True), _adsb(snaps)
    for g in gtracks:
        ids, x, P = confirmed_tracks(g)
        sim.add(g["t"], np.asarray(truth[g["t"]]["id"]), truth_state(truth[g["t"]]), ids, x, P)
        adsb.add(g["t"], ids, x, P)
    a, b = sim.metrics.summary(), adsb.ev.metrics.summary()
    assert a.steps == b.steps > 100 and adsb.unverified == set()
    assert (a.switches, a.breaks) == (b.switches, b.breaks)
    assert b.mean_gospa == pytest.approx(a.mean_gospa, abs=0.5)
    assert b.gospa == pytest.approx(a.gospa, rel=1e-3)
    assert count_switches(sim.metrics.joint_associations()) == count_switches(
        adsb.ev.metrics.joint_associations())
    ra, rb = sim.after(20.0), adsb.ev.after(20.0)
    assert sorted(ra) == sorted(rb) == [1, 2]
    for i in ra:
        rmse_a, rmse_b = (float(np.sqrt(r[:, 3].mean())) for r in (ra[i], rb[i]))
        assert rmse_b == pytest.approx(rmse_a, abs=0.5), i


def test_tracks_on_aircraft_without_adsb_are_unverified(run: Any) -> None:
    gtracks, _, snaps = run
    full, adsb = _adsb(snaps).truth, _adsb(snaps, drop={"000002"})
    for g in gtracks:
        ids, x, P = confirmed_tracks(g)
        adsb.add(g["t"], ids, x, P)
    on_2 = set()
    for g in gtracks[-5:]:  # the tracks on aircraft 2 at the end, far from aircraft 1
        ids, x = full.at(g["t"])
        one = x[ids.tolist().index(1), ::2]
        on_2 |= {k["id"] for k in g["tracks"] if k["status"] == "confirmed"
                 and np.linalg.norm(np.array(k["x"])[::2] - one) > 5e3}
    assert on_2 and on_2 <= adsb.unverified
    assert adsb.ev.metrics.summary().false == pytest.approx(0.0)


def test_evaluate_truth_adsb_on_a_recording_prints_the_simulator_truth_scores(
        run: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    gtracks, truth, snaps = run
    for k, s in enumerate(snaps):
        (tmp_path / f"aircraft-{k:06d}.json").write_text(s)
    with (tmp_path / "run.pfrec").open("wb") as f:
        rec = RecordWriter(f, "pf/v1", 0.0)
        for g in gtracks:
            rec.write("pf/v1/radar/gtracks", g["t"], protocol.encode(g))
    sim = Evaluation()
    for g in gtracks:
        sim.add(g["t"], np.asarray(truth[g["t"]]["id"]), truth_state(truth[g["t"]]), *confirmed_tracks(g))
    code = cli_main(["evaluate", "--config", str(SCENARIO), "--truth-adsb", str(tmp_path),
                     "--tracks", str(tmp_path / "run.pfrec")])
    out = capsys.readouterr().out
    assert code == 0, out
    gospa = float(re.search(r"mean GOSPA (\S+) m", out).group(1))  # type: ignore[union-attr]
    assert gospa == pytest.approx(sim.metrics.summary().mean_gospa, abs=0.5)
    assert "unverified (no ADS-B aircraft within the cutoff, not scored): 0 tracks" in out
    assert "000001" in out and "000002" in out  # the RMSE rows named by address
