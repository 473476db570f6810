"""What ``pfusion view`` shows: decoded messages in, a bounded, coalesced JSON stream out.

The model keeps the *latest state per topic* (a topic is one panel's data: the global
tracks, one base's elementary tracks, one array's waterfall, one array's TMA, the
services table...). Each topic has a version that changes when a message changes it;
:meth:`ViewModel.delta` gives a page every topic whose version differs from the ones it
already has, each topic's JSON encoded once per version and shared by every page. A page
that falls behind therefore skips intermediate versions instead of queueing them: what
waits for a slow page is bounded by the number of topics, never by the message rate.

Everything kept is bounded: trails (``TRAIL`` points a track, one per ``TRAIL_DT`` s of
message time), waterfall rows (``ROWS`` per array), bearing-track series (the rows'
time window), sonar arrays (``MAX_ARRAYS``; elementary tracks only of the file's bases).
Tracks that leave the global picture drop their trail.

Shapes drawn by the page, in the deployment's East-North frame (metres; the geometry
topic carries the frame's WGS-84 origin [lat, lon, h] when the deployment sets
[radar.origin], from which the page draws its latitude/longitude graticule):
- 2-sigma ellipse of a 2x2 position covariance C: semi-axes 2 sqrt(lambda_1,2) of the
  eigenvalues of C and the major axis' angle counter-clockwise from East (closed form
  of the 2x2 symmetric eigenproblem).
- An elementary track's bistatic ellipse arc (001 [1]): the points at azimuth a around
  the receiver (clockwise from North, ``ARC_SIGMAS`` sigma of theta either side) whose
  path R_T + R_R equals the track's r_b, R_R = (r_b^2 - L^2) / (2 (r_b - u . d)), d the
  receiver->transmitter vector, L = |d|, u the unit vector of a. Drawn in the horizontal
  plane (the altitudes of tx, rx and target are left out: a plan view).
No I/O, no clock: driven by the messages' own times.
"""

from __future__ import annotations

import json
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from common.deploy.config import Config
from common.wire.view_services import ServicesTable, Who

TRAIL = 30
TRAIL_DT = 1.0
ROWS = 240
MAX_ARRAYS = 16
ARC_SIGMAS = 2.0
ARC_POINTS = 17
ELLIPSE_SIGMAS = 2.0
POS = [0, 2]  # x, y in a global state [x vx y vy z vz] (001 [47])


def ellipses(cov: np.ndarray) -> np.ndarray:
    """(N, 3) [a, b, angle] of the ``ELLIPSE_SIGMAS`` ellipses of (N, 2, 2) covariances:
    a >= b semi-axes (m), angle of a counter-clockwise from East (rad)."""
    cov = np.asarray(cov, dtype=float).reshape(-1, 2, 2)
    p00, p11, p01 = cov[:, 0, 0], cov[:, 1, 1], 0.5 * (cov[:, 0, 1] + cov[:, 1, 0])
    mean = 0.5 * (p00 + p11)
    rad = np.hypot(0.5 * (p00 - p11), p01)
    lam = np.maximum(np.stack([mean + rad, mean - rad], axis=1), 0.0)
    angle = 0.5 * np.arctan2(2.0 * p01, p00 - p11)
    return np.column_stack([ELLIPSE_SIGMAS * np.sqrt(lam), angle])


def bistatic_arc(rb: float, theta: float, sigma_theta: float, tx: np.ndarray,
                 rx: np.ndarray) -> list[list[float]]:
    """Points [x, y] of the ellipse R_T + R_R = rb (001 [1]) at azimuths theta +-
    ARC_SIGMAS sigma_theta seen from the receiver (empty where rb <= L: no ellipse)."""
    d = np.asarray(tx, dtype=float)[:2] - np.asarray(rx, dtype=float)[:2]
    length = float(np.hypot(*d))
    if rb <= length:
        return []
    half = min(np.pi, ARC_SIGMAS * max(sigma_theta, 1e-3))
    az = theta + np.linspace(-half, half, ARC_POINTS)
    u = np.column_stack([np.sin(az), np.cos(az)])  # clockwise from North (+y)
    r = (rb**2 - length**2) / (2.0 * (rb - u @ d))
    pts = np.asarray(rx, dtype=float)[:2] + r[:, None] * u
    return _round(pts)


def _round(a: Any, nd: int = 1) -> Any:
    """Rounded nested lists; non-finite values become None (JSON null: NaN and
    Infinity are not JSON, and one would make the page drop the whole message)."""
    r = np.round(np.asarray(a, dtype=float), nd)
    if np.isfinite(r).all():
        return r.tolist()
    out = r.astype(object)
    out[~np.isfinite(r)] = None
    return out.tolist()


@dataclass
class _Topic:
    version: int = 0
    state: Any = None
    encoded: tuple[int, str] | None = None

    def set(self, state: Any) -> None:
        self.state = state
        self.version += 1

    def json(self) -> str:
        if self.encoded is None or self.encoded[0] != self.version:
            self.encoded = (self.version, json.dumps(self.state, separators=(",", ":")))
        return self.encoded[1]


@dataclass
class _Track:
    """What the view remembers of a global track between messages."""

    trail: deque[list[int]] = field(default_factory=lambda: deque(maxlen=TRAIL))  # [x, y] m
    trail_t: float = -np.inf
    seen: int = 0


@dataclass
class _Array:
    """One sonar array: waterfall rows, bearing-track series, own-ship trail."""

    rows: deque[list[Any]] = field(default_factory=lambda: deque(maxlen=ROWS))
    series: dict[int, deque[list[float]]] = field(default_factory=dict)
    own: deque[list[float]] = field(default_factory=lambda: deque(maxlen=ROWS))


class ViewModel:
    """Latest state per topic of one deployment; :meth:`ingest` decoded messages,
    :meth:`delta` for each page."""

    def __init__(self, cfg: Config) -> None:
        self.cfg = cfg
        self.topics: dict[str, _Topic] = {}
        self._tracks: dict[int, _Track] = {}
        self._arrays: dict[str, _Array] = {}
        self._services = ServicesTable()
        self._link: bool | None = None
        self._topic("geometry").set({
            "root": cfg.zenoh.root,
            "bases": [{"id": b.id, "tx": _round(b.tx[:2]), "rx": _round(b.rx[:2])}
                      for b in cfg.bases],
            "arrays": [a.id for a in cfg.arrays],
            "origin": None if cfg.origin is None else [cfg.origin.lat0, cfg.origin.lon0, cfg.origin.h0],
        })

    def _topic(self, name: str) -> _Topic:
        t = self.topics.get(name)
        if t is None:
            t = self.topics[name] = _Topic()
        return t

    def ingest(self, kind: str, msg: dict[str, Any]) -> None:
        """Take one decoded message (``common.wire.protocol.decode``) of ``kind``; kinds
        the view does not draw are ignored. Raises ValueError for a message it cannot
        place (elementary tracks of a base the deployment does not have)."""
        handler = getattr(self, f"_on_{kind}", None)
        if handler is not None:
            handler(msg)

    def _on_gtracks(self, msg: dict[str, Any]) -> None:
        t, tracks = float(msg["t"]), msg["tracks"]
        ids = [int(k["id"]) for k in tracks]
        for old in set(self._tracks) - set(ids):
            del self._tracks[old]
        out = []
        if tracks:  # rounded once per message: the page draws metres, not millimetres
            xa = np.array([k["x"] for k in tracks], dtype=float)
            P = np.array([k["P"] for k in tracks], dtype=float).reshape(-1, 6, 6)
            x, ell = _round(xa), _round(ellipses(P[:, POS][:, :, POS]), 3)
            sig = _round(np.sqrt(np.maximum(np.diagonal(P, axis1=1, axis2=2), 0.0)), 2)
            xy = xa[:, POS]
            finite = np.isfinite(xy).all(axis=1)  # a non-finite position leaves no trail point
            xy = np.clip(np.where(finite[:, None], xy, 0.0), -1e12, 1e12)
            trail_xy = np.rint(xy).astype(np.int64).tolist()
        for i, k in enumerate(tracks):
            mem = self._tracks.setdefault(ids[i], _Track())
            mem.seen += 1
            if t >= mem.trail_t + TRAIL_DT and finite[i]:
                mem.trail.append(trail_xy[i])
                mem.trail_t = t
            out.append({
                "id": ids[i], "status": k["status"], "amb": bool(k["ambiguous"]),
                "x": x[i], "sig": sig[i], "ell": ell[i], "score": round(float(k["score"]), 2),
                "et": [[b, int(e)] for b, e in k["etracks"]],
                "n": mem.seen, "trail": list(mem.trail),
            })
        self._topic("gtracks").set({"t": t, "tracks": out})

    def _on_etracks(self, msg: dict[str, Any]) -> None:
        base = self.cfg.base(msg["base"])  # ConfigError (a ValueError): a base not in the file
        arcs = []
        for k in msg["tracks"]:
            xk = np.asarray(k["x"], dtype=float)
            n = xk.size  # 3 at a range-Doppler base: no theta, the whole ellipse
            P = np.asarray(k["P"], dtype=float).reshape(n, n)
            theta, sigma = (float(xk[3]), float(np.sqrt(max(P[3, 3], 0.0)))) if n == 5 else (0.0, np.pi)
            pts = bistatic_arc(float(xk[0]), theta, sigma, base.tx, base.rx)
            if pts:
                arcs.append({"id": int(k["id"]), "status": k["status"],
                             "amb": bool(k["ambiguous"]), "pts": pts})
        self._topic(f"etracks/{base.id}").set({"t": float(msg["t"]), "arcs": arcs})

    def _on_truth_radar(self, msg: dict[str, Any]) -> None:
        self._topic("truth_radar").set({"t": float(msg["t"]), "id": msg["id"].tolist(),
                                        "x": _round(msg["x"]), "y": _round(msg["y"])})

    def _array(self, array: str) -> _Array:
        a = self._arrays.get(array)
        if a is None:
            if len(self._arrays) >= MAX_ARRAYS:
                raise ValueError(f"array '{array}': the view already shows {MAX_ARRAYS} arrays")
            a = self._arrays[array] = _Array()
        return a

    def _on_detections(self, msg: dict[str, Any]) -> None:
        a, t = self._array(msg["array"]), float(msg["t"])
        a.rows.append([t, _round(np.degrees(msg["brg"]))])
        a.own.append([round(float(msg["own"]["x"]), 1), round(float(msg["own"]["y"]), 1)])
        self._waterfall(msg["array"], a)

    def _on_btracks(self, msg: dict[str, Any]) -> None:
        a, t = self._array(msg["array"]), float(msg["t"])
        for k in msg["tracks"]:
            s = a.series.setdefault(int(k["id"]), deque(maxlen=ROWS))
            s.append([t, round(float(np.degrees(k["x"][0])), 2), int(k["status"] == "confirmed")])
        self._waterfall(msg["array"], a)

    def _waterfall(self, array: str, a: _Array) -> None:
        """Drop bearing-track series older than the waterfall's window."""
        since = a.rows[0][0] if a.rows else -np.inf
        for tid in [i for i, s in a.series.items() if s[-1][0] < since]:
            del a.series[tid]
        self._topic(f"waterfall/{array}").set({
            "rows": list(a.rows),
            "tracks": {str(i): [p for p in s if p[0] >= since] for i, s in a.series.items()},
        })

    def _on_tma(self, msg: dict[str, Any]) -> None:
        a, sols = self._array(msg["array"]), msg["solutions"]
        ell: Any = ellipses(np.array([np.asarray(s["P"]).reshape(4, 4)[:2, :2] for s in sols])) \
            if sols else []
        self._topic(f"tma/{msg['array']}").set({
            "t": float(msg["t"]), "own": list(a.own),
            "sols": [{"track": int(s["track"]), "x": round(s["x"], 1), "y": round(s["y"], 1),
                      "vx": round(s["vx"], 2), "vy": round(s["vy"], 2),
                      "range": round(s["range"], 1), "course": round(float(np.degrees(s["course"])), 2),
                      "speed": round(s["speed"], 2), "constrained": bool(s["constrained"]),
                      "range_obs": bool(s.get("range_observable", True)),
                      "ell": _round(e, 3)} for s, e in zip(sols, ell)],
        })

    def _on_truth_sonar(self, msg: dict[str, Any]) -> None:
        self._array(msg["array"])
        self._topic(f"truth_sonar/{msg['array']}").set({
            "t": float(msg["t"]), "id": msg["id"].tolist(), "x": _round(msg["x"]),
            "y": _round(msg["y"]), "own": [round(msg["own"]["x"], 1), round(msg["own"]["y"], 1)]})

    def set_alive(self, live: set[Who], now: float) -> None:
        """The (service, instance) liveliness tokens present now (``now``: monotonic s)."""
        if self._services.set_alive(live, now):
            self._topic("services").set({"rows": self._services.rows(now)})

    def set_metrics(self, metrics: dict[Who, dict[str, Any]], now: float) -> None:
        """The latest counters per (service, instance) (``pfusion status``'s)."""
        if self._services.set_metrics(metrics, now):
            self._topic("services").set({"rows": self._services.rows(now)})

    def sim_status(self, msg: dict[str, Any], now: float) -> None:
        """A simulator's ``sim/status``: ``done`` means its token goes as finished."""
        if msg["state"] == "done" and self._services.sim_done():
            self._topic("services").set({"rows": self._services.rows(now)})

    def set_link(self, router: bool) -> None:
        """Whether the view's session has a router now (topic ``link``, set on change)."""
        if router != self._link:
            self._link = router
            self._topic("link").set({"router": router})

    def delta(self, sent: dict[str, int], extra: dict[str, Any] | None = None
              ) -> tuple[str | None, dict[str, int]]:
        """The JSON message ``{"topics": {name: state}, **extra}`` of every topic whose
        version is not the one in ``sent`` (None if none), and the versions it carries."""
        changed = [(n, t) for n, t in self.topics.items() if sent.get(n) != t.version]
        if not changed:
            return None, sent
        body = ",".join(f"{json.dumps(n)}:{t.json()}" for n, t in changed)
        more = "".join(f",{json.dumps(k)}:{json.dumps(v, separators=(',', ':'))}"
                       for k, v in (extra or {}).items())
        return "{\"topics\":{" + body + "}" + more + "}", sent | {n: t.version for n, t in changed}
