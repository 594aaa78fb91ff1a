"""The package's import graph (issue 19): each layer imports only the ones below it.

Every module of ``hillshade_rt`` is parsed with ``ast`` (not imported): every ``import`` and
``from ... import`` anywhere in it counts, deferred ones inside functions included, relative ones
resolved. ``from pkg import name`` is an import of ``pkg.name`` when that is a module, else of
``pkg``; importing ``a.b.c`` also imports the packages ``a`` and ``a.b``, except those the
importing module lies in itself (they are already being imported). Dynamic imports
(``importlib.import_module``: the package's lazy public names, the registry's ``FunctionRef``)
are not seen; ``test_registry_refs_point_into_algorithms`` checks the registry's.
"""

from __future__ import annotations

import ast
import pathlib


import hillshade_rt

ROOT = pathlib.Path(hillshade_rt.__file__).parent
PACKAGE = "hillshade_rt"
ALGORITHMS = "hillshade_rt.algorithms"
# what the algorithms may import from above their own package
# (``_preload``: numba's start-up, which ``_jitcache`` sets up for every kernel)
BELOW_ALGORITHMS = {"hillshade_rt", "hillshade_rt.errors", "hillshade_rt.model",
                    "hillshade_rt.model.geometry", "hillshade_rt.model.sun",
                    "hillshade_rt._preload"}


def modules() -> dict[str, pathlib.Path]:
    """Dotted name -> file of every module of the package (a package by its __init__.py)."""
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _is_package(path: pathlib.Path) -> bool:
    return path.name == "__init__.py"


def _targets(name: str, path: pathlib.Path, known) -> list[tuple[str, str, int]]:
    """(module, what was named, line) for every import statement of module ``name``: the
    module of the package each one imports (or None when outside the package)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    here = name if _is_package(path) else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append((alias.name, alias.name, node.lineno))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here
                for _ in range(node.level - 1):
                    base = base.rpartition(".")[0]
                source = f"{base}.{node.module}" if node.module else base
            else:
                source = node.module
            for alias in node.names:
                sub = f"{source}.{alias.name}"
                found.append((sub if sub in known else source, alias.name, node.lineno))
    return found


def _resolve(target: str, known) -> str | None:
    """The longest prefix of ``target`` that is a module of the package."""
    while target and target not in known:
        target = target.rpartition(".")[0]
    return target or None


def graph() -> dict[str, set[str]]:
    """module -> the modules of the package it imports (directly, or as parent packages)."""
    known = modules()
    edges: dict[str, set[str]] = {m: set() for m in known}
    for name, path in known.items():
        for target, _, _ in _targets(name, path, known):
            mod = _resolve(target, known)
            if mod is None or mod == name:
                continue
            edges[name].add(mod)
            parent = mod.rpartition(".")[0]
            while parent:                  # importing a.b.c runs a and a.b first ...
                if not (name == parent or name.startswith(parent + ".")):   # ... unless inside
                    edges[name].add(parent)
                parent = parent.rpartition(".")[0]
    return edges


def cycles(edges: dict[str, set[str]] | None = None) -> list[tuple[str, ...]]:
    """Every elementary cycle of the import graph (``graph()``, or ``edges``), each as the
    modules along it starting from its smallest name, sorted: for each start, the paths
    through larger names only that come back to it (each cycle is found once, from its
    smallest module)."""
    edges = graph() if edges is None else edges
    found = []
    for start in sorted(edges):
        stack = [(start, iter(sorted(edges[start])))]
        path, on_path = [start], {start}
        while stack:
            node, it = stack[-1]
            nxt = next(it, None)
            if nxt is None:
                stack.pop()
                on_path.discard(path.pop())
            elif nxt == start:
                found.append(tuple(path))
            elif nxt > start and nxt not in on_path and nxt in edges:
                path.append(nxt)
                on_path.add(nxt)
                stack.append((nxt, iter(sorted(edges[nxt]))))
    return sorted(found)


def _within(edges, keep) -> dict[str, set[str]]:
    return {m: {t for t in ts if keep(t)} for m, ts in edges.items() if keep(m)}


def _in_algorithms(m: str) -> bool:
    return m == ALGORITHMS or m.startswith(ALGORITHMS + ".")


def test_graph_sees_deferred_and_relative_imports():
    """The walk itself: a relative import at the top (brute -> ._cuda), one inside a function
    (gpu.GpuDem.canonical -> .algorithms.frames), ``from . import module`` (sweep -> brute), a
    parent package (gpu -> algorithms, through algorithms._cuda)."""
    edges = graph()
    assert "hillshade_rt.algorithms._cuda" in edges["hillshade_rt.algorithms.brute"]
    assert "hillshade_rt.algorithms.frames" in edges["hillshade_rt.engine.gpu"]
    assert "hillshade_rt.algorithms.brute" in edges["hillshade_rt.algorithms.sweep"]
    assert "hillshade_rt.algorithms" in edges["hillshade_rt.engine.gpu"]
    assert "hillshade_rt.algorithms" not in edges["hillshade_rt.algorithms.brute"]   # its own
    assert cycles({"a": {"b"}, "b": {"a", "c"}, "c": {"b"}, "d": {"d"}}) == [
        ("a", "b"), ("b", "c"), ("d",)]


def test_algorithms_never_import_gpu_or_the_layers_above():
    """algorithms/ imports only itself and geometry, errors, sun: never gpu (the device runtime
    sits above it and imports it), the engine, the command line or the I/O."""
    edges = graph()
    bad = {(m, t) for m, ts in edges.items() if _in_algorithms(m) for t in ts
           if not _in_algorithms(t) and t not in BELOW_ALGORITHMS}
    assert not bad


def test_no_cycle_inside_algorithms_or_with_gpu():
    edges = _within(graph(), lambda m: _in_algorithms(m) or m == "hillshade_rt.engine.gpu")
    assert cycles(edges) == []


def private_uses(name: str, path: pathlib.Path, known) -> list[str]:
    """Where module ``name`` uses another module's private name (one leading underscore): takes
    it in an import, or reads it off a module of the package it imported (``bounds._strips``).
    Private *modules* (``_cuda``, ``_jitcache``) are their package's, not counted."""
    bad = []
    bound = set()         # local names of modules of the package imported here
    for target, what, line in _targets(name, path, known):
        if target in known and target.endswith("." + what):
            bound.add(what)
        elif (what.startswith("_") and not what.startswith("__")
              and _resolve(target, known) not in (None, name)):
            bad.append(f"{path.name}:{line}: {what} from {target}")
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            bound.update(a.asname for a in node.names if a.asname)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in bound and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            bad.append(f"{path.name}:{node.lineno}: {node.value.id}.{node.attr}")
    return bad


def test_no_module_uses_private_names_of_another():
    """A name with a leading underscore is its module's own: no module of the package imports
    one from another module nor reads one off it."""
    known = modules()
    bad = [use for name, path in known.items() for use in private_uses(name, path, known)]
    assert not bad


def test_registry_refs_point_into_algorithms():
    """The registry's lazy references (imported at their first call) name functions of modules
    in algorithms/: the one import the walk cannot see stays inside the package, downward."""
    from hillshade_rt.algorithms import REGISTRY
    known = modules()
    for spec in REGISTRY.values():
        for ref in filter(None, (spec.cpu, spec.gpu)):
            assert f"{ALGORITHMS}.{ref.module}" in known, ref
            assert callable(ref.load()), ref


def test_registry_imports_no_algorithm():
    """Importing the registry imports no algorithm (no numpy, no numba): the command line
    builds its options from it before any of that is loaded."""
    edges = graph()
    assert edges[ALGORITHMS] <= {"hillshade_rt.errors"}


def test_no_cycles_in_package():
    """No import cycle anywhere in the package, deferred imports included. (The cycles there
    were, 31 of them, all went through gpu.py and the algorithm modules that imported its
    ``cuda``/``kernel``: ``algorithms/_cuda.py`` ended them.)"""
    assert cycles() == []


# the layers, top to bottom (docs/architecture.md): a module imports only modules of its own
# layer or of the layers below (its own layer: the cycle test keeps that one-way)
LAYERS = [
    # warm runs the commands themselves (their kernels compiled as they use them); testing
    # serves the tests and benchmarks, which use every layer (nothing in the package imports it)
    ("hillshade_rt.__main__", "hillshade_rt.warm", "hillshade_rt.testing"),
    # the front doors
    ("hillshade_rt.cli",),
    ("hillshade_rt.api", "hillshade_rt.xarray"),
    # whole runs, files in and out
    ("hillshade_rt.run",),
    # engine/: three layers of its own (the array API, the window job and the irradiance
    # physics over the shader, over the GPU runtime, products and per-cell suns)
    ("hillshade_rt.engine.arrays", "hillshade_rt.engine.windows",
     "hillshade_rt.engine.sun_sums", "hillshade_rt.engine.irradiance"),
    ("hillshade_rt.engine.shader", "hillshade_rt.engine.lighting"),
    ("hillshade_rt.engine", "hillshade_rt.io", "hillshade_rt.pictures"),
    ("hillshade_rt.algorithms",),
    ("hillshade_rt.model",),
    ("hillshade_rt.errors", "hillshade_rt._preload", "hillshade_rt._lazy", "hillshade_rt"),
]

# the modules that may sit loose in hillshade_rt/ (every other module lives in its layer's folder)
LOOSE = {"__init__", "__main__", "_lazy", "_preload", "errors", "api", "warm", "testing"}


def layer_of(module: str) -> int:
    """The index in ``LAYERS`` of ``module`` (0 the top): the longest prefix listed."""
    best, depth = None, -1
    for i, prefixes in enumerate(LAYERS):
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and p.count(".") > depth:
                best, depth = i, p.count(".")
    assert best is not None, f"{module} is in no layer: add it to LAYERS"
    return best


def test_every_import_goes_down_the_layers():
    """Following the command line to a kernel crosses each layer once, downward: no module
    imports a module of a layer above its own (deferred imports included)."""
    edges = graph()
    up = sorted(f"{m} -> {t}" for m, ts in edges.items() for t in ts
                if layer_of(t) < layer_of(m))
    assert not up


def test_no_click_below_the_command_line():
    """Only cli/ imports click: the library (api, run, ...) raises HillshadeError and
    UsageProblem, and the command line turns them into its messages and exit statuses."""
    bad = []
    for name, path in modules().items():
        if name == "hillshade_rt.cli" or name.startswith("hillshade_rt.cli."):
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                     else [])
            bad += [f"{name}:{node.lineno}" for n in names if n.split(".")[0] == "click"]
    assert not bad


def test_the_folders_are_the_layers():
    """No module sits loose beside the layers' folders (only the package's entry points, its
    errors and the top layer's modules), and every folder of the package is a layer of
    ``LAYERS`` (or lies inside one) and is named in docs/architecture.md."""
    loose = sorted(p.stem for p in ROOT.glob("*.py") if p.stem not in LOOSE)
    assert not loose, f"modules outside the layers' folders: {loose}"
    doc = (ROOT.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    for folder in sorted(p.parent.name for p in ROOT.glob("*/__init__.py")):
        layer_of(f"{PACKAGE}.{folder}")
        assert f"{folder}/" in doc, f"docs/architecture.md does not describe {folder}/"
