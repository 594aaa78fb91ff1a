"""Public names imported when first used (PEP 562), for the package and for ``io``: a module
whose names live in its submodules loads none of them (nor numpy, numba, GDAL) until a name is
asked for."""

import importlib


def lazy_names(package: str, exports: dict, namespace: dict):
    """(``__getattr__``, ``__dir__``) for the module ``package`` whose names ``exports`` maps to
    the submodule holding each; a name once loaded is kept in ``namespace`` (its globals)."""
    def __getattr__(name):
        if name in exports:
            value = getattr(importlib.import_module(f".{exports[name]}", package), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(namespace) | set(exports))
    return __getattr__, __dir__
