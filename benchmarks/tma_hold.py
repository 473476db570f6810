"""TMA accuracy and consistency on the two geometries of issue 13, in one process, 20 seeds:
final position error RMS against the Cramer-Rao bound, and the NEES of the published
covariance, with the bearings TMA is fed: the raw associated detections (what the bearing
tracker associated, true covariance sigma^2 I, what services/tma is served) or the
tracker's filtered bearings (x[0], sqrt(P[0,0]) of common.sonar.bearing.tracker); and the
register of the multiple-hypothesis mode (common.sonar.mht.tracker): the detections of the main
hypothesis by the retrodicted weights ("mht raw", what its history queryable serves to
TMA) or the retrodicted bearings ("mht smoothed", served beside them).

Run: .venv/bin/python benchmarks/tma_hold.py [--runs 20]

Geometries:
  close   a 15 kn target passing about 1 km from the own ship (5 kn), 2 deg noise,
          60 s, 30 samples, own ship turning 60 deg at sample 15;
  5 turns own ship 6 kn zig-zagging 045/135 with five turns over 30 min, target 6.3 km
          away at 4 kn, 1 deg noise, one bearing every 10 s (180 samples).
Estimator: the service's per-track core (common.sonar.tma.constrained.TmaTracker: TMA of 002, CTMA
of 003 with the minimal bounds), one cycle on all bearings.
Goals (exit code 1 when one fails), raw detections: RMS <= 1.3 x CRLB, no run above
5 x CRLB on both; mean NEES (4 dof: x, y, vx, vy at the last time) inside its 95 %
interval on the five-turn geometry. The filtered feed is printed beside, as the
measurement that motivates the change.
Measured 2026-11-23 (20 runs):
  geometry  feed          CRLB m   RMS m  RMS/CRLB  max/CRLB   NEES  (95 % interval 2.86-5.33)
  close     raw           3997.3   656.6     0.16      0.22   66.87
  close     filtered      3997.3   575.0     0.14      0.20  166.63
  close     mht raw       3997.3   678.6     0.17      0.22   66.73
  close     mht smoothed  3997.3   662.2     0.17      0.22   22.16
  5 turns   raw            655.5   606.1     0.92      1.68    4.01
  5 turns   filtered       655.5   830.0     1.27      2.42   30.36
  5 turns   mht raw        655.5   606.1     0.92      1.68    4.01
  5 turns   mht smoothed   655.5   675.5     1.03      1.91   25.21
The retrodicted bearings are smoothed over n_retro cycles: correlated, hence a TMA
treating them as independent is overconfident (NEES 25 for 4 dof), as with the filtered
ones; the MHT register's detections give the raw feed's numbers.
The close geometry is hardly observable in 60 s: its CRLB is about 4 km at 1 km range,
and unconstrained TMA (002) diverges in some runs (ranges beyond 1e9 m); the CTMA of 003
(minimal bounds 100 m-100 km, 0.1-15 m/s) keeps the error far below the CRLB, which
ignores the bounds. Its published P is then no error covariance (mean NEES about 67):
no NEES goal there (a known limit, stated).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common.core.angles import wrap_2pi  # noqa: E402
from common.core.gating import quadratic_form  # noqa: E402
from common.evaluation.pcrlb import mean_nees_interval  # noqa: E402
from common.sonar.mht.params import MhtParams, SonarTrackerParams  # noqa: E402
from common.sonar.tma.bounds import MINIMAL_BOUNDS  # noqa: E402
from common.sonar.tma.constrained import TmaTracker  # noqa: E402
from common.sonar.tma.crlb import position_rms_bound  # noqa: E402
from common.sonar.trackers import bearing_tracker  # noqa: E402

KN = 1852.0 / 3600.0


def own_path(t: np.ndarray, course_deg: np.ndarray, speed: float) -> np.ndarray:
    """Own positions at t for the course held over each interval (course_deg per sample)."""
    c = np.radians(course_deg[:-1])
    step = speed * np.diff(t)[:, None] * np.stack((np.sin(c), np.cos(c)), 1)
    return np.vstack(([0.0, 0.0], np.cumsum(step, 0)))


def geometry(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Sample times, own positions, true target (x0, y0, vx, vy) at t = 0, bearing sigma."""
    if name == "close":
        t = np.arange(30) * 2.0
        own = own_path(t, np.where(np.arange(30) < 15, 0.0, 60.0), 5 * KN)
        v = 15 * KN
        beta = np.array([1000.0, 30 * 2.0 * 0.5 * v + 77.0, 0.0, -v])  # CPA about 1 km near t = 30 s
        return t, own, beta, math.radians(2.0)
    t = np.arange(180) * 10.0
    course = np.select([t < 300, t < 600, t < 900, t < 1200, t < 1500], [45, 135, 45, 135, 45], 135.0)
    crs = math.radians(250.0)
    return t, own_path(t, course, 6 * KN), np.array([2000.0, 6000.0, 4 * KN * math.sin(crs),
                                                      4 * KN * math.cos(crs)]), math.radians(1.0)


def bearings(t: np.ndarray, own: np.ndarray, beta: np.ndarray) -> np.ndarray:
    x, y = beta[0] + beta[2] * t, beta[1] + beta[3] * t
    return np.arctan2(x - own[:, 0], y - own[:, 1])


def filtered(t: np.ndarray, z: np.ndarray, sig: float) -> tuple[np.ndarray, np.ndarray]:
    """The bearing tracker's filtered bearings and sigmas of the one contact."""
    tr = bearing_tracker(SonarTrackerParams(mode="broadband", crossing=False), MhtParams(), "cylindrical", sig)
    b, s = np.empty(t.size), np.empty(t.size)
    for k in range(t.size):
        c = tr.step(t[k], np.array([wrap_2pi(z[k])]), np.array([100.0]), 0.0)
        first = int(np.argmin(c.ids))
        b[k], s[k] = c.x[first, 0], math.sqrt(c.P[first, 0, 0])
    return b, s


def mht_register(t: np.ndarray, z: np.ndarray, sig: float, own: np.ndarray
                 ) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """The multiple-hypothesis tracker's register of the one contact (000 retrodiction,
    common.sonar.mht.retrodiction), both feeds: (times, bearings, sigmas, own positions) of
    the main hypothesis's detections ("mht raw") and of the retrodicted bearings ("mht
    smoothed")."""
    tr = bearing_tracker(SonarTrackerParams(mode="broadband", mode_association="mht"), MhtParams(),
                         "cylindrical", sig)
    for k in range(t.size):
        c = tr.step(t[k], np.array([wrap_2pi(z[k])]), np.array([100.0]), 0.0,
                    own_x=own[k, 0], own_y=own[k, 1])
    found = tr.history_of(int(c.ids[c.confirmed][0]))
    assert found is not None
    h = found[1]
    rows = np.searchsorted(t, h["t_retro"])
    return {"mht raw": (h["t"], h["brg"], h["sbrg"], np.column_stack([h["own_x"], h["own_y"]])),
            "mht smoothed": (h["t_retro"], h["brg_retro"], h["sbrg_retro"], own[rows])}


def run(name: str, runs: int) -> tuple[dict[str, np.ndarray], float]:
    """Per feed: (runs, 2) final position error (m) and NEES; and the CRLB (m)."""
    t, own, beta, sig = geometry(name)
    truth = bearings(t, own, beta)
    bound = position_rms_bound(beta, t, own, sig, 0.0, float(t[-1]))
    x_true = np.array([beta[0] + beta[2] * t[-1], beta[1] + beta[3] * t[-1], beta[2], beta[3]])
    out: dict[str, list[tuple[float, float]]] = {
        "raw": [], "filtered": [], "mht raw": [], "mht smoothed": []}
    for seed in range(runs):
        z = truth + sig * np.random.default_rng(seed).standard_normal(t.size)
        fb, fs = filtered(t, z, sig)
        feeds = {"raw": (t, z, np.full(t.size, sig), own), "filtered": (t, fb, fs, own),
                 **mht_register(t, z, sig, own)}
        for feed, (tf, b, s, of) in feeds.items():
            c = TmaTracker(MINIMAL_BOUNDS).update(tf, b, s, of)
            e = np.array([c.x, c.y, c.vx, c.vy]) - x_true
            P = np.asarray(c.P, float).reshape(4, 4)
            out[feed].append((float(np.hypot(e[0], e[1])), float(quadratic_form(e, P))))
    return {k: np.array(v) for k, v in out.items()}, bound


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    a = ap.parse_args(argv)
    lo, hi = mean_nees_interval(4, a.runs)
    ok = True
    print(f"{'geometry':<10}{'feed':<14}{'CRLB m':>9}{'RMS m':>9}{'RMS/CRLB':>9}{'max/CRLB':>9}"
          f"{'NEES':>8}  (95 % interval {lo:.2f}-{hi:.2f})")
    for name in ("close", "5 turns"):
        res, bound = run(name, a.runs)
        for feed, r in res.items():
            rms = float(np.sqrt(np.mean(r[:, 0] ** 2)))
            nees = float(np.mean(r[:, 1]))
            print(f"{name:<10}{feed:<14}{bound:>9.1f}{rms:>9.1f}{rms / bound:>9.2f}"
                  f"{r[:, 0].max() / bound:>9.2f}{nees:>8.2f}")
            if feed in ("raw", "mht raw"):
                ok &= rms <= 1.3 * bound and r[:, 0].max() <= 5 * bound
                ok &= name == "close" or lo <= nees <= hi
    print("goals met" if ok else "GOAL FAILED: RMS <= 1.3 CRLB, max <= 5 CRLB, NEES in its interval (5 turns)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
