"""``pfusion view`` as an operator's tool (issue 32), in headless Chromium against the real
view and router (fixtures and helpers of test_view.py): sortable, filterable track tables
with a selected track's bases and history; the latitude/longitude graticule of a
geodetic deployment (metric grid otherwise); the sonar waterfall's time axis (newest at
the top), the TMA legend, labels kept inside their canvas, m/s or kn; and a status
palette that stays distinguishable with protanopia, deuteranopia and tritanopia.
Messages are put on the bus by the test (no simulator): each test costs a few seconds
beside the browser's start."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pymap3d
import pytest

from common.bus.transport import free_port, wait_port
from common.wire import protocol
from tests.colour_vision import MACHADO, closest_pair
from tests.harness import ROOT, SCENARIOS, Deployment
from tests.integration.test_view import browser, shot, sonar_messages, wait  # noqa: F401 (fixture)

TWO_TARGETS = SCENARIOS / "two_targets.toml"
NETWORK_RD = SCENARIOS / "network_rd.toml"
MIN_DE2000 = 15.0  # every pair of status colours (and each against the background)
OLD_PALETTE = {"confirmed": "#66bb6a", "tentative": "#b0bec5", "coasting": "#ffa726",
               "ambiguous": "#e040fb", "truth": "#5c6bc0", "background": "#0b1117"}
KN = 3600 / 1852


def gtracks(t: float, tracks: list[tuple[int, str, float, float, float, list[list[Any]]]]) -> bytes:
    """radar/gtracks of (id, status, x, y, vx, etracks [[base, id]])."""
    return protocol.encode({"v": protocol.VERSION, "t": t, "tracks": [
        {"id": i, "status": st, "x": [x, vx, y, 0.0, 9e3, 0.0], "P": np.eye(6).ravel() * 2500.0,
         "score": 1.0, "etracks": et, "ambiguous": False} for i, st, x, y, vx, et in tracks]})


def view(d: Deployment, name: str, config: Path) -> int:
    port = free_port()
    d.start(name, "view", "--config", str(config), "--port", str(port))
    wait_port(port, 60)
    return port


def open_page(driver: Any, port: int) -> None:
    driver.get(f"http://127.0.0.1:{port}/")
    wait("the page's socket", lambda: driver.execute_script("return wsOpen"), 30)


def column(driver: Any, body: str, key: str) -> list[str]:
    return driver.execute_script(
        f"return [...document.querySelectorAll('#{body} tr')].map(r => r.dataset['{key}'])")


def labels_inside(driver: Any) -> list[Any]:
    """Every label drawn on every canvas that is not wholly inside it."""
    return driver.execute_script(
        "return [...document.querySelectorAll('canvas')].flatMap(c => (c.labels || []).filter("
        "([t, x, y, w]) => x < 0 || x + w > c.width || y - 10 < 0 || y > c.height).map(l => [c.className, ...l]))")


@pytest.mark.timeout(300)
def test_tables_sort_filter_and_show_a_tracks_bases_and_history(browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """A click on a header sorts (again: reversed), the text box filters, a selected
    global track shows the bases that hold it and its last updates, a selected sonar
    track its array, TMA and bearings; m/s or kn everywhere; the rows updated in place by
    the next message. About 6 s."""
    from selenium.webdriver.common.by import By

    with Deployment(tmp_path) as d:
        port = view(d, "view", TWO_TARGETS)
        open_page(browser, port)
        for t, dx in ((10.0, 0.0), (11.0, 150.0)):
            d.session.put(f"{ROOT}/radar/gtracks", gtracks(t, [
                (3, "confirmed", 5e3 + dx, 1e3, 150.0, [["b1", 4], ["b2", 9]]),
                (1, "tentative", 9e3 + dx, 2e3, 100.0, [["b3", 2]]),
                (2, "coasting", -4e3 + dx, 3e3, 250.0, [["b1", 5]])]))
            wait(f"the tracks of t={t}", lambda t=t: browser.execute_script(
                "return topics.gtracks && topics.gtracks.t") == t, 30)
        assert column(browser, "tracks", "id") == ["1", "2", "3"]  # by id, ascending
        browser.find_element(By.CSS_SELECTOR, "th[data-table='g'][data-key='id']").click()
        assert column(browser, "tracks", "id") == ["3", "2", "1"]  # the same header: reversed
        browser.find_element(By.CSS_SELECTOR, "th[data-table='g'][data-key='x']").click()
        assert column(browser, "tracks", "id") == ["2", "3", "1"]  # west to east
        browser.find_element(By.CSS_SELECTOR, "th[data-table='g'][data-key='speed']").click()
        browser.find_element(By.CSS_SELECTOR, "th[data-table='g'][data-key='speed']").click()
        assert column(browser, "tracks", "id") == ["2", "3", "1"]  # fastest first
        assert browser.find_element(By.CSS_SELECTOR, "th[data-key='speed']").get_attribute("data-sorted") == "desc"
        box = browser.find_element(By.ID, "filter-g")
        box.send_keys("tentative")
        assert column(browser, "tracks", "id") == ["1"]
        box.clear()
        box.send_keys("b1")  # by base
        assert sorted(column(browser, "tracks", "id")) == ["2", "3"]
        box.clear()
        browser.execute_script("$('filter-g').dispatchEvent(new Event('input'))")
        assert len(column(browser, "tracks", "id")) == 3

        browser.find_element(By.CSS_SELECTOR, "#tracks tr[data-id='3']").click()
        details = browser.find_element(By.ID, "details").text
        assert details.startswith("track 3  confirmed"), details
        assert "bases     b1 (etrack 4), b2 (etrack 9)" in details
        history = re.findall(r"^\s+(\d+\.\d) +(-?\d+\.\d\d) +(-?\d+\.\d\d)", details, re.M)
        assert history == [("11.0", "5.15", "1.00"), ("10.0", "5.00", "1.00")], details  # newest first

        browser.find_element(By.ID, "speed-units").send_keys("kn")
        assert browser.find_element(By.ID, "speed-head").text == "kn"
        speed = browser.find_element(By.CSS_SELECTOR, "#tracks tr[data-id='3'] td:nth-child(6)").text
        assert speed == f"{150 * KN:.0f}", speed
        assert f"{150 * KN:.1f} kn, course 90.0 deg" in browser.find_element(By.ID, "details").text
        # the next message updates the rows in place: the same row elements, new values
        browser.execute_script("window.kept = [...document.querySelectorAll('#tracks tr')]")
        d.session.put(f"{ROOT}/radar/gtracks", gtracks(12.0, [
            (3, "confirmed", 5.3e3, 1e3, 150.0, [["b1", 4], ["b2", 9]]),
            (1, "tentative", 9.3e3, 2e3, 100.0, [["b3", 2]]),
            (2, "coasting", -3.7e3, 3e3, 250.0, [["b1", 5]])]))
        wait("the tracks of t=12", lambda: browser.execute_script("return topics.gtracks.t") == 12.0, 30)
        assert browser.execute_script(
            "return [...document.querySelectorAll('#tracks tr')].every((r, i) => r === kept[i]) && kept.length"
            " === 3"), "rows rebuilt"
        assert column(browser, "tracks", "id") == ["2", "3", "1"]
        assert browser.find_element(By.CSS_SELECTOR, "#tracks tr[data-id='2'] td:nth-child(3)").text == "-3.70"

        msgs = sonar_messages()
        second = dict(msgs[3][1]["tracks"][0], id=8, status="tentative", x=[3.0, 0.0, 60.0, 0.0])
        msgs[3][1]["tracks"].append(second)
        for suffix, msg in msgs:
            d.session.put(f"{ROOT}/{suffix}", protocol.encode(msg))
        wait("two sonar tracks listed", lambda: len(column(browser, "sonar-tracks", "key")) == 2, 30)
        browser.find_element(By.CSS_SELECTOR, "th[data-table='s'][data-key='brg']").click()
        browser.find_element(By.CSS_SELECTOR, "th[data-table='s'][data-key='brg']").click()
        assert column(browser, "sonar-tracks", "key") == ["a1/8", "a1/7"]  # 171.9 then 57.3 deg
        browser.find_element(By.ID, "filter-s").send_keys("confirmed")
        assert column(browser, "sonar-tracks", "key") == ["a1/7"]
        tma_row = browser.find_element(By.CSS_SELECTOR, "#sonar-tracks tr[data-key='a1/7']")
        assert tma_row.find_elements(By.TAG_NAME, "td")[6].text == f"{2.24 * KN:.1f}"
        tma_row.click()
        sonar = browser.find_element(By.ID, "details").text
        assert sonar.startswith("sonar track 7 of array a1  confirmed"), sonar
        assert f"TMA       7.21 km, course 116.3 deg, {2.24 * KN:.1f} kn" in sonar
        assert re.search(r"^\s+40\.0 s +57\.30 deg  confirmed$", sonar, re.M), sonar
        shot(browser, "view-ops-tables")


@pytest.mark.timeout(300)
def test_graticule_in_latitude_longitude_for_a_geodetic_deployment(browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """network_rd.toml ([radar.origin] 47 N 8 E): the plan is ruled in latitude and
    longitude, labelled on its edges, its conversions equal to pymap3d's (1e-7 deg);
    two_targets.toml (no origin): a metric grid in km, no degrees. About 5 s."""
    with Deployment(tmp_path) as d:
        geo, flat = view(d, "view-geo", NETWORK_RD), view(d, "view-flat", TWO_TARGETS)
        open_page(browser, geo)
        grat = wait("a graticule", lambda: browser.execute_script(
            "render(); return $('plan').graticule"), 30)
        assert 2 <= len(grat["lats"]) <= 40 and 2 <= len(grat["lons"]) <= 40, grat
        assert 45.0 < min(grat["lats"]) and max(grat["lats"]) < 49.0, grat  # the network, not the globe
        assert 5.0 < min(grat["lons"]) and max(grat["lons"]) < 11.0, grat
        texts = [lab[0] for lab in browser.execute_script("return $('plan').labels")]
        lat_labels = [t for t in texts if re.fullmatch(r"\d+°(\d+(\.\d)?')?N", t)]
        lon_labels = [t for t in texts if re.fullmatch(r"\d+°(\d+(\.\d)?')?E", t)]
        assert len(lat_labels) >= 2 and len(lon_labels) >= 2, texts
        assert not [t for t in texts if t.endswith(" km")], texts
        assert "47°N" in lat_labels or any(t.startswith("47°") for t in lat_labels), lat_labels
        for e, n, u in ((-80e3, 40e3, 0.0), (120e3, -60e3, 500.0), (0.0, 0.0, 0.0)):
            lat, lon, h = browser.execute_script(
                "return enuToGeo(arguments[0], arguments[1], arguments[2], topics.geometry.origin)", e, n, u)
            want = pymap3d.enu2geodetic(e, n, u, 47.0, 8.0, 450.0)
            assert np.allclose([lat, lon], want[:2], atol=1e-7) and abs(h - want[2]) < 1e-3, (lat, lon, h, want)
            back = browser.execute_script(
                "return geoToEnu(arguments[0], arguments[1], arguments[2], topics.geometry.origin)", lat, lon, h)
            assert np.allclose(back, [e, n, u], atol=1e-3), back
        assert labels_inside(browser) == []
        shot(browser, "view-ops-graticule")

        open_page(browser, flat)
        wait("the metric plan", lambda: browser.execute_script(
            "render(); return $('plan').labels.length > 0"), 30)
        assert browser.execute_script("return $('plan').graticule") is None
        texts = [lab[0] for lab in browser.execute_script("return $('plan').labels")]
        assert texts and all(t.endswith(" km") for t in texts), texts
        assert browser.execute_script("return topics.geometry.origin") is None


@pytest.mark.timeout(300)
def test_waterfall_axis_tma_legend_labels_inside_and_palette_for_colour_deficiencies(
        browser: Any, tmp_path: Path) -> None:  # noqa: F811
    """The waterfall's time axis runs newest at the top, in min:s; the TMA panel has a
    legend; a solution near the canvas edge keeps its label inside; the page's status
    colours (read from the page: palette and legend swatches) stay >= MIN_DE2000 apart
    (CIEDE2000) for normal vision and simulated protanopia, deuteranopia, tritanopia,
    which the previous palette failed. About 4 s."""
    from selenium.webdriver.common.by import By

    with Deployment(tmp_path) as d:
        port = view(d, "view", TWO_TARGETS)
        open_page(browser, port)
        msgs = sonar_messages()
        sol = msgs[-1][1]["solutions"][0]
        msgs[-1][1]["solutions"].append(sol | {"track": 9, "x": 3.0e4, "y": 0.0, "constrained": True})
        for suffix, msg in msgs:
            d.session.put(f"{ROOT}/{suffix}", protocol.encode(msg))
        wait("the sonar panels", lambda: browser.execute_script(
            "return !!topics['tma/a1'] && document.querySelectorAll('#array-a1 canvas').length === 2"), 30)
        browser.execute_script("render()")
        axis = browser.execute_script("return document.querySelector('#array-a1 .waterfall').axis")
        assert axis["top"] == 40.0 and axis["bottom"] == 0.0  # newest row at the top
        ticks = browser.execute_script(
            "return document.querySelector('#array-a1 .waterfall').labels.filter(l => /^\\d+:\\d\\d$/.test(l[0]))"
            ".map(l => [l[0], l[2]])")
        assert [t for t, _ in ticks] == [f"0:{s:02d}" for s in range(0, 41, 5)], ticks  # message time
        ys = [y for _, y in ticks]
        assert ys == sorted(ys, reverse=True), ticks  # later times higher up
        # detections drawn from the page's pixel layer: each 2 x 2 px where the axes place it
        dots = browser.execute_script(
            "const c = document.querySelector('#array-a1 .waterfall'), ctx = c.getContext('2d'), a = c.axis;"
            "const W = c.width - 50, H = c.height - 26, px = (x, y) => Array.from(ctx.getImageData(x, y, 1, 1).data);"
            "return topics['waterfall/a1'].rows.flatMap(([t, bs]) => bs.map((b) => {"
            "  const x = Math.round(50 + b / 360 * W), y = Math.round((a.t1 - t) / (a.t1 - a.t0) * H);"
            "  return [b, t, px(x - 1, Math.max(y - 1, 0)), px(x, y), px(x + 3, y + 3)]; }))")
        assert len(dots) == 6, dots
        for b, t, inside, corner, beside in dots:
            if abs(b - 143.2) < 1 and t == 20.0:  # the detection no bearing track crosses
                assert inside == corner == [0xcf, 0xd8, 0xdc, 255] and beside != inside, (b, t, inside, corner, beside)
        assert sum(abs(b - 143.2) < 1 and t == 20.0 for b, t, *_ in dots) == 1, dots
        legend = browser.find_element(By.CSS_SELECTOR, "#array-a1 .tma-legend").text
        for item in ("own ship", "TMA", "constrained TMA", "truth", "range unobservable"):
            assert item in legend, legend
        tma_labels = browser.execute_script("return document.querySelector('#array-a1 .tma').labels.map(l => l[0])")
        assert any(t.startswith("9: ") for t in tma_labels), tma_labels
        at, drawn = browser.execute_script(
            "const c = document.querySelector('#array-a1 .tma'); "
            "return [c.xf.x(30000) + 6, c.labels.find(l => l[0].startsWith('9: '))]")
        assert at + drawn[3] > 420 and drawn[1] + drawn[3] <= 418, (at, drawn)  # it would be cut: moved in
        assert labels_inside(browser) == []
        browser.find_element(By.ID, "speed-units").send_keys("kn")
        assert browser.find_element(By.CSS_SELECTOR, "#array-a1 .sols").text.splitlines()[0].endswith(
            f"{2.24 * KN:.1f} kn")

        palette = browser.execute_script("return PALETTE")
        assert set(palette) == set(OLD_PALETTE)
        for status in ("confirmed", "tentative", "coasting", "ambiguous", "truth"):
            swatch = browser.execute_script(
                f"return getComputedStyle(document.querySelector('.legend .sw.{status}')).color")
            rgb = tuple(int(c) for c in re.findall(r"\d+", swatch)[:3])
            assert rgb == tuple(int(palette[status][i:i + 2], 16) for i in (1, 3, 5)), (status, swatch)
        assert len(set(browser.execute_script("return Object.values(SHAPES)"))) == 5  # a shape each
        for deficiency in MACHADO:
            de, p, q = closest_pair(palette, deficiency)
            print(f"{deficiency}: closest {p} / {q} at CIEDE2000 {de:.1f}")
            assert de >= MIN_DE2000, (deficiency, p, q, de)
        assert min(closest_pair(OLD_PALETTE, k)[0] for k in MACHADO) < MIN_DE2000  # the test can fail
        shot(browser, "view-ops-sonar")
