"""Writes the dense scenes of issue 14: scenarios/dense300.toml and dense1000.toml.

Run: .venv/bin/python benchmarks/dense_scene.py  (the files are committed: frozen)

The issue's scene: one receiver and the four transmitters of scenarios/dense.toml with
2-4 channels each (b1 c1-c4, b2 c1-c3, b3 c1-c3, b4 the DVB-T c5-c6), Pd 0.85, 4 false
plots per channel per scan, 1 s scans, 120 scans; targets 10-60 km from the receiver
(uniform in area), 1-10 km up, 50-300 m/s horizontal, a fifth of them turning once
(1-3 deg/s for 20-60 s), a tenth appearing and a tenth disappearing during the run.
Channel sigmas as dense.toml. One seed per target count.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from common.core.angles import wrap_360

REPO = Path(__file__).resolve().parents[1]

HEADER = """# Dense air picture of issue 14: {n} aircraft 10-60 km from the receiver, 1-10 km up,
# 50-300 m/s, a fifth turning; one receiver, 4 transmitters with 2-4 channels, Pd 0.85,
# 4 false plots per channel per scan. Written by benchmarks/dense_scene.py (seed {seed}),
# then frozen.

[zenoh]
root = "pf/v1"

[radar]
[[radar.base]]
id = "b1"
tx = [-35000.0, 20000.0, 300.0]
rx = [0.0, 0.0, 30.0]
channels = ["c1", "c2", "c3", "c4"]
p = 2

[[radar.base]]
id = "b2"
tx = [45000.0, 10000.0, 500.0]
rx = [0.0, 0.0, 30.0]
channels = ["c1", "c2", "c3"]
p = 1

[[radar.base]]
id = "b3"
tx = [5000.0, -52000.0, 400.0]
rx = [0.0, 0.0, 30.0]
channels = ["c1", "c2", "c3"]
p = 1

[[radar.base]]
id = "b4"
tx = [-22000.0, -18000.0, 250.0]
rx = [0.0, 0.0, 30.0]
channels = ["c5", "c6"]
p = 0

[sim]
name = "dense{n}"
scan_period = 1.0
n_scans = 120

[sim.radar]
pd = 0.85
clutter = 4.0
srb = 150.0
svb = 1.5
saz_deg = 1.0
snr_db = 18.0
snr_threshold_db = 12.0
rb_max = 250000.0
vb_max = 600.0

[sim.radar.channel.c2]
srb = 250.0
svb = 2.5
saz_deg = 1.5

[sim.radar.channel.c4]
pd = 0.8
srb = 200.0
svb = 2.0
saz_deg = 2.0

[sim.radar.channel.c5]
srb = 100.0
svb = 1.0
saz_deg = 1.5

[sim.radar.channel.c6]
srb = 100.0
svb = 1.0
saz_deg = 1.5
"""


def targets(n: int, seed: int) -> str:
    """The [[sim.radar.target]] tables of n targets."""
    rng = np.random.default_rng(seed)
    rho = np.sqrt(rng.uniform(10e3**2, 60e3**2, n))
    az = rng.uniform(0.0, 2 * np.pi, n)
    z = rng.uniform(1e3, 10e3, n)
    course = rng.uniform(0.0, 360.0, n)
    speed = rng.uniform(50.0, 300.0, n)
    kind = rng.uniform(size=n)
    out = []
    for i in range(n):
        lines = ["[[sim.radar.target]]", f"id = {i + 1}",
                 f"pos = [{rho[i] * np.sin(az[i]):.0f}.0, {rho[i] * np.cos(az[i]):.0f}.0, {z[i]:.0f}.0]",
                 f"course_deg = {course[i]:.1f}", f"speed = {speed[i]:.1f}"]
        if kind[i] < 0.1:
            lines.append(f"t_on = {rng.uniform(5, 80):.0f}.0")
        elif kind[i] < 0.2:
            lines.append(f"t_off = {rng.uniform(40, 115):.0f}.0")
        if rng.uniform() < 0.2:
            t = rng.uniform(20, 90) if kind[i] >= 0.1 else rng.uniform(85, 100)
            rate = rng.choice([-1, 1]) * rng.uniform(1.0, 3.0)
            turn = rate * rng.uniform(20, 60)
            lines += ["", "[[sim.radar.target.leg]]", f"t = {t:.0f}.0",
                      f"course_deg = {wrap_360(course[i] + turn):.1f}", f"turn_rate_deg = {rate:.2f}"]
        out.append("\n".join(lines))
    return "\n\n".join(out) + "\n"


def main() -> None:
    for n, seed in ((300, 300), (1000, 1000)):
        path = REPO / "scenarios" / f"dense{n}.toml"
        path.write_text(HEADER.format(n=n, seed=seed) + "\n" + targets(n, seed))
        print(f"wrote {path.relative_to(REPO)}")


if __name__ == "__main__":
    main()
