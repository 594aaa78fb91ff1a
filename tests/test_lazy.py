"""_lazy.py: a module's public names imported when first asked for (PEP 562), as ``hillshade_rt``
and ``hillshade_rt.io`` use it: importing either loads none of its submodules (nor numpy, numba
or GDAL), and each name, once asked for, is the object of the submodule named for it."""

import importlib
import json
import subprocess
import sys

import pytest

from hillshade_rt._lazy import lazy_names


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A package ``lazypkg`` whose names ``Alpha`` and ``beta`` live in its submodules ``a`` and
    ``sub.b`` (each counts its imports in ``lazypkg.loads``)."""
    root = tmp_path / "lazypkg"
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text(
        "from hillshade_rt._lazy import lazy_names\n"
        "loads = []\n"
        "_EXPORTS = {'Alpha': 'a', 'beta': 'sub.b'}\n"
        "__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())\n")
    (root / "a.py").write_text("from . import loads\nloads.append('a')\nclass Alpha:\n    pass\n")
    (root / "sub" / "__init__.py").write_text("")
    (root / "sub" / "b.py").write_text("from .. import loads\nloads.append('b')\n"
                                       "def beta():\n    return 42\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield importlib.import_module("lazypkg")
    for name in [m for m in sys.modules if m == "lazypkg" or m.startswith("lazypkg.")]:
        del sys.modules[name]


def test_a_name_is_imported_when_first_used_and_kept(package):
    assert package.loads == [] and "lazypkg.a" not in sys.modules
    alpha = package.Alpha
    assert package.loads == ["a"] and "lazypkg.a" in sys.modules
    assert alpha is sys.modules["lazypkg.a"].Alpha
    assert "lazypkg.sub.b" not in sys.modules                 # only the submodule asked for
    assert vars(package)["Alpha"] is alpha                    # kept: no second look-up
    assert package.beta() == 42 and package.loads == ["a", "b"]
    from lazypkg import beta                                  # noqa: F401 -- from-import too
    assert beta is sys.modules["lazypkg.sub.b"].beta and package.loads == ["a", "b"]


def test_dir_lists_the_names_before_they_load_and_others_raise(package):
    names = dir(package)
    assert names == sorted(names) and {"Alpha", "beta", "loads", "_EXPORTS"} <= set(names)
    assert package.loads == []
    with pytest.raises(AttributeError, match="module 'lazypkg' has no attribute 'gamma'"):
        package.gamma
    assert not hasattr(package, "a_typo") and package.loads == []


def test_the_helper_alone():
    namespace = {}
    getattr_, dir_ = lazy_names("json", {"JSONDecoder": "decoder"}, namespace)
    assert getattr_("JSONDecoder") is json.decoder.JSONDecoder
    assert namespace == {"JSONDecoder": json.decoder.JSONDecoder}
    assert dir_() == ["JSONDecoder"]
    with pytest.raises(AttributeError):
        getattr_("loads")                     # json has it, but it is not exported lazily


@pytest.mark.parametrize("package", ["hillshade_rt", "hillshade_rt.io"])
def test_every_exported_name_is_its_submodules(package):
    module = importlib.import_module(package)
    exports = module._EXPORTS
    assert set(module.__all__) >= set(exports) and set(dir(module)) >= set(exports)
    for name, sub in exports.items():
        assert getattr(module, name) is getattr(importlib.import_module(f"{package}.{sub}"),
                                                name), name


def test_importing_the_packages_loads_nothing_heavy():
    """In a fresh interpreter: ``import hillshade_rt`` and ``hillshade_rt.io`` import no
    submodule with a name of theirs, nor numpy, numba or GDAL; the first name asked for
    does."""
    code = ("import sys, json\n"
            "import hillshade_rt, hillshade_rt.io\n"
            "before = sorted(m for m in sys.modules if m.split('.')[0] in "
            "{'numpy', 'numba', 'rasterio', 'osgeo'} or m in "
            "('hillshade_rt.api', 'hillshade_rt.engine.arrays', 'hillshade_rt.io.source'))\n"
            "hillshade_rt.HillshadeError\n"
            "light = 'hillshade_rt.errors' in sys.modules and 'numpy' not in sys.modules\n"
            "hillshade_rt.io.read_dem\n"
            "after = [m for m in ('numpy', 'hillshade_rt.io.source') if m in sys.modules]\n"
            "print(json.dumps([before, light, after]))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    before, light, after = json.loads(r.stdout)
    assert before == [] and light is True
    assert after == ["numpy", "hillshade_rt.io.source"]
