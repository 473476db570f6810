"""Multi-process tests of the per-base radar chain: router + simulator + one
channel-plotter and one elementary-tracker per base, each a real process."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from common.bus.transport import stamp
from common.core.angles import wrap_pi
from common.deploy.config import load
from common.radar.geometry.bistatic import azimuth, bistatic_range
from common.wire import protocol
from tests.harness import ROOT, SCENARIOS, Deployment

SCN = SCENARIOS / "two_targets.toml"
BAD_SCN = """
[zenoh]
root = "pf/v1"
[[radar.base]]
id = "b1"
tx = [-35000.0, 20000.0, 300.0]
rx = [0.0, 0.0, 30.0]
channels = ["c1", "c2"]
"""


def near(tracks: list[dict], rb: float, az: float, sigma_rb: float) -> list[dict]:
    """Confirmed or coasting tracks within 5 fused sigmas in r_b and 3 deg of a target."""
    return [k for k in tracks if k["status"] != "tentative"
            and abs(k["x"][0] - rb) < 5 * sigma_rb and abs(wrap_pi(k["x"][3] - az)) < math.radians(3)]


def test_two_targets_every_base(tmp_path: Path) -> None:
    cfg = load(SCN)
    bases = [b.id for b in cfg.bases]
    with Deployment(tmp_path) as d:
        d.collect("radar/etracks/*")
        d.collect("radar/fused/*")
        d.collect("sim/truth/radar")
        alive = d.start_services(SCN, ("channel-plotter", "elementary-tracker"))
        d.wait_alive(alive)
        d.simulate(SCN, seed=1, wait_alive=alive)
        truth = {m["t"]: m for m in d.of("sim/truth/radar")}
        t_last = max(truth)
        d.wait_for(lambda: all(any(m["t"] == t_last for m in d.of(f"radar/etracks/{b}"))
                               for b in bases))

    n_scans = len(truth)
    assert n_scans == 120 and all(len(m["id"]) == 2 for m in truth.values())
    false_ids: set[tuple[str, int]] = set()
    for base in cfg.bases:
        fused = d.of(f"radar/fused/{base.id}")
        etracks = d.of(f"radar/etracks/{base.id}")
        assert [m["t"] for m in etracks] == sorted(truth)  # one message per scan, in order
        sigma_rb = float(np.median(np.concatenate([m["srb"] for m in fused])))
        first_seen: dict[int, int] = {}
        numbers: dict[int, list[tuple[int, list[int]]]] = {}
        errors = []
        for k, msg in enumerate(etracks):
            m = truth[msg["t"]]
            pos = np.column_stack([m["x"], m["y"], m["z"]])
            rbs, azs = bistatic_range(pos, base.tx, base.rx), azimuth(pos, base.rx)
            matched: set[int] = set()
            for tid, rb, az in zip(m["id"].tolist(), rbs, azs):
                first_seen.setdefault(tid, k)
                hits = near(msg["tracks"], rb, az, sigma_rb)
                numbers.setdefault(tid, []).append((k, [h["id"] for h in hits]))
                matched.update(h["id"] for h in hits)
                errors += [h["x"][0] - rb for h in hits if h["status"] == "confirmed"]
            false_ids |= {(base.id, tr["id"]) for tr in msg["tracks"]
                          if tr["status"] == "confirmed" and tr["id"] not in matched}
        for tid, seq in numbers.items():
            confirmed_at = [k for k, ids in seq if len(ids) == 1]
            assert confirmed_at and confirmed_at[0] - first_seen[tid] <= 10, (base.id, tid, seq[:12])
            after = [ids for k, ids in seq if k >= confirmed_at[0]]
            assert all(ids == after[0] for ids in after), (base.id, tid, after)
        assert sorted(numbers) == [1, 2]
        rmse = float(np.sqrt(np.mean(np.square(errors))))
        print(f"{base.id}: r_b RMSE {rmse:.1f} m, fused sigma {sigma_rb:.1f} m")
        assert rmse < sigma_rb, (base.id, rmse, sigma_rb)
    assert len(false_ids) < len(cfg.bases) * n_scans / 100, false_ids


def test_bad_plots_and_fused_are_counted_and_skipped(tmp_path: Path) -> None:
    scn = tmp_path / "bad.toml"
    scn.write_text(BAD_SCN)
    good = {"v": 1, "base": "b1", "rb": [30000.0], "vb": [10.0], "az": [1.0],
            "srb": [150.0], "svb": [2.0], "saz": [0.02]}
    with Deployment(tmp_path) as d:
        d.collect("radar/etracks/b1")  # not radar/fused/b1: the collector would choke on our garbage
        d.collect("metrics/**")
        d.start("plotter", "channel-plotter", "--config", str(scn), "--base", "b1")
        d.start("tracker", "elementary-tracker", "--config", str(scn), "--base", "b1")
        d.wait_alive(["channel_plotter/b1", "elementary_tracker/b1"])

        def put(key: str, payload: bytes, attachment: bytes | None = None) -> None:
            d.session.put(f"{ROOT}/{key}", payload, attachment=attachment)

        def plots(t: float, ch: str, **kw: object) -> bytes:
            return protocol.encode({**good, "t": t, "seq": int(t), "channel": ch, **kw})

        # c1 carries publisher stamps 0, 1, 3, 6: three samples never arrived
        for t, n in ((1.0, 0), (2.0, 1)):
            put("radar/plots/b1/c1", plots(t, "c1"), stamp("sensor", n))
            put("radar/plots/b1/c2", plots(t, "c2"))
        put("radar/plots/b1/c1", b"\xc1garbage")
        put("radar/plots/b1/c1", plots(3.0, "c1", base="b9"))
        put("radar/plots/b1/c1", plots(3.0, "c1", rb=[float("nan")]))
        put("radar/plots/b1/c2", plots(1.5, "c2"))  # time going backwards on c2
        put("radar/fused/b1", b"not msgpack at all")
        for t, n in ((3.0, 3), (4.0, 6)):
            put("radar/plots/b1/c1", plots(t, "c1"), stamp("sensor", n))
            put("radar/plots/b1/c2", plots(t, "c2"), b"\x93bad" if t == 3.0 else None)

        def latest(service: str, field: str) -> dict:
            ms = [m for k, m in d.messages if k == f"{ROOT}/metrics/{service}/b1"]
            return ms[-1][field] if ms else {}

        def rejected(service: str) -> dict:
            return latest(service, "rejected")

        d.wait_for(lambda: len(d.of("radar/etracks/b1")) == 4
                   and sum(rejected("channel_plotter").values()) >= 5
                   and bool(latest("channel_plotter", "missed"))
                   and sum(rejected("elementary_tracker").values()) >= 1, timeout=30)
        # every scan was fused and tracked: the two plots of each scan made one track
        assert [m["t"] for m in d.of("radar/etracks/b1")] == [1.0, 2.0, 3.0, 4.0]
        assert [len(m["tracks"]) for m in d.of("radar/etracks/b1")] == [0, 1, 1, 1]
        r = rejected("channel_plotter")
        assert r.get("decode:<payload>") == 1 and r.get("unknown_base") == 1
        assert r.get("decode:rb[0]") == 1 and r.get("time_backwards") == 1
        assert r.get("attachment") == 1  # and its sample was still fused (t = 3 above)
        assert latest("channel_plotter", "missed") == {f"{ROOT}/radar/plots/b1/c1": 3}
        assert latest("elementary_tracker", "missed") == {}  # the plotter's stamps: no gap
        assert rejected("elementary_tracker") == {"decode:<payload>": 1}
        assert all(c.alive() for c in d.children)
