"""hillshade-rt view in a real browser: Debian's chromium, headless, driven by selenium through
/usr/bin/chromedriver (no browser is downloaded). Load the page, move the time slider with the
keyboard, wait for the picture to change, compare its shadow pixels with the command line's mask
(arrays.shadow_mask) for the sun the server used, and save a screenshot for docs/viewer.md.

Marked ``browser``; ``.ci/run`` installs chromium and chromium-driver when they are missing and
sets HILLSHADE_RT_REQUIRE_BROWSER=1, so that in CI a missing browser fails the test instead of
skipping it."""

from __future__ import annotations

import base64
import os
import shutil
import threading
import time

import numpy as np
import pytest

from hillshade_rt.engine.arrays import shadow_mask
from hillshade_rt.io import read_dem
from hillshade_rt.run.view_server import make_server
from hillshade_rt.run.viewer import Viewer
from hillshade_rt.testing import repo_root

pytestmark = pytest.mark.browser

CHROMIUM, DRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"
DEM = os.path.join(repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")
# the docs' screenshot is refreshed only when asked (make docs-viewer): a test run leaves the
# checkout as it found it
DOCS_SCREENSHOT = os.path.join(repo_root(), "docs", "img", "viewer.png")


def required() -> bool:
    return bool(os.environ.get("HILLSHADE_RT_REQUIRE_BROWSER") or os.environ.get("CI"))


@pytest.fixture(scope="module")
def browser():
    missing = [p for p in (CHROMIUM, DRIVER) if not os.path.exists(p)]
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        missing.append("selenium (pip install 'hillshade-rt[test]')")
    if missing:
        msg = f"the browser test needs {', '.join(missing)} (apt-get install chromium chromium-driver)"
        if required():
            pytest.fail(msg)
        pytest.skip(msg)
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
              "--window-size=1300,900", "--force-device-scale-factor=1"):
        opts.add_argument(a)
    drv = webdriver.Chrome(service=Service(DRIVER), options=opts)
    yield drv
    drv.quit()


@pytest.fixture(scope="module")
def server():
    viewer = Viewer(read_dem(DEM))
    srv = make_server(viewer, 0)
    threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.1}, daemon=True).start()
    yield srv
    srv.shutdown()
    srv.server_close()
    viewer.close()


def wait_for(drv, script, timeout=120.0):
    """The value of ``script`` once it is truthy."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = drv.execute_script(script)
        if v:
            return v
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for: {script}")


def picture(drv) -> np.ndarray:
    """The picture on the page (the overlay's pixels, via a canvas) as (h, w, 4) uint8."""
    import warnings

    from rasterio.errors import NotGeoreferencedWarning
    from rasterio.io import MemoryFile
    url = drv.execute_script("return viewer.pixels()")
    png = base64.b64decode(url.split(",", 1)[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with MemoryFile(png) as mf, mf.open() as ds:
            return np.moveaxis(ds.read(), 0, -1)


def cells_of(lo, hi, n_px):
    """Each pixel's cell along one axis: as the server maps them (run.viewer.pixel_cells)."""
    return np.floor(lo + (np.arange(n_px) + 0.5) * ((hi - lo) / n_px)).astype(np.int64)


@pytest.mark.slow
def test_time_slider_updates_the_shadows(browser, server, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    dem = read_dem(DEM)
    drv = browser
    drv.get(server.url)
    wait_for(drv, "return window.viewer && viewer.renders >= 1")
    # a winter day (the date picker set as a person would leave it), 08:00 on the slider
    drv.execute_script("const d = document.getElementById('date'); d.value = '2026-12-21';"
                       "d.dispatchEvent(new Event('change'));"
                       "const t = document.getElementById('time'); t.value = '480';"
                       "t.dispatchEvent(new Event('input'));")
    first = wait_for(drv, "return viewer.last && viewer.last.time.includes('T08:00') "
                          "&& viewer.last")
    # the DEM's own zone (Big Tujunga, California), with its winter offset on that date
    assert wait_for(drv, "const z = document.getElementById('zone').textContent;"
                         "return z.includes('UTC-08:00') && z") == \
        "times in America/Los_Angeles (UTC-08:00, PST)"
    assert first["time"].endswith("-08:00")
    before = picture(drv)
    n = drv.execute_script("return viewer.renders")

    # move the slider with the keyboard: 18 steps of 5 minutes, to 09:30
    slider = drv.find_element(By.ID, "time")
    slider.send_keys(*([Keys.ARROW_RIGHT] * 18))
    last = wait_for(drv, f"return viewer.renders > {n} && viewer.last.time.includes('T09:30') "
                         "&& viewer.last")
    after = picture(drv)
    assert last["azimuth"] != first["azimuth"]
    assert after.shape == (last["h"], last["w"], 4)
    assert not np.array_equal(after, before)           # the picture changed

    # its shadow pixels are the command line's mask for that sun, cell for cell
    assert last["level"] == 1
    x0, y0, x1, y1 = last["bbox"]
    rows, cols = dem.shape
    r = cells_of(y0, y1, last["h"])
    c = cells_of(x0, x1, last["w"])
    rin, cin = (r >= 0) & (r < rows), (c >= 0) & (c < cols)
    assert rin.sum() > 300 and cin.sum() > 300        # most of the DEM is on screen
    want = shadow_mask(dem, last["azimuth"], last["elevation"])
    want_px = want[np.ix_(r[rin], c[cin])]
    got = after[np.ix_(rin, cin)]
    shadow = (got[..., 2].astype(int) > got[..., 0].astype(int)).astype(np.uint8)
    shadow[got[..., 3] == 0] = 255
    assert 0.02 < np.mean(want_px == 1) < 0.9
    assert np.array_equal(shadow, want_px)

    # a click shows the point's height, light and horizon profile
    ActionChains(drv).move_to_element_with_offset(drv.find_element(By.ID, "map"), 40, 60) \
        .click().perform()
    text = wait_for(drv, "const t = document.getElementById('point').textContent;"
                         "return t.includes('height') && t")
    assert "lit" in text or "in shadow" in text
    shot = str(tmp_path / "viewer.png")
    drv.save_screenshot(shot)
    with open(shot, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    if os.environ.get("HILLSHADE_RT_DOCS_SCREENSHOT"):
        tmp = DOCS_SCREENSHOT + ".tmp.png"
        shutil.copyfile(shot, tmp)
        os.replace(tmp, DOCS_SCREENSHOT)


@pytest.mark.slow
def test_compass_drag_and_toggles(browser, server):
    """Dragging the sun on the compass sets azimuth and elevation by hand (the picture follows);
    soft shadows and sun hours each bring a new picture; the download link names the sun."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    drv = browser
    drv.get(server.url)
    wait_for(drv, "return window.viewer && viewer.renders >= 1")
    n = drv.execute_script("return viewer.renders")
    compass = drv.find_element(By.ID, "compass")
    # from the centre (zenith) 40 px to the east and 40 px north, then release: the compass's
    # horizon is 80 px from the centre, so elevation 90 * (1 - 56.6 / 80) = 26.4, azimuth 45
    ActionChains(drv).move_to_element(compass).click_and_hold().move_by_offset(20, -20) \
        .move_by_offset(20, -20).release().perform()
    last = wait_for(drv, f"return viewer.renders > {n} && viewer.state.mode === 'manual' "
                         "&& Math.abs(viewer.last.azimuth - 45) < 3 && viewer.last")
    assert abs(last["elevation"] - 26.4) < 3.0
    assert "set by hand" in drv.find_element(By.ID, "sunlabel").text
    for box, header in (("soft", None), ("sunhours", "sun hours")):
        n = drv.execute_script("return viewer.renders")
        drv.find_element(By.ID, box).click()
        wait_for(drv, f"return viewer.renders > {n}")
        if header:
            assert header in drv.find_element(By.ID, "status").text
        drv.find_element(By.ID, box).click()          # off again
        wait_for(drv, f"return viewer.renders > {n + 1}")


@pytest.mark.slow
def test_terrain_brush_changes_the_picture(browser, server):
    """The brush: toggled on, a click raises the terrain there (a 400 m block, 300 m across),
    the picture is drawn again with its shadow; undo brings the first picture back."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    drv = browser
    drv.get(server.url)
    wait_for(drv, "return window.viewer && viewer.renders >= 1")
    # a low sun from the south-west by hand: long shadows, the same for every render
    drv.execute_script("viewer.state.mode = 'manual'; viewer.state.az = 225; viewer.state.el = 10;"
                       "document.getElementById('soft').dispatchEvent(new Event('change'));")
    base = wait_for(drv, "return viewer.last && viewer.last.azimuth === 225 && viewer.renders")
    before = picture(drv)
    drv.find_element(By.ID, "brush").click()
    assert drv.find_element(By.ID, "brush").get_attribute("aria-pressed") == "true"
    for field, value in (("radius", "150"), ("delta", "400")):
        box = drv.find_element(By.ID, field)
        box.clear()
        box.send_keys(value)
    map_el = drv.find_element(By.ID, "map")
    ActionChains(drv).move_to_element(map_el).click().perform()      # the map's centre
    wait_for(drv, "return viewer.edits === 1")
    wait_for(drv, f"return viewer.renders > {base}")
    after = picture(drv)
    assert after.shape == before.shape and not np.array_equal(after, before)
    assert "1 edit(s)" in drv.find_element(By.ID, "edits").text
    n = drv.execute_script("return viewer.renders")
    drv.find_element(By.ID, "undo").click()
    wait_for(drv, f"return viewer.edits === 0 && viewer.renders > {n}")
    assert np.array_equal(picture(drv), before)
    drv.find_element(By.ID, "brush").click()          # off: a click shows a point again
    assert drv.find_element(By.ID, "brush").get_attribute("aria-pressed") == "false"
