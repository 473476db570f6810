"""Screenshots of the live view for docs/view.md, taken in headless Chromium with the
scene of ``benchmarks/view_frames.py`` (1000 radar tracks, their truth and elementary
tracks at 3 bases, and ``--sonar`` sonar tracks) published every second over a real
router to a real ``pfusion view``; the page's history is filled first (as the
benchmark does) so that it can be scrubbed back 5 minutes.

Writes, each quantised to 32 colours (small files):
- ``view-1000.png``: the whole page at 1000 tracks, all layers on;
- ``view-zoom.png``: the radar plan zoomed in on one track: 2-sigma ellipses, trails,
  elementary-track arcs of the 3 bases, truth;
- ``view-paused.png``: the header and the plan paused and scrubbed back 5 minutes;
- ``view-1000-sonar.png``: the sonar panel (waterfall, TMA plan and list).

Run: .venv/bin/python benchmarks/view_shots.py [--out docs/img] [--sonar 12]
"""

from __future__ import annotations

import argparse
import io
import sys
import threading
import time
from pathlib import Path
from typing import Any

from PIL import Image

from benchmarks.view_frames import FILL_JS, T0, Scene, live_view, load_topics, publish

OUT = Path(__file__).resolve().parents[1] / "docs" / "img"


def save(png: bytes, path: Path, crop: tuple[int, int, int, int] | None = None) -> None:
    """A PNG quantised to 32 colours, cropped to (left, top, right, bottom) if given."""
    img = Image.open(io.BytesIO(png)).convert("RGB")
    if crop:
        img = img.crop(crop)
    img.quantize(colors=32).save(path, optimize=True)
    print(f"{path}: {img.width}x{img.height}, {path.stat().st_size / 1e3:.0f} kB")


def live(d: Any) -> None:
    """Wait for the badge to say live (a loaded view may fall a few seconds behind)."""
    deadline = time.monotonic() + 60
    while d.execute_script("return $('conn').dataset.state") != "live" and time.monotonic() < deadline:
        time.sleep(0.5)


def shoot(d: Any, out: Path) -> None:
    from selenium.webdriver.common.by import By

    live(d)
    save(d.get_screenshot_as_png(), out / "view-1000.png")
    plan = d.find_element(By.ID, "plan")
    d.execute_script("const k = topics.gtracks.tracks[0], n = navs.get($('plan'));"
                     "select(k.id); Object.assign(n, {auto: false, cx: k.x[0], cy: k.x[2], s: $('plan').width / 25e3});"
                     "render();")
    save(plan.screenshot_as_png, out / "view-zoom.png")
    live(d)
    d.execute_script("fitAll($('plan')); const ts = timeline.times(); timeline.seek(ts[ts.length - 1] - 300);")
    rect = d.execute_script("const r = $('plan').getBoundingClientRect(); return [r.right, r.bottom];")
    save(d.get_screenshot_as_png(), out / "view-paused.png", (0, 0, int(rect[0]) + 8, int(rect[1]) + 30))
    d.execute_script("timeline.goLive(); $('sonar').scrollIntoView();")
    save(d.find_element(By.ID, "sonar").screenshot_as_png, out / "view-1000-sonar.png")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--sonar", type=int, default=12, help="sonar tracks (100 in the benchmark; fewer read better)")
    ap.add_argument("--seconds", type=int, default=40, help="live seconds before the screenshots")
    args = ap.parse_args()
    scene, tpl = Scene(1000, args.sonar), load_topics(1000, args.sonar, 3)
    stop = threading.Event()
    try:
        with live_view((1300, 1000)) as (session, d, _):
            d.execute_script(FILL_JS, tpl, 600, 1.0)
            feed = threading.Thread(target=publish, args=(session, scene, args.seconds + 60, stop))
            feed.start()
            shown = "return !!topics.gtracks && topics.gtracks.t >= arguments[0]"
            while not d.execute_script(shown, T0 + args.seconds):
                time.sleep(0.5)
            shoot(d, args.out)
            stop.set()
            feed.join()
    finally:
        stop.set()
    return 0


if __name__ == "__main__":
    sys.exit(main())
