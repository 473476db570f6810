"""Multi-process test of range-Doppler bases (`azimuth = false`): router + simulator +
one channel-plotter and one elementary-tracker per base, each a real process; global
fusion refuses the deployment."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from common.deploy.config import load
from common.radar.geometry.bistatic import bistatic_range, bistatic_range_rate
from common.wire import protocol
from tests.harness import ROOT, SCENARIOS, Deployment


def rd_scenario(tmp_path: Path) -> Path:
    """two_targets.toml with every base declared azimuth = false, 60 scans."""
    text = (SCENARIOS / "two_targets.toml").read_text()
    text = text.replace('channels = ["c1", "c2", "c3"]\n', 'channels = ["c1", "c2", "c3"]\nazimuth = false\n')
    text = text.replace("n_scans = 120", "n_scans = 60")
    path = tmp_path / "rd.toml"
    path.write_text(text)
    assert all(not b.azimuth for b in load(path).bases)
    return path


def test_range_doppler_bases_through_processes(tmp_path: Path) -> None:
    scn = rd_scenario(tmp_path)
    cfg = load(scn)
    with Deployment(tmp_path) as d:
        d.collect("radar/etracks/*")
        d.collect("radar/fused/*")
        d.collect("sim/truth/radar")
        d.collect("metrics/**")
        alive = d.start_services(scn, ("channel-plotter", "elementary-tracker"))
        d.wait_alive(alive)
        d.simulate(scn, seed=2, wait_alive=alive)
        truth = {m["t"]: m for m in d.of("sim/truth/radar")}
        t_last = max(truth)
        d.wait_for(lambda: all(any(m["t"] == t_last for m in d.of(f"radar/etracks/{b.id}"))
                               for b in cfg.bases))
        # plots with azimuth at a base declared without: counted, not fused
        bad = {"v": 1, "t": t_last + 1.0, "seq": 10**6, "base": "b1", "channel": "c1",
               "rb": [3e4], "vb": [1.0], "az": [1.0], "srb": [150.0], "svb": [2.0], "saz": [0.02]}
        d.session.put(f"{ROOT}/radar/plots/b1/c1", protocol.encode(bad))

        def rejected() -> dict:
            ms = [m for k, m in d.messages if k == f"{ROOT}/metrics/channel_plotter/b1"]
            return ms[-1]["rejected"] if ms else {}

        d.wait_for(lambda: rejected().get("unexpected_azimuth") == 1, timeout=30)
        fusion = d.start("global-fusion", "global-fusion", "--config", str(scn))
        fusion.proc.wait(timeout=60)
        d.children.remove(fusion)
        logs = " ".join(p.read_text() for p in tmp_path.glob("*.log"))

    assert "unexpected_azimuth" in logs  # the reason is logged, not only counted
    assert fusion.proc.returncode == 2  # global fusion (001 step 24) refuses the deployment
    assert "b1, b2, b3 declared azimuth = false" in (tmp_path / "global-fusion.log").read_text()
    for base in cfg.bases:
        assert all("az" not in m and "saz" not in m for m in d.of(f"radar/fused/{base.id}"))
        etracks = d.of(f"radar/etracks/{base.id}")
        assert [m["t"] for m in etracks] == sorted(truth)
        held = 0
        for msg in etracks:
            assert msg["azimuth"] is False and all(len(k["x"]) == 3 and len(k["P"]) == 9 for k in msg["tracks"])
            if msg["t"] < 20.0:
                continue
            m = truth[msg["t"]]
            pos, vel = (np.column_stack([m[f"{p}{c}"] for c in "xyz"]) for p in ("", "v"))
            rbs, vbs = bistatic_range(pos, base.tx, base.rx), bistatic_range_rate(pos, vel, base.tx, base.rx)
            conf = [k for k in msg["tracks"] if k["status"] != "tentative"]
            held += all(any(abs(k["x"][0] - rb) < 4 * np.sqrt(k["P"][0])
                            and abs(k["x"][1] - vb) < 4 * np.sqrt(k["P"][4]) for k in conf)
                        for rb, vb in zip(rbs, vbs))
        assert held >= 0.95 * (len(etracks) - 20), (base.id, held)
