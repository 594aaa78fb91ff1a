"""The shadow / hillshade run (run.shade): its configuration is keywords only, the lighting
reaches the local runs whole (``engine.lighting.Lighting``), in memory and in windows give the
same typed result (``run.local.ShadeResult``) cell for cell, and the lighting's settings (soft
shadows, self-shadowing, ambient) reach the product."""

import dataclasses

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine.lighting import Lighting
from hillshade_rt.run import local
from hillshade_rt.run.config import RunOptions, ShadeConfig
from hillshade_rt.run.local import ShadeResult
from hillshade_rt.run.shade import shade
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

TR = Affine(10.0, 0, 5000.0, 0, -10.0, 9000.0)
SUN = {"azimuth": 203.7, "elevation": 11.0}


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    z = fractal_terrain(130, 147, seed=37, relief=300.0)
    z[60:63, 40:70] = np.nan
    return write_geotiff(tmp_path_factory.mktemp("shade") / "dem.tif", z, TR)


@pytest.fixture
def seen(monkeypatch):
    """The local runs wrapped: each call's lighting and result, by the run's name."""
    calls = {}

    def spy(name):
        real = getattr(local, name)

        def wrapped(inputs, source, scale, req, out, timer, lighting, quiet, **kw):
            res = real(inputs, source, scale, req, out, timer, lighting, quiet, **kw)
            calls[name] = (lighting, res)
            return res
        monkeypatch.setattr(local, name, wrapped)

    spy("shade_in_memory")
    spy("shade_in_windows")
    return calls


def config(dem, out, **kw):
    return ShadeConfig(files=[dem], output=str(out), sun=dict(SUN), curvature=False,
                       run=RunOptions(quiet=True, preview=kw.pop("preview", None)), **kw)


def test_the_config_takes_keywords_only(dem):
    with pytest.raises(TypeError):
        ShadeConfig([dem], "shadow")
    cfg = ShadeConfig(files=[dem], kind="hillshade")
    assert cfg.kind == "hillshade" and cfg.ambient == 0.2


def test_memory_and_windows_give_the_same_result(tmp_path, dem, seen):
    a = shade(config(dem, tmp_path / "a.tif", preview=str(tmp_path / "a.png")))
    b = shade(config(dem, tmp_path / "b.tif", preview=str(tmp_path / "b.png"),
                     window_size=(64, 64)))
    la, ra = seen["shade_in_memory"]
    lb, rb = seen["shade_in_windows"]
    assert a["processing"]["mode"] == "in memory" and b["processing"]["mode"] == "tiled"
    # the lighting reaches both whole, the same
    assert isinstance(la, Lighting) and la == lb
    assert la.as_dict() == dict(algorithm=a["algorithm"], options={}, backend=a["backend"],
                                curvature=False, refraction_k=None, soft=False,
                                self_shadow=False, ambient=0.2, lift=0.0)
    # typed results whose fields agree
    assert isinstance(ra, ShadeResult) and isinstance(rb, ShadeResult)
    assert {f.name for f in dataclasses.fields(ShadeResult)} >= {
        "dem", "suns", "sun_info", "records", "stats", "algo_stats", "zrange", "curvature",
        "gpu", "processing"}
    assert [(s.azimuth, s.elevation) for s in ra.suns] == [(s.azimuth, s.elevation)
                                                           for s in rb.suns]
    assert ra.suns[0].azimuth == pytest.approx(203.7)
    assert ra.zrange == pytest.approx(rb.zrange)
    for k in ("shadow_cells", "lit_cells", "nodata_cells"):
        assert ra.stats[k] == rb.stats[k], k
    assert ra.records[0]["shadow_fraction"] == pytest.approx(rb.records[0]["shadow_fraction"])
    assert ra.curvature["applied"] is False and rb.curvature["applied"] is False
    assert ra.processing["mode"] == "in memory" and rb.processing["mode"] == "tiled"
    # cell for cell: the outputs, and the previews (the relief and the product's shade)
    ma, mb = read_band(tmp_path / "a.tif"), read_band(tmp_path / "b.tif")
    assert 0 < (ma == 1).sum() < (ma == 0).sum()       # some shadow, mostly lit
    np.testing.assert_array_equal(ma, mb)
    pa, pb = ra.relief(203.7, 11.0), rb.relief(203.7, 11.0)
    assert pa.shape == ma.shape + (3,) and pa.dtype == np.uint8
    np.testing.assert_array_equal(pa, pb)
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def test_an_all_nodata_result_draws_black(tmp_path):
    path = write_geotiff(tmp_path / "void.tif", np.full((20, 30), np.nan, np.float32), TR)
    rep = shade(config(path, tmp_path / "o.tif", preview=str(tmp_path / "o.png")))
    assert rep["processing"]["mode"] == "all nodata" and (tmp_path / "o.png").exists()
    res = ShadeResult(dem=type("G", (), {"shape": (20, 30)})(), suns=[], sun_info=None,
                      records=[], stats=None, algo_stats={}, zrange=(None, None),
                      curvature=None, gpu=None, processing={})
    assert not res.relief(163.0, 20.0).any() and res.relief(163.0, 20.0).shape == (20, 30, 3)


@pytest.mark.parametrize("windows", [None, (64, 64)])
def test_soft_and_self_shadow_reach_the_product(tmp_path, dem, seen, windows):
    name = "shade_in_memory" if windows is None else "shade_in_windows"
    shade(config(dem, tmp_path / "hard.tif", window_size=windows))
    shade(config(dem, tmp_path / "self.tif", window_size=windows, self_shadow=True))
    assert seen[name][0].self_shadow is True
    soft = shade(config(dem, tmp_path / "soft.tif", window_size=windows, soft=True))
    assert seen[name][0].soft is True and soft["product"]["soft"] is True
    hard, self_, frac = (read_band(tmp_path / f) for f in ("hard.tif", "self.tif", "soft.tif"))
    # self-shadowing adds the faces turned from a low sun to the cast shadows
    assert ((hard == 1) <= (self_ == 1)).all() and (self_ == 1).sum() > (hard == 1).sum()
    # soft shadows: the sun's disc in view, partly on the shadows' edges
    assert frac.dtype == np.float32
    valid = frac != np.float32(-9999)
    assert ((frac[valid] > 0) & (frac[valid] < 1)).any()
    assert (valid == (hard != 255)).all()


def test_ambient_reaches_the_hillshade(tmp_path, dem, seen):
    low = shade(config(dem, tmp_path / "low.tif", kind="hillshade", self_shadow=True,
                       ambient=0.1))
    high = shade(config(dem, tmp_path / "high.tif", kind="hillshade", self_shadow=True,
                        ambient=0.5))
    assert seen["shade_in_memory"][0].ambient == 0.5
    assert low["product"]["ambient"] == 0.1 and high["product"]["ambient"] == 0.5
    a, b = read_band(tmp_path / "low.tif"), read_band(tmp_path / "high.tif")
    shadow = (a > 0) & (a < 40)           # cells in shadow: ambient x 254 + 1
    assert shadow.any() and (b[shadow] > a[shadow]).all()
