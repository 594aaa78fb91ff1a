"""hillshade_rt.testing, the helpers the tests and benchmarks share, and the rule that goes with
it: tests and benchmarks import shared code from there only. No ``sys.path`` edits, no import of
``conftest``, of another test file or of another script of tests/ or benchmarks/ (such imports
work only from one folder, or with the path edited)."""

import ast
import os
import subprocess
import sys

import pytest

from hillshade_rt import testing
from hillshade_rt.testing import BENCH_REAL_DEMS, SMALL_REAL_DEMS, data_path, real_dems

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDERS = ("tests", "benchmarks")


def _sources():
    for folder in FOLDERS:
        for dirpath, dirnames, files in os.walk(os.path.join(ROOT, folder)):
            dirnames[:] = [d for d in dirnames if d not in ("data", "__pycache__")]
            for f in sorted(files):
                if f.endswith(".py"):
                    yield os.path.join(dirpath, f)


def _local_modules():
    """Names a file of tests/ or benchmarks/ could be imported as (conftest, test_x, bench_x,
    ptx_check, ...), and the folders themselves."""
    return {os.path.splitext(os.path.basename(p))[0] for p in _sources()} | set(FOLDERS)


def _violations(path, local):
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), path)
    rel = os.path.relpath(path, ROOT)
    for node in ast.walk(tree):            # imports inside functions included
        where = f"{rel}:{node.lineno}" if hasattr(node, "lineno") else rel
        if (isinstance(node, ast.Attribute) and node.attr == "path"
                and isinstance(node.value, ast.Name) and node.value.id == "sys"):
            yield f"{where}: sys.path"
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                yield f"{where}: relative import"
            elif node.module == "sys" and any(a.name == "path" for a in node.names):
                yield f"{where}: from sys import path"
            elif node.module.split(".")[0] in local:
                yield f"{where}: from {node.module} import ..."
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in local:
                    yield f"{where}: import {a.name}"
        elif (isinstance(node, ast.Call) and node.args
              and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
              and ((isinstance(node.func, ast.Attribute) and node.func.attr == "import_module")
                   or (isinstance(node.func, ast.Name) and node.func.id == "__import__"))
              and node.args[0].value.split(".")[0] in local):
            yield f"{where}: imports {node.args[0].value!r} by name"


def test_tests_and_benchmarks_import_shared_code_from_hillshade_rt_testing_only():
    local = _local_modules()
    assert {"conftest", "test_testing", "bench_cpu"} <= local    # the scan sees both folders
    bad = [v for p in _sources() for v in _violations(p, local)]
    assert not bad, ("import shared helpers from hillshade_rt.testing (fixtures stay in "
                     "tests/conftest.py), never by editing sys.path or importing a file of "
                     "tests/ or benchmarks/:\n" + "\n".join(bad))


def test_the_scan_catches_each_kind(tmp_path):
    p = tmp_path / "x.py"
    p.write_text("import sys, os\n"
                 "sys.path.insert(0, os.path.dirname(__file__))\n"
                 "from conftest import fractal_terrain\n"
                 "import test_tiling\n"
                 "def f():\n"
                 "    from bench_cpu import timed\n"
                 "    import importlib\n"
                 "    importlib.import_module('terrain')\n"
                 "from . import helpers\n"
                 "from hillshade_rt.testing import spectral\n"
                 "'''sys.path in a docstring is fine'''\n")
    found = list(_violations(str(p), {"conftest", "test_tiling", "bench_cpu", "terrain"}))
    assert sorted(v.split(": ", 1)[1] for v in found) == sorted([
        "sys.path", "from conftest import ...", "import test_tiling",
        "from bench_cpu import ...", "imports 'terrain' by name", "relative import"]), found


def test_the_module_imports_nothing_heavy():
    """It ships in the package: numpy at module level, nothing else that is slow or optional."""
    code = ("import sys, hillshade_rt.testing\n"
            "print(' '.join(sorted({m.split('.')[0] for m in sys.modules})))")
    mods = set(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True).stdout.split())
    assert "numpy" in mods
    assert not mods & {"pytest", "numba", "rasterio", "click", "affine", "pyproj", "pvlib",
                       "hypothesis", "dask", "tifffile"}, mods


def test_real_dems_are_in_the_checkout_with_labels():
    for names in (BENCH_REAL_DEMS, SMALL_REAL_DEMS):
        dems = real_dems(names)
        assert [os.path.basename(p) for p, _ in dems] == list(names)
        assert all(os.path.isfile(p) and label for p, label in dems)
    assert real_dems()[1][1].startswith("Everest") and real_dems()[-1][1].startswith("Jacksboro")
    assert os.path.isfile(data_path("jacksboro_fault_srtm3_mpl_403x344.tif"))


def test_real_dems_say_when_the_files_are_absent(tmp_path):
    with pytest.raises(FileNotFoundError, match="not a source checkout"):
        real_dems(root=tmp_path)
    with pytest.raises(FileNotFoundError, match="not a source checkout"):
        data_path("x.tif", root=tmp_path)
    (tmp_path / "tests" / "data").mkdir(parents=True)
    with pytest.raises(FileNotFoundError) as e:
        real_dems(root=tmp_path)
    for name in BENCH_REAL_DEMS:
        assert name in str(e.value)
    with pytest.raises(KeyError, match="not a real DEM"):
        real_dems(["nowhere.tif"])


def test_generators_are_reproducible():
    """Same arguments, same arrays (the benchmarks' figures and the tests' cases rely on it)."""
    for f, args in ((testing.fractal_terrain, (33, 47, 5)), (testing.spectral, (40, 3.2, 1)),
                    (testing.spectral_f64, (32,)), (testing.smooth_facets, (40,)),
                    (testing.ridges, (10, 20, 30))):
        a, b = f(*args), f(*args)
        assert a.dtype == "float32" and a.tobytes() == b.tobytes(), f.__name__
    z = testing.spectral(64, 3.2, seed=2)
    assert testing.tiled(z, 150).shape == (150, 150)
    assert (testing.tiled(z, 150)[64:128, :64] == z).all()
