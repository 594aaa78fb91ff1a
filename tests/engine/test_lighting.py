"""engine.lighting: the settings of a lighting run as one frozen value."""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

from hillshade_rt.engine.lighting import Lighting
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import fractal_terrain


def test_frozen_and_keyword_only():
    lit = Lighting(algorithm="bounds", options={"a": 1})
    with pytest.raises(dataclasses.FrozenInstanceError):
        lit.algorithm = "brute"
    with pytest.raises(TypeError):
        lit.options["a"] = 2           # the options are read only too
    with pytest.raises(TypeError):
        Lighting("bounds")             # keywords only


def test_checks_and_defaults():
    assert Lighting(curvature=None).curvature == "auto"
    assert Lighting(lift="2.5").lift == 2.5
    for bad in ({"curvature": "yes"}, {"backend": "auto"}, {"lift": -1.0},
                {"lift": float("nan")}):
        with pytest.raises(HillshadeError):
            Lighting(**bad)


def test_pickles_for_dask_tasks_and_but():
    lit = Lighting(algorithm="smap", options={"better_nextv": True}, soft=True, lift=1.5)
    back = pickle.loads(pickle.dumps(lit))
    assert back == lit and back.options == {"better_nextv": True}
    other = lit.but(soft=False)
    assert other.soft is False and lit.soft is True and other.lift == 1.5


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_shader_is_the_shader_of_its_settings(azimuth):
    z = fractal_terrain(96, 96, 7, relief=400.0)
    grid = Grid.uniform(96, 96, 10.0, 10.0)
    sun = SunOver(None, azimuth, 9.0)
    lit = Lighting(algorithm="brute", curvature=False, lift=0.0)
    got = render(lit.shader(z, grid), sun, "shadow")
    want = render(Shader(z, grid, "brute", {}, "cpu", False), sun, "shadow")
    np.testing.assert_array_equal(got, want)
    assert 0 < got.mean() < 1           # the case decides something
    lifted = render(lit.but(lift=30.0).shader(z, grid), sun, "shadow")
    assert lifted.sum() < got.sum()     # an observer 30 m up sees more sun
