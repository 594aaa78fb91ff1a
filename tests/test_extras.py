"""Each extra of pyproject.toml brings what the docs' examples that name it import: a section of
docs/usage.md that says ``pip install 'hillshade-rt[NAME]'`` has Python examples whose
third-party imports (and the imports of the package's own modules they import, lazy ones
included: ``hillshade_rt.xarray`` imports dask for chunked arrays) must come with the
install's dependencies plus that extra. Nothing is installed: the requirements are read from
pyproject.toml, import names mapped to distributions with importlib.metadata, and what a
requirement brings along read from the installed distributions' metadata."""

from __future__ import annotations

import ast
import importlib.metadata as md
import os
import re
import sys
import tomllib

import pytest
from packaging.requirements import Requirement

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = "hillshade_rt"


def pyproject() -> dict:
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        return tomllib.load(f)


def sections(text: str):
    """(title, body) of each ``##`` section of a Markdown text."""
    parts = re.split(r"^## +(.+)$", text, flags=re.M)
    return [(parts[i].strip(), parts[i + 1]) for i in range(1, len(parts), 2)]


def python_blocks(body: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", body, flags=re.M | re.S)


def extras_named(body: str) -> set[str]:
    return set(re.findall(r"hillshade-rt\[([a-z0-9_-]+)\]", body))


def imports_of(source: str) -> set[str]:
    """The absolute imports' full module names of ``source`` (every one, inside functions too)."""
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.add(node.module)
    return out


def own_module_source(name: str) -> str | None:
    """The source of the package's module ``name``, else None; of a package (hillshade_rt.xarray)
    the sources of all its modules, which its names import."""
    rel = name.split(".")[1:]
    path = os.path.join(ROOT, PACKAGE, *rel) + ".py"
    if os.path.isfile(path):
        with open(path, encoding="utf-8") as f:
            return f.read()
    folder = os.path.join(ROOT, PACKAGE, *rel)
    if not os.path.isfile(os.path.join(folder, "__init__.py")):
        return None
    sources = []
    for here, _, files in sorted(os.walk(folder)):
        for file in sorted(f for f in files if f.endswith(".py")):
            with open(os.path.join(here, file), encoding="utf-8") as f:
                sources.append(f.read())
    return "\n".join(sources)


def third_party(names: set[str]) -> set[str]:
    return {n.split(".")[0] for n in names
            if n.split(".")[0] not in sys.stdlib_module_names and n.split(".")[0] != PACKAGE}


def example_imports(blocks: list[str]) -> set[str]:
    """Top-level third-party import names of the examples and of the package's modules they
    import (one level: the module an example names, with its lazy imports)."""
    names = set()
    for code in blocks:
        mods = imports_of(code)
        names |= third_party(mods)
        for m in mods:
            if m.split(".")[0] == PACKAGE and m != PACKAGE:
                src = own_module_source(m)
                if src is not None:
                    names |= third_party(imports_of(src))
    return names


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def brought(requirements: list[str]) -> set[str]:
    """The distributions ``requirements`` install (normalised names), with what they require in
    turn as far as the installed distributions' metadata says (extras of a requirement too)."""
    seen: set[tuple[str, str]] = set()
    todo = [(Requirement(r), "") for r in requirements]
    out = set()
    while todo:
        req, parent_extra = todo.pop()
        if req.marker is not None and not req.marker.evaluate({"extra": parent_extra}):
            continue
        name = _norm(req.name)
        for extra in sorted(req.extras) or [""]:
            if (name, extra) in seen:
                continue
            seen.add((name, extra))
            out.add(name)
            try:
                reqs = md.requires(req.name) or []
            except md.PackageNotFoundError:
                continue
            for r in reqs:
                sub = Requirement(r)
                if sub.marker is None or sub.marker.evaluate({"extra": extra}):
                    todo.append((sub, extra))
    return out


def doc_cases():
    with open(os.path.join(ROOT, "docs", "usage.md"), encoding="utf-8") as f:
        text = f.read()
    cases = []
    for title, body in sections(text):
        blocks = python_blocks(body)
        for extra in sorted(extras_named(body)):
            if blocks:
                cases.append(pytest.param(extra, title, blocks, id=f"{extra}: {title}"))
    return cases


CASES = doc_cases()


def test_the_docs_name_the_xarray_extra_with_python_examples():
    assert any(p.values[0] == "xarray" for p in CASES)


@pytest.mark.parametrize("extra, title, blocks", CASES)
def test_extra_brings_what_its_examples_import(extra, title, blocks):
    project = pyproject()["project"]
    extras = project["optional-dependencies"]
    assert extra in extras, f"docs/usage.md '{title}' names the extra {extra!r}, which is not one"
    have = brought(project["dependencies"] + extras[extra])
    dists = md.packages_distributions()
    missing = {}
    for name in sorted(example_imports(blocks)):
        assert name in dists, f"'{title}': {name} is imported but no installed distribution has it"
        if not any(_norm(d) in have for d in dists[name]):
            missing[name] = dists[name]
    assert not missing, (f"pip install 'hillshade-rt[{extra}]' does not bring what the examples "
                         f"of '{title}' import: {missing}")


def test_the_judge_sees_a_missing_requirement():
    """The xarray example's chunked arrays need dask: without it in the extra, the test fails."""
    blocks = ["import rioxarray\nimport hillshade_rt.xarray\n"]
    names = example_imports(blocks)
    assert {"rioxarray", "xarray", "dask"} <= names
    # xarray and rioxarray alone do not bring dask (were that to change, this demonstration
    # needs another missing requirement: it must not skip itself into green)
    assert "dask" not in brought(["xarray>=2023.1", "rioxarray>=0.15"])
