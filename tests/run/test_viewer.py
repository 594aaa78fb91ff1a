"""hillshade-rt view's model (run/viewer.py), served in a thread on a free port and asked with
urllib. The pictures' shadow pixels (blue > red) are checked against arrays.shadow_mask, the
command line's mask, for the same sun."""

from __future__ import annotations

import json
import os
import urllib.error
import urllib.request
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from hillshade_rt.engine.arrays import shadow_mask
from hillshade_rt.io import read_dem
from hillshade_rt.run.viewer import Viewer
from hillshade_rt.testing import data_path, http_get, png_pixels, serving

DEM = data_path("everest_srtm3_voids_crop200.tif")     # EPSG:4326, 19.5 % voids


@pytest.fixture(scope="module")
def dem():
    return read_dem(DEM)


@pytest.fixture(scope="module")
def server(dem):
    with serving(Viewer(dem)) as srv:
        yield srv


def shadow_of(pic):
    """1 where a pixel shows shadow (blue > red), 0 lit, 255 transparent (void, outside)."""
    rgb = pic[..., :3].astype(int)
    out = (rgb[..., 2] > rgb[..., 0]).astype(np.uint8)
    out[pic[..., 3] == 0] = 255
    return out


def render(server, **q):
    query = "&".join(f"{k}={v}" for k, v in q.items())
    status, headers, body = http_get(server, "/api/render?" + query)
    assert status == 200, body
    return png_pixels(body), headers


def test_info(server, dem):
    status, _, body = http_get(server, "/api/info")
    info = json.loads(body)
    assert status == 200
    assert (info["rows"], info["cols"]) == dem.shape
    assert info["has_time"] and info["zone"] == "Asia/Kathmandu"       # Everest, 86.6 E
    assert info["zone_label"] == "Asia/Kathmandu (UTC+05:45)" and info["zone_source"] == \
        "the DEM's centre"
    assert "auto" in info["algorithms"] and info["algorithm"] == "auto"
    assert info["height_range"][0] == pytest.approx(float(np.nanmin(dem.heights)))
    # the file's name, never the machine's folders
    assert info["name"] == os.path.basename(DEM) and "path" not in info
    assert os.path.dirname(os.path.abspath(DEM)).encode() not in body


@pytest.mark.parametrize("az, el", [(203.7, 12.0), (163.0, 25.0), (290.0, 8.0)])
def test_full_resolution_equals_the_cli_mask(server, dem, az, el):
    rows, cols = dem.shape
    pic, h = render(server, az=az, el=el, bbox=f"0,0,{cols},{rows}", w=cols, h=rows)
    assert h["X-Level"] == "1"
    want = shadow_mask(dem, az, el)
    assert 0.05 < np.mean(want == 1) < 0.9       # a real test: shadow and light both
    assert np.array_equal(shadow_of(pic), want)


def test_window_zoomed_in_and_out(server, dem):
    az, el = 203.7, 12.0
    want = shadow_mask(dem, az, el)
    # a window of the DEM at 1:1: the mask's cells there (computed with its halo)
    pic, h = render(server, az=az, el=el, bbox="50,60,150,140", w=100, h=80)
    assert h["X-Level"] == "1"
    assert np.array_equal(shadow_of(pic), want[60:140, 50:150])
    # zoomed in 3x: each cell 3x3 pixels
    pic, _ = render(server, az=az, el=el, bbox="120,30,160,50", w=120, h=60)
    assert np.array_equal(shadow_of(pic), np.repeat(np.repeat(want[30:50, 120:160], 3, 0), 3, 1))
    # the whole DEM on 50 x 50 pixels: the overview level (every 4th cell)
    pic, h = render(server, az=az, el=el, w=50, h=50)
    assert h["X-Level"] == "4" and pic.shape == (50, 50, 4)
    void = np.isnan(dem.heights[::4, ::4])
    assert np.array_equal(pic[..., 3] == 0, void)


def test_window_partly_and_wholly_outside(server, dem):
    az, el = 163.0, 25.0
    want = shadow_mask(dem, az, el)
    # 20 pixels beyond the western and northern edges: transparent there
    pic, _ = render(server, az=az, el=el, bbox="-20,-20,80,80", w=100, h=100)
    s = shadow_of(pic)
    assert (pic[:20, :, 3] == 0).all() and (pic[:, :20, 3] == 0).all()
    assert np.array_equal(s[20:, 20:], want[:80, :80])
    # wholly outside: a transparent picture, no error
    pic, h = render(server, az=az, el=el, bbox="500,500,600,600", w=64, h=32)
    assert pic.shape == (32, 64, 4) and (pic[..., 3] == 0).all()
    status, _, body = http_get(server, "/api/point?x=-3&y=10")
    assert status == 404 and b"outside" in body


def test_time_gives_the_sun_of_that_time(server, dem):
    from hillshade_rt.model.site import dem_site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.model.times import parse_time
    rows, cols = dem.shape
    pic, h = render(server, time="2026-06-21T16:30", bbox=f"0,0,{cols},{rows}", w=cols, h=rows)
    t = parse_time("2026-06-21T16:30+05:45")
    s = sun_over(dem_site(dem), dem.shape, [t])[0]
    az, el = float(h["X-Sun-Azimuth"]), float(h["X-Sun-Elevation"])
    assert (az, el) == (s.azimuth, s.elevation)
    assert h["X-Time"].startswith("2026-06-21T16:30:00+05:45")
    assert np.array_equal(shadow_of(pic), shadow_mask(dem, az, el))


def test_soft_and_sun_hours_pictures(server, dem):
    rows, cols = dem.shape
    pic, _ = render(server, az=203.7, el=12, soft=1, bbox=f"0,0,{cols},{rows}", w=cols, h=rows)
    hard = shadow_mask(dem, 203.7, 12)
    s = shadow_of(pic)
    # the soft picture: shadowed where the disk is mostly hidden, so close to the hard mask
    assert np.mean(s[hard != 255] == hard[hard != 255]) > 0.95
    pic, h = render(server, sunhours="2026-06-21", w=100, h=100)
    assert 12.0 < float(h["X-Sun-Hours-Max"]) < 15.0     # the day's length at 28 N, in June
    assert pic[..., 3].any()


def test_point(server, dem):
    az, el = 203.7, 12.0
    want = shadow_mask(dem, az, el)
    r, c = np.argwhere(np.isfinite(dem.heights) & (want == 1))[7]
    status, _, body = http_get(server, f"/api/point?x={c + 0.5}&y={r + 0.5}&az={az}&el={el}")
    p = json.loads(body)
    assert status == 200 and (p["row"], p["col"]) == (r, c)
    assert p["sun"] == {"azimuth": az, "elevation": el, "time": None}    # as the JSON says it
    assert p["height"] == pytest.approx(float(dem.heights[r, c]))
    assert p["lit"] is False
    # in shadow: the horizon toward the sun stands above it (interpolated between 2-degree steps)
    assert len(p["horizon"]["azimuths"]) == 180 and p["horizon"]["toward_sun"] > el - 2.0
    r, c = np.argwhere(np.isfinite(dem.heights) & (want == 0))[11]
    p = json.loads(http_get(server, f"/api/point?x={c + 0.2}&y={r + 0.9}&az={az}&el={el}")[2])
    assert p["lit"] is True and -90 <= p["lat"] <= 90


def test_sunpath(server):
    status, _, body = http_get(server, "/api/sunpath?date=2026-06-21")
    path = json.loads(body)
    assert status == 200 and len(path["points"]) == 144
    els = [p["elevation"] for p in path["points"]]
    noon = path["points"][int(np.argmax(els))]
    # Everest (28 N) at the June solstice: the sun culminates about 85 degrees up, near local
    # noon (Nepal's UTC+5:45 is 19 minutes behind the mean solar time at 86.6 E)
    assert 80 < max(els) < 90 and 11 * 60 <= noon["minutes"] <= 13 * 60
    assert min(els) < 0


def test_download_is_the_mask(server, dem):
    from rasterio.io import MemoryFile
    status, headers, body = http_get(server, "/api/download?az=290&el=8")
    assert status == 200 and "attachment" in headers["Content-Disposition"]
    with MemoryFile(body) as mf, mf.open() as ds:
        got = ds.read(1)
        assert ds.crs == dem.crs and ds.transform == dem.transform and ds.nodata == 255
    assert np.array_equal(got, shadow_mask(dem, 290, 8))


def test_concurrent_requests(server, dem):
    rows, cols = dem.shape
    suns = [(163.0, 25.0), (203.7, 12.0), (290.0, 8.0), (40.0, 30.0), (120.0, 15.0),
            (250.0, 20.0)] * 2
    wants = {s: shadow_mask(dem, *s) for s in suns}

    def one(s):
        return s, render(server, az=s[0], el=s[1], bbox=f"0,0,{cols},{rows}", w=cols, h=rows)[0]
    with ThreadPoolExecutor(8) as ex:
        futures = [ex.submit(one, s) for s in suns]
        futures += [ex.submit(http_get, server, "/api/render?az=x") for _ in range(4)]
        results = [f.result() for f in futures]
    for s, pic in results[:len(suns)]:
        assert np.array_equal(shadow_of(pic), wants[s]), s
    assert all(r[0] == 400 for r in results[len(suns):])


def test_a_dem_without_a_crs_has_no_times(tmp_path):
    from hillshade_rt.run.config import ReadOptions
    from hillshade_rt.testing import fractal_terrain, reference_mask, write_geotiff
    z = fractal_terrain(64, 80, seed=9).astype(np.float32)
    path = write_geotiff(tmp_path / "plain.tif", z)
    dem = ReadOptions(pixel_size="5").read(path)
    with serving(Viewer(dem)) as srv:
        info = json.loads(http_get(srv, "/api/info")[2])
        assert info["has_time"] is False and info["zone"] is None and info["date"] is None
        status, _, body = http_get(srv, "/api/render?time=2026-06-21T12:00")
        assert status == 400 and b"no place on Earth" in body
        assert http_get(srv, "/api/sunpath?date=2026-06-21")[0] == 400
        pic, _ = render(srv, az=163, el=20, bbox="0,0,80,64", w=80, h=64)
        # the plain-Python reference of the model (no curvature on a 0.5 km raster)
        assert np.array_equal(shadow_of(pic), reference_mask(z, 5.0, 5.0, 163.0, 20.0))


def test_gpu_backend_gives_the_cpu_pictures():
    """The viewer on the CUDA backend (the simulator here: a small DEM): the whole view and a
    window with its halo equal the CPU's mask."""
    from affine import Affine

    from hillshade_rt.testing import fractal_terrain, memory_dem
    z = fractal_terrain(17, 21, 5, relief=150.0, octaves=4).astype(np.float32)
    z[6:8, 9:11] = np.nan
    dem = memory_dem(z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), "EPSG:32611")
    viewer = Viewer(dem, "auto", "gpu")
    try:
        for az, el, bbox in ((203.7, 12.0, "0,0,21,17"), (163.0, 20.0, "5,4,15,12")):
            x0, y0, x1, y1 = (int(v) for v in bbox.split(","))
            pic, meta = viewer.render({"az": str(az), "el": str(el), "bbox": bbox,
                                       "w": str(x1 - x0), "h": str(y1 - y0)})
            want = shadow_mask(dem, az, el, backend="cpu")[y0:y1, x0:x1]
            assert np.array_equal(shadow_of(pic), want), (az, el)
            assert meta["X-Algorithm"] == "auto (brute)"      # auto's pick on the GPU
        # a brush edit on the GPU's copy (GpuDem.update): the CPU's mask of the edited heights
        z0 = z.copy()         # the viewer edits the DEM's array in place
        z1, _ = disk_edit(z0, dem.grid, 10, 5, 70.0, 200.0)
        viewer.edit({"x": 5.5, "y": 10.5, "radius": 70, "delta": 200})
        pic, _ = viewer.render({"az": "110", "el": "15", "bbox": "0,0,21,17", "w": "21",
                                "h": "17"})
        want = shadow_mask(memory_dem(z1, dem.transform, dem.crs), 110.0, 15.0, backend="cpu")
        assert np.array_equal(shadow_of(pic), want)
        assert not np.array_equal(want, shadow_mask(memory_dem(z0, dem.transform, dem.crs),
                                                    110.0, 15.0, backend="cpu"))
    finally:
        viewer.close()


# --------------------------------------------------------------------------------------------
# the DEM's zone

def test_zone_of_a_dem_in_zurich_with_daylight_saving():
    """The slider's local time is Zurich's clock: 12:00 is 10:00 UTC in July (CEST), 11:00 UTC
    in January (CET); the page is told the zone's name and its offset on the date shown."""
    from affine import Affine

    from hillshade_rt.testing import fractal_terrain, memory_dem
    z = fractal_terrain(40, 50, 3, relief=300.0).astype(np.float32) + 400.0
    dem = memory_dem(z, Affine(0.001, 0, 8.515, 0, -0.001, 47.39), "EPSG:4326")
    viewer = Viewer(dem)
    try:
        info = viewer.info()
        assert info["zone"] == "Europe/Zurich" and info["zone_source"] == "the DEM's centre"
        for day, off in (("2026-07-15", "+02:00"), ("2026-01-15", "+01:00")):
            sun = viewer.sun({"time": f"{day}T12:00"})
            assert sun.time == f"{day}T12:00:00{off}"
            path = viewer.sunpath({"date": day})
            assert path["zone_label"].startswith(f"Europe/Zurich (UTC{off}")
            assert path["points"][72]["time"] == f"{day}T12:00:00{off}"
        # --tz still wins, and --tz auto is the default spelled out
        assert Viewer(dem, tz="UTC").info()["zone"] == "UTC"
        assert Viewer(dem, tz="auto").info()["zone"] == "Europe/Zurich"
    finally:
        viewer.close()


# --------------------------------------------------------------------------------------------
# the terrain brush

def post(server, path, obj=None, raw=None):
    """(status, body) of POST ``path`` with ``obj`` as JSON (or ``raw`` bytes)."""
    data = raw if raw is not None else (b"" if obj is None else json.dumps(obj).encode())
    req = urllib.request.Request(server.url.rstrip("/") + path, data=data, method="POST",
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


@pytest.fixture
def edit_server():
    """A viewer of its own (edits change its heights) on the Everest DEM."""
    viewer = Viewer(read_dem(DEM))
    with serving(viewer) as srv:
        yield srv, viewer


def disk_edit(z, grid, r, c, radius, delta, flat=False):
    """The brush's edit written out: the cells whose centre lies within ``radius`` metres of
    cell (r, c) (the spacing of row r) raised by ``delta``, or (``flat``) set to z[r, c] +
    ``delta``; voids stay voids."""
    out = z.copy()
    dx, dy = float(grid.dx[r]), float(grid.dy[r])
    ii, jj = np.indices(z.shape)
    inside = ((ii - r) * dy) ** 2 + ((jj - c) * dx) ** 2 <= radius ** 2
    if flat:
        out[inside & np.isfinite(z)] = z[r, c] + np.float32(delta)
    else:
        out[inside] = z[inside] + np.float32(delta)
    return out, int(inside.sum())


def test_brush_edit_renders_the_edited_mask_and_undo_restores(edit_server):
    from hillshade_rt.testing import memory_dem
    srv, viewer = edit_server
    dem0 = read_dem(DEM)
    z0 = dem0.heights.copy()
    rows, cols = z0.shape
    az, el = 203.7, 12.0
    whole = dict(az=az, el=el, bbox=f"0,0,{cols},{rows}", w=cols, h=rows)
    before, _ = render(srv, **whole)
    small_before, _ = render(srv, az=az, el=el, w=50, h=50)          # level 4
    r, c = np.argwhere(np.isfinite(z0))[len(z0) * cols // 2]
    status, body = post(srv, "/api/edit", {"x": c + 0.5, "y": r + 0.5, "radius": 400,
                                           "delta": 800, "shape": "disk"})
    assert status == 200, body
    res = json.loads(body)
    z1, n1 = disk_edit(z0, dem0.grid, r, c, 400.0, 800.0)
    assert res["edits"] == 1 and res["cells"] == n1 and n1 > 10
    want = shadow_mask(memory_dem(z1, dem0.transform, dem0.crs), az, el)
    assert not np.array_equal(want, shadow_mask(dem0, az, el))     # the edit casts a shadow
    pic, _ = render(srv, **whole)
    assert np.array_equal(shadow_of(pic), want)
    # the overview levels follow: as a viewer made on the edited heights draws them
    fresh = Viewer(memory_dem(z1, dem0.transform, dem0.crs))
    try:
        for q in (dict(az=az, el=el, w=50, h=50), dict(az=290, el=8, w=100, h=100)):
            want_pic, _ = fresh.render({k: str(v) for k, v in q.items()})
            got, h = render(srv, **q)
            assert h["X-Level"] != "1" and np.array_equal(got, want_pic), q
    finally:
        fresh.close()
    # a flat top over it, then undo twice: the pictures and heights of the file again
    status, body = post(srv, "/api/edit", {"x": c + 0.5, "y": r + 0.5, "radius": 250,
                                           "delta": -100, "shape": "flat"})
    assert status == 200 and json.loads(body)["edits"] == 2
    z2, _ = disk_edit(z1, dem0.grid, r, c, 250.0, -100.0, flat=True)
    pic, _ = render(srv, **whole)
    assert np.array_equal(shadow_of(pic), shadow_mask(memory_dem(z2, dem0.transform, dem0.crs),
                                                      az, el))
    assert json.loads(post(srv, "/api/undo")[1])["edits"] == 1
    assert np.array_equal(viewer.z, z1, equal_nan=True)
    assert json.loads(post(srv, "/api/undo")[1])["edits"] == 0
    assert np.array_equal(viewer.z, z0, equal_nan=True)
    assert np.array_equal(render(srv, **whole)[0], before)
    assert np.array_equal(render(srv, az=az, el=el, w=50, h=50)[0], small_before)
    status, body = post(srv, "/api/undo")
    assert status == 400 and b"nothing to undo" in body


def test_brush_reset_and_the_download_of_the_edited_terrain(edit_server):
    from rasterio.io import MemoryFile

    from hillshade_rt.testing import memory_dem
    srv, viewer = edit_server
    dem0 = read_dem(DEM)
    z0 = dem0.heights.copy()
    z = z0
    for x, y in ((60.5, 70.5), (120.5, 90.5)):
        assert post(srv, "/api/edit", {"x": x, "y": y, "radius": 300, "delta": 500})[0] == 200
        z, _ = disk_edit(z, dem0.grid, int(y), int(x), 300.0, 500.0)
    status, headers, body = http_get(srv, "/api/download?az=290&el=8")
    assert status == 200 and "_edited_" in headers["Content-Disposition"]
    with MemoryFile(body) as mf, mf.open() as ds:
        got, tags = ds.read(1), ds.tags()
    assert np.array_equal(got, shadow_mask(memory_dem(z, dem0.transform, dem0.crs), 290, 8))
    assert tags["TERRAIN"].startswith("edited: 2 brush edit(s)") and \
        len(json.loads(tags["EDITS"])) == 2
    status, body = post(srv, "/api/reset")
    assert status == 200 and json.loads(body)["edits"] == 0
    assert np.array_equal(viewer.z, z0, equal_nan=True)
    status, headers, body = http_get(srv, "/api/download?az=290&el=8")
    with MemoryFile(body) as mf, mf.open() as ds:
        assert "TERRAIN" not in ds.tags()
        assert np.array_equal(ds.read(1), shadow_mask(dem0, 290, 8))


@pytest.mark.parametrize("body, words", [
    (b"{not json", "not JSON"),
    (b'{"x": 5, "y": 5, "delta": 10}', "missing radius"),
    (b'{"x": 5, "y": 5, "radius": 10}', "missing delta"),
    (b'{"x": "a", "y": 5, "radius": 10, "delta": 1}', "x must be a number"),
    (b'{"x": 5, "y": 5, "radius": -1, "delta": 1}', "radius must be"),
    (b'{"x": 5, "y": 5, "radius": 10, "delta": 1, "shape": "cone"}', "shape must be"),
    (b'{"x": -5, "y": 5, "radius": 10, "delta": 1}', "outside the DEM"),
    (b'[1, 2]', "JSON object"),
])
def test_malformed_edits_400_and_the_server_goes_on(edit_server, body, words):
    srv, viewer = edit_server
    z0 = viewer.z.copy()
    status, text = post(srv, "/api/edit", raw=body)
    assert status == 400 and words in text.decode() and "\n" not in text.decode().strip()
    assert np.array_equal(viewer.z, z0, equal_nan=True) and http_get(srv, "/api/info")[0] == 200
    assert post(srv, "/api/nothing")[0] == 404


def test_an_edit_reaches_every_algorithm_prepared(edit_server):
    """Shaders of several algorithms share the heights: each is updated (each sees the old
    heights go), so each draws the edited terrain's mask, at full resolution and at level 2."""
    from hillshade_rt.testing import memory_dem
    srv, viewer = edit_server
    dem0 = read_dem(DEM)
    rows, cols = dem0.shape
    az, el = 250.0, 10.0
    algos = ("auto", "brute", "bounds")
    for a in algos:       # prepared before the edit
        render(srv, az=az, el=el, algorithm=a, w=cols, h=rows)
        render(srv, az=az, el=el, algorithm=a, w=cols // 2, h=rows // 2)
    assert post(srv, "/api/edit", {"x": 100.5, "y": 100.5, "radius": 500, "delta": 1500})[0] == 200
    z1, _ = disk_edit(dem0.heights, dem0.grid, 100, 100, 500.0, 1500.0)
    edited = memory_dem(z1, dem0.transform, dem0.crs)
    want = shadow_mask(edited, az, el)
    fresh = Viewer(edited)
    try:
        want_small, _ = fresh.render({"az": str(az), "el": str(el), "w": str(cols // 2),
                                      "h": str(rows // 2)})
    finally:
        fresh.close()
    for a in algos:
        pic, h = render(srv, az=az, el=el, algorithm=a, w=cols, h=rows)
        assert h["X-Level"] == "1" and np.array_equal(shadow_of(pic), want), a
        pic, h = render(srv, az=az, el=el, algorithm=a, w=cols // 2, h=rows // 2)
        assert h["X-Level"] == "2" and np.array_equal(shadow_of(pic), shadow_of(want_small)), a
    # the highest cells cut down to a level roof, above the lowest: every Shader's height range
    # follows (none saw the new heights before its own update, so none misses the lost maximum)
    r, c = np.unravel_index(np.nanargmax(z1), z1.shape)
    status, body = post(srv, "/api/edit", {"x": c + 0.5, "y": r + 0.5, "radius": 600,
                                           "delta": -1600, "shape": "flat"})
    assert status == 200, body
    z2, _ = disk_edit(z1, dem0.grid, r, c, 600.0, -1600.0, flat=True)
    assert np.nanmin(z1) < np.nanmax(z2) < np.nanmax(z1)
    for (n, a), sh in viewer._shaders.items():
        zn = z2[::n, ::n]
        assert (sh.zmin, sh.zmax) == (np.nanmin(zn), np.nanmax(zn)), (n, a)
    assert json.loads(body)["height_range"] == [float(np.nanmin(z2)), float(np.nanmax(z2))]


def test_an_edit_at_map_coordinates_or_lon_lat(edit_server):
    """map_x/map_y (the DEM's CRS) and lon/lat name the same cell as pixel x/y."""
    srv, viewer = edit_server
    tr = viewer.dem.transform
    x, y = 80.5, 120.5
    mx, my = tr @ (x, y)
    p = json.loads(http_get(srv, f"/api/point?x={x}&y={y}&az=100&el=30")[2])
    wins = []
    for q in ({"x": x, "y": y}, {"map_x": mx, "map_y": my}, {"lon": p["lon"], "lat": p["lat"]}):
        status, body = post(srv, "/api/edit", dict(q, radius=200, delta=5))
        assert status == 200, body
        wins.append(json.loads(body)["window"])
    assert wins[0] == wins[1] == wins[2]
    status, body = post(srv, "/api/edit", {"lon": 200, "lat": 95, "radius": 1, "delta": 1})
    assert status == 400


def test_an_edit_too_large_is_refused(edit_server, monkeypatch):
    import hillshade_rt.run.viewer as model
    srv, viewer = edit_server
    monkeypatch.setattr(model, "MAX_EDIT_CELLS", 1000)
    status, text = post(srv, "/api/edit", {"x": 5, "y": 5, "radius": 1e6, "delta": 1})
    assert status == 400 and b"40000 cells: at most 1000" in text
    # the box is clipped to the DEM: the whole DEM raised at once is one edit
    monkeypatch.setattr(model, "MAX_EDIT_CELLS", 40000)
    assert post(srv, "/api/edit", {"x": 5, "y": 5, "radius": 1e6, "delta": 1})[0] == 200
    assert np.nanmax(viewer.z) == pytest.approx(np.nanmax(read_dem(DEM).heights) + 1)


def test_edits_are_serialized_with_renders(edit_server):
    """Edits posted while pictures are asked for: every picture is of the terrain before or
    after some edit, never half of one (the worker thread runs one at a time)."""
    from hillshade_rt.testing import memory_dem
    srv, viewer = edit_server
    dem0 = read_dem(DEM)
    rows, cols = dem0.shape
    az, el = 163.0, 25.0
    spots = [(40.5, 40.5), (150.5, 60.5), (100.5, 150.5)]
    masks, z = [shadow_mask(dem0, az, el)], dem0.heights.copy()
    for x, y in spots:
        z, _ = disk_edit(z, dem0.grid, int(y), int(x), 300.0, 600.0)
        masks.append(shadow_mask(memory_dem(z, dem0.transform, dem0.crs), az, el))

    def one(i):
        if i % 3 == 0:
            x, y = spots[i // 3]
            return "edit", post(srv, "/api/edit", {"x": x, "y": y, "radius": 300, "delta": 600})
        return "render", render(srv, az=az, el=el, bbox=f"0,0,{cols},{rows}", w=cols, h=rows)[0]
    with ThreadPoolExecutor(6) as ex:
        results = list(ex.map(one, range(9)))
    for kind, res in results:
        if kind == "edit":
            assert res[0] == 200
        else:   # the edits may land in any order: some subset of them is in each picture
            s = shadow_of(res)
            assert any(np.array_equal(s, m) for m in masks) or viewer_subset(s, dem0, spots, az, el)
    assert np.array_equal(shadow_of(render(srv, az=az, el=el, bbox=f"0,0,{cols},{rows}", w=cols,
                                           h=rows)[0]), masks[-1])


def viewer_subset(s, dem0, spots, az, el):
    """Whether ``s`` is the mask of the DEM with some subset of the edits at ``spots``."""
    from itertools import combinations

    from hillshade_rt.testing import memory_dem
    for k in range(len(spots) + 1):
        for sub in combinations(spots, k):
            z = dem0.heights.copy()
            for x, y in sub:
                z, _ = disk_edit(z, dem0.grid, int(y), int(x), 300.0, 600.0)
            if np.array_equal(s, shadow_mask(memory_dem(z, dem0.transform, dem0.crs), az, el)):
                return True
    return False
