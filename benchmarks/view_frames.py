"""View frame-time benchmark (issue 32): the page's own frame time, memory and input
rate at 1000 radar tracks at 1 Hz plus 100 sonar tracks, all layers on, measured in
headless Chromium (Debian's ``chromium`` and ``chromium-driver``, under Selenium).

A real ``pfusion router`` and ``pfusion view`` (``scenarios/two_targets.toml``: 3 bases)
run on loopback; this process publishes every second, over the router, ``radar/gtracks``
(1000 tracks on straight lines), ``radar/etracks/<b>`` for the 3 bases (1000 each: the
elementary-track arcs), ``sim/truth/radar`` (1000), and for array a1
``sonar/detections``, ``sonar/btracks``, ``sonar/tma`` and ``sim/truth/sonar`` (100
each). The page shows all layers (trails, ellipses, arcs, truth) and a selected track.

Before the run the page's history is filled with ``--history`` s of frames (1 per s)
made by the real view model from the same messages, so that the run is that of a page
open for 10 minutes; after it, ``--scrubs`` seeks to random times of the history.

Measured in the page: frame time (each WebSocket message: parse, record, draw, by
performance.now() in view.js, ``timeline.drawTimes``), the gaps between animation frames
(requestAnimationFrame, a script started here: a long gap is a page that froze), page memory
after a garbage collection (CDP ``Runtime.getHeapUsage``: heap and array buffers; the
renderer processes' Pss is printed beside it), scrub latency (seek and draw).
WebSocket bytes/s from the view's ``/stats``.

Goals (exit code 1 otherwise): frame time p99 <= 50 ms and max <= 250 ms, animation
frame gaps max <= 250 ms, page memory <= 500 MB, scrub max <= 200 ms.

Run: .venv/bin/python benchmarks/view_frames.py [--tracks 1000] [--sonar 100] [--seconds 60]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from common.bus.procs import Child, start_router
from common.bus.transport import free_port, open_session, wait_port
from common.core.angles import wrap_2pi
from common.deploy.config import ZenohConfig, load
from common.wire import protocol
from common.wire.view_model import ViewModel

ROOT = "pf/v1"
CONFIG = Path(__file__).resolve().parents[1] / "scenarios" / "two_targets.toml"
T0 = 1000.0  # message time of the first published second
GOALS = {"frame_p99": 50.0, "frame_max": 250.0, "gap_max": 250.0, "heap_mb": 500.0, "scrub_max": 200.0}

# Fills the page's history: arguments[0] the view model's topics at time T, [1] frames,
# [2] s between frames; frame i at page time now - (n - i) dt shows T - (n - i) dt, the
# tracks moved back along their velocity. Returns the ms it took.
FILL_JS = """
const [tpl, n, dt] = arguments, now = (performance.timeOrigin + performance.now()) / 1000;
const t1 = performance.now();
for (let i = 0; i < n; i++) {
  const s = (i - n) * dt, f = {};
  Object.entries(tpl).forEach(([name, st]) => {
    if (name === 'gtracks') f[name] = { t: st.t + s, tracks: st.tracks.map((k) => ({ ...k,
      x: [k.x[0] + k.x[1] * s, k.x[1], k.x[2] + k.x[3] * s, k.x[3], k.x[4], k.x[5]] })) };
    else if (name === 'truth_radar') f[name] = { ...st, t: st.t + s, x: st.x.map((v) => v + 100 * s) };
    else if (name.startsWith('etracks/')) f[name] = { ...st, t: st.t + s };
    else if (name.startsWith('waterfall/')) {
      const last = st.rows[st.rows.length - 1];
      f[name] = { rows: [[last[0] + s, last[1]]], tracks: Object.fromEntries(Object.entries(st.tracks)
        .map(([id, p]) => [id, [[p[p.length - 1][0] + s, p[p.length - 1][1], p[p.length - 1][2]]]])) };
    } else if (/^(tma|truth_sonar)\\//.test(name)) f[name] = structuredClone(st);
  });
  timeline.take(f, now + s); timeline.settle();
}
return performance.now() - t1;
"""

# Seeks to arguments[0] random page times of the history; the ms of each, then live.
SCRUB_JS = """
const ts = timeline.times(), out = [];
for (let i = 0; i < arguments[0]; i++) out.push(timeline.seek(ts[0] + Math.random() * (ts[ts.length - 1] - ts[0])));
timeline.goLive();
return out;
"""

# Where a frame's time goes, on the live state: parse and record (median of 5), and the
# draw split by the page's functions (each wrapped, mean ms over 5 renders; render()
# without argument draws every panel, as when every topic changed).
BREAKDOWN_JS = """
const text = JSON.stringify({ topics: timeline.live() }), out = { kB: text.length / 1e3 };
const median = (f) => { const ms = []; for (let i = 0; i < 5; i++) { const t = performance.now(); f();
  ms.push(performance.now() - t); } return ms.sort((a, b) => a - b)[2]; };
out.parse = median(() => JSON.parse(text));
out.record = median(() => { timeline.take(JSON.parse(text).topics); timeline.settle(); }) - out.parse;
const fns = ['drawPlan', 'grid', 'crosses', 'drawTracks', 'trackTable', 'waterfall', 'tmaPlan', 'sonarTable',
  'services', 'details', 'tick']
  .filter((f) => typeof window[f] === 'function'), acc = {};
const orig = Object.fromEntries(fns.map((f) => [f, window[f]]));
fns.forEach((f) => { acc[f] = 0; window[f] = function (...a) {
  const t = performance.now();
  try { return orig[f].apply(this, a); } finally { acc[f] += performance.now() - t; } }; });
let total = 0;
for (let i = 0; i < 5; i++) { const t = performance.now(); render(); total += performance.now() - t; }
fns.forEach((f) => { window[f] = orig[f]; out[f] = acc[f] / 5; });
out.render = total / 5;
return out;
"""

GAPS_JS = """
window.gaps = []; let last = performance.now();
const loop = (t) => { gaps.push(t - last); last = t; requestAnimationFrame(loop); };
requestAnimationFrame(loop); timeline.drawTimes();
"""


class Scene:
    """n radar targets on straight lines (150-250 m/s, 9 km up), m sonar contacts."""

    def __init__(self, n: int, m: int, seed: int = 1) -> None:
        rng = np.random.default_rng(seed)
        self.cfg = load(CONFIG)
        self.p0 = rng.uniform(-8e4, 8e4, (n, 2))
        heading, speed = rng.uniform(0, 2 * np.pi, n), rng.uniform(150, 250, n)
        self.v = np.column_stack([speed * np.sin(heading), speed * np.cos(heading)])
        self.status = rng.choice(["confirmed", "tentative", "coasting"], n, p=[0.9, 0.05, 0.05])
        self.amb = rng.random(n) < 0.02
        self.brg0, self.rate = rng.uniform(0, 2 * np.pi, m), rng.uniform(-5e-3, 5e-3, m)
        self.rng0, self.cv = rng.uniform(3e3, 3e4, m), rng.uniform(-5.0, 5.0, (m, 2))

    def messages(self, t: float) -> list[tuple[str, dict[str, Any]]]:
        """Every key's message of second t (key suffix under the root, message)."""
        v, dt = {"v": protocol.VERSION, "t": t}, t - T0
        p = self.p0 + self.v * dt
        P = np.diag([2500.0, 4.0, 2500.0, 4.0, 1e6, 1.0]).ravel()
        out: list[tuple[str, dict[str, Any]]] = [("radar/gtracks", {**v, "tracks": [
            {"id": i, "status": str(self.status[i]), "x": [p[i, 0], self.v[i, 0], p[i, 1], self.v[i, 1], 9e3, 0.0],
             "P": P, "score": 10.0, "etracks": [[b.id, i] for b in self.cfg.bases], "ambiguous": bool(self.amb[i])}
            for i in range(len(p))]})]
        Pe = np.diag([400.0, 4.0, 1e-4, np.radians(0.5) ** 2, 1e-6]).ravel()
        for b in self.cfg.bases:
            rb = np.hypot(*(p - b.tx[:2]).T) + np.hypot(*(p - b.rx[:2]).T)
            theta = np.arctan2(p[:, 0] - b.rx[0], p[:, 1] - b.rx[1])
            out.append((f"radar/etracks/{b.id}", {**v, "base": b.id, "tracks": [
                {"id": i, "status": "confirmed", "x": [rb[i], 0.0, 0.0, theta[i], 0.0], "P": Pe, "score": 5.0,
                 "n_ch": 3, "updated": True, "ambiguous": False} for i in range(len(p))]}))
        z = np.zeros(len(p))
        out.append(("sim/truth/radar", {**v, "id": np.arange(len(p)), "x": p[:, 0] + 100.0, "y": p[:, 1],
                                        "z": z + 9e3, "vx": self.v[:, 0], "vy": self.v[:, 1], "vz": z}))
        return out + self.sonar(t, v)

    def sonar(self, t: float, v: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
        m, dt = len(self.brg0), t - T0
        brg = np.asarray(wrap_2pi(self.brg0 + self.rate * dt))
        own = {"x": 3.0 * dt, "y": 0.0, "heading": np.pi / 2, "speed": 3.0}
        x, y = own["x"] + self.rng0 * np.sin(brg), self.rng0 * np.cos(brg)
        sol = {"t": t, "P": np.diag([1e5, 4e4, 1.0, 1.0]).ravel(), "constrained": False,
               "bounds": [100.0, 1e5, 0.0, 0.0, 0.0, 20.0],
               "bounds_modified": False, "phase": "post", "residual_factor": 1.0, "legs": [0.0]}
        return [
            ("sonar/detections/a1", {**v, "seq": int(t), "array": "a1", "own": own, "brg": brg,
                                     "amp": np.full(m, 70.0)}),
            ("sonar/btracks/a1", {**v, "array": "a1", "tracks": [
                {"id": k, "status": "confirmed", "x": [brg[k], self.rate[k], 70.0, 0.0],
                 "P": [1e-4, 0, 0, 0] * 4, "quality": 1.0, "ambiguous": False} for k in range(m)]}),
            ("sonar/tma/a1", {**v, "array": "a1", "solutions": [
                {**sol, "track": k, "x": x[k], "y": y[k], "range": self.rng0[k], "vx": self.cv[k, 0],
                 "vy": self.cv[k, 1], "course": float(wrap_2pi(np.arctan2(*self.cv[k]))),
                 "speed": float(np.hypot(*self.cv[k]))} for k in range(m)]}),
            ("sim/truth/sonar", {**v, "array": "a1", "own": own, "id": np.arange(m), "x": x, "y": y,
                                 "vx": np.zeros(m), "vy": np.zeros(m), "brg": brg}),
        ]


def load_topics(n: int, m: int, seconds: int = 30) -> dict[str, Any]:
    """The topics the real view model makes of ``seconds`` s of the scene (a full
    waterfall needs its scans), as the page receives them (parsed JSON)."""
    scene, model = Scene(n, m), ViewModel(load(CONFIG))
    for k in range(seconds):
        for key, msg in scene.messages(T0 - seconds + k + 1):
            kind = protocol.kind_of(f"{ROOT}/{key}", ROOT)
            assert kind is not None
            model.ingest(kind, protocol.decode(kind, protocol.encode(msg)))
    return {name: json.loads(t.json()) for name, t in model.topics.items()
            if name not in ("geometry", "services", "link")}


def heap_mb(driver: Any) -> float:
    """The page's JS memory after a garbage collection (MB): the heap in use plus the
    array buffers' backing stores (typed arrays live outside the heap)."""
    driver.execute_cdp_cmd("HeapProfiler.collectGarbage", {})
    u = driver.execute_cdp_cmd("Runtime.getHeapUsage", {})
    return float(u["usedSize"] + u.get("embedderHeapUsedSize", 0) + u.get("backingStorageSize", 0)) / 1e6


def renderer_mb(driver: Any) -> float:
    """Proportional resident memory (MB, Pss: shared pages split among their users) of
    the browser's renderer processes (the pages)."""
    parent: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
    mine, todo = set(), [driver.service.process.pid]
    while todo:
        pid = todo.pop()
        mine.add(pid)
        todo += [c for c, p in parent.items() if p == pid and c not in mine]
    kb = 0
    for pid in mine:
        try:
            if b"--type=renderer" in Path(f"/proc/{pid}/cmdline").read_bytes():
                kb += next(int(line.split()[1]) for line in Path(f"/proc/{pid}/smaps_rollup").read_text()
                           .splitlines() if line.startswith("Pss:"))
        except (OSError, StopIteration):
            continue
    return kb / 1e3


@contextmanager
def chromium() -> Iterator[Any]:
    """Headless Chromium under Selenium with the system chromedriver."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    browser, driver = shutil.which("chromium"), shutil.which("chromedriver")
    if not (browser and driver):
        raise SystemExit("view_frames: needs chromium and chromium-driver (apt-get install chromium chromium-driver)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = browser
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1200", "--force-device-scale-factor=1"):
        opts.add_argument(arg)
    d = webdriver.Chrome(service=Service(executable_path=driver), options=opts)
    d.set_script_timeout(300)
    try:
        yield d
    finally:
        d.quit()


def view_stats(port: int) -> dict[str, Any]:
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/stats", timeout=10) as r:
        return json.loads(r.read())


def publish(session: Any, scene: Scene, seconds: int, stop: threading.Event) -> None:
    """One second of every key each second (message times T0, T0 + 1, ...)."""
    import zenoh

    wall0 = time.monotonic()
    for k in range(seconds):
        if stop.wait(max(0.0, wall0 + k - time.monotonic())):
            return
        for key, msg in scene.messages(T0 + k):
            session.put(f"{ROOT}/{key}", protocol.encode(msg), congestion_control=zenoh.CongestionControl.BLOCK)


def pct(v: list[float]) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=float)
    return (float(np.percentile(a, 50)), float(np.percentile(a, 99)), float(a.max())) if a.size else (np.nan,) * 3


@contextmanager
def live_view(size: tuple[int, int] | None = None) -> Iterator[tuple[Any, Any, int]]:
    """A loopback router, `pfusion view` on it and a page (window `size`) with every layer
    on, the elementary arcs included: (Zenoh session, WebDriver, the view's port)."""
    router, endpoint = start_router()
    port = free_port()
    view = Child("view", "view", "--config", str(CONFIG), "--connect", endpoint, "--port", str(port))
    try:
        wait_port(port, 60)
        with open_session(ZenohConfig([endpoint], [], ROOT)) as session, chromium() as d:
            if size is not None:
                d.set_window_size(*size)
            d.get(f"http://127.0.0.1:{port}/")
            while not d.execute_script("return wsOpen"):
                time.sleep(0.2)
            d.execute_script("$('layer-arcs').checked = true;")
            yield session, d, port
    finally:
        view.stop()
        router.stop()


def run(args: argparse.Namespace) -> dict[str, Any]:
    scene = Scene(args.tracks, args.sonar)
    tpl = load_topics(args.tracks, args.sonar, 10)
    stop = threading.Event()
    try:
        with live_view() as (session, d, port):
            fill_ms = d.execute_script(FILL_JS, tpl, args.history, 1.0)
            filled_mb = heap_mb(d)
            feed = threading.Thread(target=publish, args=(session, scene, args.seconds + 30, stop))
            feed.start()
            while not d.execute_script("return !!topics.gtracks && topics.gtracks.t >= arguments[0]", T0):
                time.sleep(0.2)
            d.execute_script("select(topics.gtracks.tracks[0].id);" + GAPS_JS)
            s0, w0 = view_stats(port), time.monotonic()
            time.sleep(args.seconds)
            gaps, frames = d.execute_script("return [gaps.splice(0), timeline.drawTimes()]")
            s1, w1 = view_stats(port), time.monotonic()
            stop.set()
            feed.join()
            state = d.execute_script("const ts = timeline.times(); "
                                     "return {n: ts.length, span: ts[ts.length - 1] - ts[0],"
                                     " bytes: timeline.bytes, tracks: timeline.live().gtracks.tracks.length}")
            run_mb, rss_mb = heap_mb(d), renderer_mb(d)
            scrubs = d.execute_script(SCRUB_JS, args.scrubs)
            parts = d.execute_script(BREAKDOWN_JS)
    finally:
        stop.set()
    return {"fill_s": fill_ms / 1e3, "filled_mb": filled_mb, "heap_mb": max(filled_mb, run_mb), "run_mb": run_mb,
            "rss_mb": rss_mb, "gaps": gaps, "frames": frames, "scrubs": scrubs, "parts": parts,
            "load": os.getloadavg(), "state": state, "wall": w1 - w0,
            "bytes_s": (s1.get("bytes", 0) - s0.get("bytes", 0)) / (w1 - w0),
            "msgs_s": (s1.get("messages", 0) - s0.get("messages", 0)) / (w1 - w0)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tracks", type=int, default=1000, help="radar tracks (and truth, and per base etracks)")
    ap.add_argument("--sonar", type=int, default=100, help="sonar tracks of array a1")
    ap.add_argument("--seconds", type=int, default=60, help="measured seconds of live data")
    ap.add_argument("--history", type=int, default=600, help="frames (1 per s) in the page's history first")
    ap.add_argument("--scrubs", type=int, default=30, help="seeks to random times after the run")
    args = ap.parse_args()
    r = run(args)
    f, g, s = pct(r["frames"]), pct(r["gaps"]), pct(r["scrubs"])
    st = r["state"]
    print(f"view_frames: {args.tracks} radar tracks at 1 Hz (+ {args.tracks} truth, 3 x {args.tracks} etracks), "
          f"{args.sonar} sonar tracks, all layers on, {r['wall']:.0f} s; history filled with {args.history} frames "
          f"in {r['fill_s']:.1f} s")
    print(f"{'measure':<34} {'n':>6} {'p50':>8} {'p99':>8} {'max':>8}  goal")
    print(f"{'frame time ms (parse+record+draw)':<34} {len(r['frames']):>6} {f[0]:>8.1f} {f[1]:>8.1f} {f[2]:>8.1f}"
          f"  p99 <= {GOALS['frame_p99']:g}, max <= {GOALS['frame_max']:g}")
    print(f"{'animation frame gap ms':<34} {len(r['gaps']):>6} {g[0]:>8.1f} {g[1]:>8.1f} {g[2]:>8.1f}"
          f"  max <= {GOALS['gap_max']:g} ({sum(v > GOALS['gap_max'] for v in r['gaps'])} longer)")
    print(f"{'scrub ms (seek + draw)':<34} {len(r['scrubs']):>6} {s[0]:>8.1f} {s[1]:>8.1f} {s[2]:>8.1f}"
          f"  max <= {GOALS['scrub_max']:g}")
    print(f"page memory (JS heap + array buffers, after GC): {r['filled_mb']:.0f} MB after the fill, "
          f"{r['run_mb']:.0f} MB after the run (goal <= {GOALS['heap_mb']:g}); renderer Pss {r['rss_mb']:.0f} MB")
    print(f"history {st['n']} frames over {st['span'] / 60:.1f} min, "
          f"{st['bytes'] / 1e6:.0f} MB of parts; {st['tracks']} tracks live")
    print(f"WebSocket: {r['bytes_s'] / 1e6:.2f} MB/s, {r['msgs_s']:.1f} messages/s to the page")
    print(f"where a frame's time goes (the live state, {r['parts']['kB']:.0f} kB of JSON), ms: " + ", ".join(
        f"{k} {v:.1f}" for k, v in r["parts"].items() if k != "kB"))
    print("machine load average (1, 5, 15 min) at the end: " + " ".join(f"{v:.1f}" for v in r["load"]))
    fails = [k for k, ok in (("frame_p99", f[1] <= GOALS["frame_p99"]), ("frame_max", f[2] <= GOALS["frame_max"]),
                             ("gap_max", g[2] <= GOALS["gap_max"]), ("heap_mb", r["heap_mb"] <= GOALS["heap_mb"]),
                             ("scrub_max", s[2] <= GOALS["scrub_max"]), ("frames", len(r["frames"]) > 0)) if not ok]
    print("goals met" if not fails else f"GOAL FAILED: {', '.join(fails)}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
