"""engine/lighting.py: the lighting settings as one value: defaults, the checks, read-only
options, copies, pickling (Dask tasks), and the Shader it builds (the same mask as the plain
reference and as a Shader built by hand)."""

import pickle

import numpy as np
import pytest

from hillshade_rt.engine.lighting import Lighting
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.model.geometry import Grid
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import fractal_terrain, reference_mask


def test_defaults_and_plain_values():
    lt = Lighting()
    assert lt.as_dict() == {"algorithm": "auto", "options": {}, "backend": "cpu",
                            "curvature": "auto", "refraction_k": None, "soft": False,
                            "self_shadow": False, "ambient": 0.2, "lift": 0.0}
    assert Lighting(curvature=None).curvature == "auto"
    assert Lighting(lift=3).lift == 3.0 and isinstance(Lighting(lift=3).lift, float)


@pytest.mark.parametrize("kw, why", [
    ({"curvature": "yes"}, "curvature must be True, False or 'auto'"),
    ({"backend": "auto"}, "a run's backend is cpu or gpu"),
    ({"lift": -1.0}, "the height above the ground must be a number of metres >= 0"),
    ({"lift": float("inf")}, "the height above the ground"),
])
def test_checks(kw, why):
    with pytest.raises(HillshadeError, match=why):
        Lighting(**kw)


def test_frozen_read_only_options_and_copies():
    opts = {"nextv": "quad"}
    lt = Lighting(algorithm="smap", options=opts)
    opts["nextv"] = "scan"                   # the caller's dict is not shared
    assert lt.options["nextv"] == "quad"
    with pytest.raises(TypeError):
        lt.options["nextv"] = "binary"
    with pytest.raises(AttributeError):
        lt.soft = True
    soft = lt.but(soft=True, ambient=0.0)
    assert soft.soft and soft.ambient == 0.0 and not lt.soft
    assert soft.options == lt.options and soft.algorithm == "smap"
    with pytest.raises(HillshadeError):
        lt.but(backend="tpu")


def test_pickles_for_dask_tasks():
    lt = Lighting(algorithm="smap", options={"better_nextv": True}, curvature=False,
                  refraction_k=0.13, soft=True, self_shadow=True, ambient=0.1, lift=2.5)
    back = pickle.loads(pickle.dumps(lt))
    assert back == lt and back.as_dict() == lt.as_dict()
    with pytest.raises(TypeError):
        back.options["better_nextv"] = False


@pytest.mark.parametrize("algorithm, azimuth", [("auto", 163.0), ("smap", 203.7),
                                                ("brute", 290.0)])
def test_the_shader_it_builds(algorithm, azimuth):
    z = fractal_terrain(24, 30, seed=13, relief=60.0)
    grid = Grid.uniform(24, 30, 3.0)
    sun = SunOver(None, azimuth, 9.0)
    lt = Lighting(algorithm=algorithm, curvature=False)
    got = render(lt.shader(z, grid), sun, "shadow")
    np.testing.assert_array_equal(got, reference_mask(z, 3.0, 3.0, azimuth, 9.0))
    by_hand = Shader(z, grid, algorithm, {}, "cpu", False)
    np.testing.assert_array_equal(got, render(by_hand, sun, "shadow"))
    if algorithm == "smap":     # marches from the ground only: said, not swapped for another
        with pytest.raises(UsageProblem, match="--algorithm smap cannot start the rays above"):
            lt.but(lift=4.0).shader(z, grid)
        return
    lifted = lt.but(lift=4.0).shader(z, grid)
    assert lifted.lift == 4.0
    np.testing.assert_array_equal(render(lifted, sun, "shadow"),
                                  reference_mask(z, 3.0, 3.0, azimuth, 9.0, lift=4.0))
