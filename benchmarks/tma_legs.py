"""Multi-leg TMA through the real processes (issue 13; 002 claims 13-16, 003 claim 9):
scenarios/sonar_tma_legs.toml (a contact turning 50 deg at 30 min, own ship zig-zagging)
through router, `pfusion simulate`, `pfusion bearing-tracker` and `pfusion tma` with
[sonar.tma.ctma] detect_manoeuvres = true, one deployment per seed.

Run: .venv/bin/python benchmarks/tma_legs.py [--runs 5] [--speed 200]

Per run: the manoeuvre times of the final solution (true 1800 s), and its position
error at its time against the Cramer-Rao bound of the true two-leg geometry (all
cycles, sigma0; common.sonar.tma.crlb with the true manoeuvre time).
Goals (exit code 1 when one fails): every run ends with a solution whose first leg
time is within 240 s of the true one (12 cycles), final error RMS over the runs <= 3 x
the bound's RMS, no run above 8 x its bound. These guard what the code does (set after
the first measurement below, not a target reached): the detector finds the turn in every
run, but its time is off by up to 100 s and the error is well above the bound of a known
manoeuvre time.

Measured 2026-11-23 (10 runs, speed 200, 2 shared cores):
  seed            1     2     3     4     5     6     7     8     9    10
  leg time s   1760  1820  1720  1700  1840  1800  1720  1740  1820  1720   (true 1800)
  error m      1427   327   568  1743   472  1211  2871  1930   246  4612
  / CRLB       1.69  0.39  0.67  2.04  0.56  1.43  3.40  2.28  0.30  5.45
  RMS 2012 m against a CRLB RMS of 843 m (2.39); the in-process study with the leg time
  known (tests/sonar/test_ctma_legs.py) is at 1.06 x CRLB, so the loss is the detector's
  (its deviation from 002 is stated in common.sonar.tma.bearings_only.detect_manoeuvre).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from common.bus.local_run import Deployment  # noqa: E402
from common.deploy.config import load  # noqa: E402
from common.sonar.tma.crlb import position_rms_bound  # noqa: E402

SCENE = REPO / "scenarios" / "sonar_tma_legs.toml"
T_MANOEUVRE = 1800.0
LEG_TOL = 240.0


def run_once(seed: int, speed: float, logdir: Path) -> tuple[tuple[float, ...], float, float]:
    """(manoeuvre times, final position error m, its CRLB m) of one seeded run."""
    t_end = (load(SCENE).doc["sim"]["n_scans"] - 1) * load(SCENE).doc["sim"]["scan_period"]
    with Deployment(logdir) as d:
        for key in ("sonar/tma/a1", "sim/truth/sonar"):
            d.collect(key)
        d.start("btracker", "bearing-tracker", "--config", str(SCENE), "--array", "a1")
        d.start("tma", "tma", "--config", str(SCENE), "--array", "a1")
        d.wait_alive(["bearing_tracker/a1", "tma/a1"])
        d.start("simulate", "simulate", "--config", str(SCENE), "--scenario", str(SCENE),
                "--seed", str(seed), "--speed", str(speed), "--wait-alive", "test/collector",
                "--wait-alive", "bearing_tracker/a1", "--wait-alive", "tma/a1")
        d.announce()
        d.wait_for(lambda: any(m["t"] == t_end for m in d.of("sonar/tma/a1")), 600)
        tma = d.of("sonar/tma/a1")
        truth = sorted(d.of("sim/truth/sonar"), key=lambda m: m["t"])
    t = np.array([m["t"] for m in truth])
    own = np.array([[m["own"]["x"], m["own"]["y"]] for m in truth])
    pos = np.array([[m["x"][0], m["y"][0]] for m in truth])
    v0 = [truth[0]["vx"][0], truth[0]["vy"][0]]
    v1 = [truth[-1]["vx"][0], truth[-1]["vy"][0]]
    beta = np.r_[pos[0], v0, v1]
    sols = tma[-1]["solutions"]
    k = [int(np.searchsorted(t, s["t"])) for s in sols]
    errs = [math.hypot(s["x"] - pos[i, 0], s["y"] - pos[i, 1]) for s, i in zip(sols, k)]
    best = int(np.argmin(errs))  # the contact's track (the others are clutter's, if any)
    s = sols[best]
    bound = position_rms_bound(beta, t, own, load(SCENE).array("a1").sigma0, 0.0, float(s["t"]),
                               (T_MANOEUVRE,))
    return tuple(s["legs"]), errs[best], bound


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--speed", type=float, default=200.0)
    a = ap.parse_args(argv)
    rows = []
    for seed in range(1, a.runs + 1):
        with tempfile.TemporaryDirectory() as tmp:
            legs, err, bound = run_once(seed, a.speed, Path(tmp))
        rows.append((legs, err, bound))
        print(f"seed {seed}: legs {[round(x) for x in legs]} s, error {err:.0f} m, "
              f"CRLB {bound:.0f} m, ratio {err / bound:.2f}", flush=True)
    err = np.array([r[1] for r in rows])
    bound = np.array([r[2] for r in rows])
    rms, brms = float(np.sqrt(np.mean(err**2))), float(np.sqrt(np.mean(bound**2)))
    legs_ok = all(r[0] and abs(r[0][0] - T_MANOEUVRE) <= LEG_TOL for r in rows)
    ok = legs_ok and rms <= 3.0 * brms and bool(np.all(err <= 8.0 * bound))
    print(f"RMS {rms:.0f} m against CRLB RMS {brms:.0f} m (ratio {rms / brms:.2f}), "
          f"max ratio {float(np.max(err / bound)):.2f}, legs found within {LEG_TOL:.0f} s: {legs_ok}")
    print("goals met" if ok else "GOAL FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
