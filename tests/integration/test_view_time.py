"""``pfusion view``'s time controls in headless Chromium (issue 32): pause freezes the
picture while messages keep arriving, scrubbing back shows the frame that was on the
page at that time (track, trail and truth as they were), "live" returns; and the page's
history at 10 minutes of 1000 tracks stays under 500 MB (scrub latency and frame time:
benchmarks/view_frames.py)."""

from __future__ import annotations

import re
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from benchmarks.view_frames import FILL_JS, SCRUB_JS, heap_mb, load_topics
from common.bus.transport import free_port, wait_port
from common.wire import protocol
from tests.harness import ROOT, Deployment
from tests.integration.test_view import (
    CONFIRMED_RGB,
    TWO_TARGETS,
    browser,  # noqa: F401  (a fixture)
    canvas_xy,
    near,
    shot,
    wait,
)

PLAN_PNG = "return $('plan').toDataURL()"


def gtracks(t: float, x: float) -> bytes:
    """Track 1 at (x, 30 km) and track 2 fixed, at message time t."""
    P = np.diag([2500.0, 1.0, 2500.0, 1.0, 2500.0, 1.0]).ravel()
    return protocol.encode({"v": protocol.VERSION, "t": t, "tracks": [
        {"id": i, "status": "confirmed", "x": [xi, 1000.0, 30e3, 0.0, 9e3, 0.0], "P": P, "score": 1.0,
         "etracks": [["b1", i]], "ambiguous": False} for i, xi in ((1, x), (2, -20e3))]})


def truth(t: float, x: float) -> bytes:
    z = [0.0]
    return protocol.encode({"v": protocol.VERSION, "t": t, "id": [1], "x": [x], "y": [31e3], "z": z,
                            "vx": z, "vy": z, "vz": z})


def shown(driver: Any) -> dict[str, Any]:
    """What the page shows now: radar time, track 1's x and trail, truth x, timeline state."""
    return driver.execute_script(
        "const k = topics.gtracks.tracks.find((k) => k.id === 1), tr = topics.truth_radar;"
        "return {t: +$('t-radar').textContent, x: k.x[0], trail: k.trail, truth: tr ? tr.x[0] : null,"
        " state: $('tl-at').dataset.state, live_t: timeline.live().gtracks.t};")


@pytest.mark.timeout(240)
def test_pause_scrub_and_live_through_the_real_view(browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """Real router and view; 10 scans of track 1 moving 1 km a scan (and its truth 500 m
    ahead); pause, 4 more scans arrive, the plan's pixels do not change; Home on the
    slider shows the oldest frame, a seek scan 0, another scan 5 with the trail of 0-5;
    live shows the last. About 10 s."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    port = free_port()
    with Deployment(tmp_path) as d:
        d.start("view", "view", "--config", str(TWO_TARGETS), "--port", str(port))
        wait_port(port, 60)
        on_page: dict[int, float] = {}  # scan -> a page time (s) when the page showed it

        def scan(k: int) -> None:  # one scan, on the page before the next
            d.session.put(f"{ROOT}/sim/truth/radar", truth(10.0 + k, 1000.0 * k + 500.0))
            d.session.put(f"{ROOT}/radar/gtracks", gtracks(10.0 + k, 1000.0 * k))
            wait(f"scan {k} on the page", lambda: browser.execute_script(
                "return timeline.live().gtracks && timeline.live().gtracks.t === arguments[0] && "
                "timeline.live().truth_radar && timeline.live().truth_radar.t === arguments[0]", 10.0 + k), 30)
            on_page[k] = browser.execute_script("return (performance.timeOrigin + performance.now()) / 1000")
            time.sleep(0.15)

        browser.get(f"http://127.0.0.1:{port}/")
        wait("the page's socket", lambda: browser.execute_script("return wsOpen"), 30)
        for k in range(10):
            scan(k)
        now = shown(browser)
        assert (now["t"], now["x"], now["truth"], now["state"]) == (19.0, 9000.0, 9500.0, "live"), now

        browser.find_element(By.ID, "tl-pause").click()
        frozen = browser.execute_script(PLAN_PNG)
        for k in range(10, 14):
            scan(k)
        now = shown(browser)
        assert (now["t"], now["x"], now["state"], now["live_t"]) == (19.0, 9000.0, "paused", 23.0), now
        assert browser.execute_script(PLAN_PNG) == frozen, "the plan changed while paused"

        # Home: the oldest frame (scan 0's track and truth, or one of them: the two may
        # reach the page one message apart); then the page time when scan 0 was shown
        browser.find_element(By.ID, "tl-scrub").send_keys(Keys.HOME)
        wait("the oldest frame shown", lambda: browser.execute_script(
            "return +$('tl-at').dataset.t === timeline.times()[0]"), 10)
        assert browser.execute_script(  # scan 0's track, truth or both
            "const g = topics.gtracks, r = topics.truth_radar;"
            "return (g || r) && (!g || g.t === 10) && (!r || r.t === 10)")
        assert browser.execute_script("return timeline.lastMs") < 1000.0  # answers (the goal: view_frames.py)
        browser.execute_script("timeline.seek(arguments[0])", on_page[0])
        first = shown(browser)
        assert (first["t"], first["x"], first["truth"], first["trail"]) == (10.0, 0.0, 500.0, [[0, 30000]]), first

        ms = browser.execute_script("return timeline.seek(arguments[0])", on_page[5])
        sixth = shown(browser)
        assert (sixth["t"], sixth["x"], sixth["truth"]) == (15.0, 5000.0, 5500.0), sixth
        assert sixth["trail"] == [[1000 * k, 30000] for k in range(6)], sixth["trail"]
        assert ms < 1000.0, ms
        img = shot(browser, "view-scrubbed")
        assert near(img, canvas_xy(browser, 5000.0, 30e3), CONFIRMED_RGB), "scan 5's track not drawn"
        label = browser.find_element(By.ID, "tl-at").text
        assert re.fullmatch(r"paused at \d\d:\d\d:\d\d UTC \(-\d+ s\)", label), label

        browser.find_element(By.ID, "tl-live").click()
        now = shown(browser)
        assert (now["t"], now["x"], now["truth"], now["state"]) == (23.0, 13000.0, 13500.0, "live"), now
        scan(14)
        assert shown(browser)["x"] == 14000.0  # live again: new scans are drawn


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_ten_minutes_of_1000_tracks_fit_and_scrub_fast(browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """600 frames (10 minutes at 1 Hz) of 1000 tracks with ellipses and truth, 3 bases'
    elementary-track arcs and 100 sonar tracks, made by the real view model and recorded
    by the page's own path (``timeline.take``, as benchmarks/view_frames.py does before
    its run): the page's memory (JS heap and array buffers) stays under 500 MB, the history
    spans the 10 minutes, and a scrub to any frame (rebuild, trails, draw) answers within
    2 s here (the 200 ms goal is benchmarks/view_frames.py's: wall times on this shared
    machine are no test). About 10-20 s."""
    port = free_port()
    topics = load_topics(1000, 100, 3)
    with Deployment(tmp_path) as d:
        d.start("view", "view", "--config", str(TWO_TARGETS), "--port", str(port))
        wait_port(port, 60)
        browser.get(f"http://127.0.0.1:{port}/")
        wait("the page's socket", lambda: browser.execute_script("return wsOpen"), 30)
        browser.execute_script("$('layer-arcs').checked = true;")
        browser.execute_script(FILL_JS, topics, 600, 1.0)
        mb = heap_mb(browser)
        span, n = browser.execute_script("const ts = timeline.times(); return [ts[ts.length - 1] - ts[0], ts.length]")
        assert n == 600 and span == pytest.approx(599.0, abs=1.0), (n, span)
        assert mb <= 500.0, mb
        ms = browser.execute_script(SCRUB_JS, 12)
        print(f"10 min of 1000 tracks: page memory {mb:.0f} MB, scrub ms {sorted(round(m) for m in ms)}")
        assert max(ms) <= 2000.0, ms
        first = browser.execute_script("timeline.seek(0); return [topics.gtracks.t, topics.gtracks.tracks.length, "
                                       "topics['etracks/b1'].arcs.length, $('tl-at').dataset.state]")
        assert first == [topics["gtracks"]["t"] - 600.0, 1000, 1000, "paused"], first
