"""The demo's pictures (matplotlib, headless Agg): a radar plan view and a sonar
bearing-time waterfall with the TMA solutions on a plan view."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402

from common.deploy.config import Config  # noqa: E402
from common.radar.geometry.bistatic import ellipse_points  # noqa: E402

Msg = dict[str, Any]
SIZE_IN = (12.0, 8.0)
DPI = 100
KM = 1e-3


def covariance_ellipse(mean: np.ndarray, cov: np.ndarray, nsig: float, **kw: Any) -> Ellipse:
    """The nsig-sigma ellipse of a 2x2 covariance (km units in, km units out)."""
    w, v = np.linalg.eigh(cov)
    w = np.clip(w, 0.0, None)
    angle = np.degrees(np.arctan2(v[1, 1], v[0, 1]))
    return Ellipse(tuple(mean), 2 * nsig * np.sqrt(w[1]), 2 * nsig * np.sqrt(w[0]),
                   angle=angle, fill=False, **kw)


def _truth_paths(truth: list[Msg]) -> dict[int, np.ndarray]:
    paths: dict[int, list[tuple[float, float]]] = {}
    for m in truth:
        for i, x, y in zip(m["id"], m["x"], m["y"]):
            paths.setdefault(int(i), []).append((x, y))
    return {i: np.asarray(p) for i, p in paths.items()}


def radar_picture(cfg: Config, truth: list[Msg], gtracks: list[Msg], path: Path) -> None:
    """Plan view: receiver, transmitters, bistatic ellipses of one instant, true
    trajectories, global tracks with numbers and 2-sigma covariance ellipses."""
    fig, ax = plt.subplots(figsize=SIZE_IN, dpi=DPI)
    rx = cfg.bases[0].rx
    ax.plot(rx[0] * KM, rx[1] * KM, "k^", ms=10, label="receiver")
    for b in cfg.bases:
        ax.plot(b.tx[0] * KM, b.tx[1] * KM, "r*", ms=12)
        ax.annotate(b.id, (b.tx[0] * KM, b.tx[1] * KM), textcoords="offset points", xytext=(5, 5))
    mid = truth[len(truth) // 2] if truth else None
    if mid is not None and len(mid["id"]):
        p = np.array([mid["x"][0], mid["y"][0], mid["z"][0]])
        for b in cfg.bases:
            rb = np.linalg.norm(p - b.tx) + np.linalg.norm(p - b.rx)
            e = ellipse_points(rb, b.tx, b.rx)
            ax.plot(e[:, 0] * KM, e[:, 1] * KM, ":", lw=0.8, color="gray")
    for i, p in _truth_paths(truth).items():
        ax.plot(p[:, 0] * KM, p[:, 1] * KM, "-", color="green", lw=2, alpha=0.5,
                label="truth" if i == min(_truth_paths(truth)) else None)
    tracks: dict[int, list[np.ndarray]] = {}
    last: dict[int, Msg] = {}
    for m in gtracks:
        for tr in m["tracks"]:
            if tr["status"] == "confirmed":
                tracks.setdefault(tr["id"], []).append(np.asarray(tr["x"]))
                last[tr["id"]] = tr
    for gid, xs in tracks.items():
        a = np.asarray(xs)
        ax.plot(a[:, 0] * KM, a[:, 2] * KM, "b-", lw=1)
        P = np.asarray(last[gid]["P"]).reshape(6, 6)[np.ix_([0, 2], [0, 2])] * KM**2
        ax.add_patch(covariance_ellipse(a[-1, [0, 2]] * KM, P, 2.0, color="blue"))
        ax.annotate(f"G{gid}", (a[-1, 0] * KM, a[-1, 2] * KM), color="blue",
                    textcoords="offset points", xytext=(6, -10))
    ax.plot([], [], "b-", label="global tracks (2-sigma)")
    pts = np.vstack([rx[:2], *[b.tx[:2] for b in cfg.bases],
                     *[p[:, :2] for p in _truth_paths(truth).values()]]) * KM
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.1 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_xlabel("East (km)")
    ax.set_ylabel("North (km)")
    ax.set_aspect("equal", adjustable="box")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right")
    ax.set_title("Multistatic passive radar: plan view")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def sonar_picture(detections: list[Msg], btracks: list[Msg], truth: list[Msg],
                  tma: list[Msg], path: Path) -> None:
    """Left: bearing-time waterfall of detections with bearing tracks. Right: own-ship
    track, true targets and the last TMA solution of each track on a plan view."""
    fig, (wf, pv) = plt.subplots(1, 2, figsize=SIZE_IN, dpi=DPI)
    t_det = np.concatenate([np.full(len(m["brg"]), m["t"]) for m in detections] or [[]])
    b_det = np.concatenate([m["brg"] for m in detections] or [[]])
    wf.scatter(np.degrees(b_det), t_det / 60.0, s=2, c="gray", alpha=0.5, label="detections")
    series: dict[int, list[tuple[float, float]]] = {}
    for m in btracks:
        for tr in m["tracks"]:
            if tr["status"] == "confirmed":
                series.setdefault(tr["id"], []).append((m["t"], tr["x"][0]))
    for tid, s in series.items():
        a = np.asarray(s)
        brg = np.degrees(a[:, 1])
        brg[np.abs(np.diff(brg, prepend=brg[0])) > 180] = np.nan
        wf.plot(brg, a[:, 0] / 60.0, "-", lw=1.5)
        wf.annotate(f"T{tid}", (np.degrees(a[-1, 1]), a[-1, 0] / 60.0))
    wf.set_xlim(0, 360)  # time upwards: newest at the top, as on the live view's waterfall
    wf.set_xlabel("true bearing (deg)")
    wf.set_ylabel("time (min), newest at top")
    wf.set_title("Bearing-time waterfall")
    own = np.array([[m["own"]["x"], m["own"]["y"]] for m in truth]) if truth else np.zeros((0, 2))
    if len(own):
        pv.plot(own[:, 0] * KM, own[:, 1] * KM, "k-", lw=2, label="own ship")
    for i, p in _truth_paths(truth).items():
        pv.plot(p[:, 0] * KM, p[:, 1] * KM, "-", color="green", alpha=0.6,
                label="truth" if i == min(_truth_paths(truth)) else None)
    final: dict[int, Msg] = {}
    for m in tma:
        for s in m["solutions"]:
            final[s["track"]] = s
    for tid, s in final.items():
        xy = np.array([s["x"], s["y"]]) * KM
        P = np.asarray(s["P"]).reshape(4, 4)[:2, :2] * KM**2
        pv.plot(*xy, "bo", ms=4)
        pv.arrow(xy[0], xy[1], s["vx"] * 600 * KM, s["vy"] * 600 * KM, color="blue", width=0.02)
        pv.add_patch(covariance_ellipse(xy, P, 2.0, color="blue"))
        pv.annotate(f"T{tid} {s['range'] * KM:.1f} km {np.degrees(s['course']):.0f}deg "
                    f"{s['speed'] / 0.514444:.1f} kn", xy, fontsize=8, color="blue",
                    textcoords="offset points", xytext=(6, 4))
    pv.plot([], [], "bo-", label="TMA (2-sigma, 10 min velocity)")
    pv.set_aspect("equal", adjustable="datalim")
    pv.grid(True, alpha=0.3)
    pv.set_xlabel("East (km)")
    pv.set_ylabel("North (km)")
    pv.set_title("Target motion analysis")
    pv.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
