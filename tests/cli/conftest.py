import importlib

import pytest


@pytest.fixture
def calls(monkeypatch):
    """``calls(module, name)``: ``module``'s function ``name`` replaced, for the test, by one that
    runs nothing and records the (positional) arguments of each call; returns the list they go
    to (what a command hands its run: the tests of each command's options)."""
    def replace(module: str, name: str) -> list:
        seen = []
        monkeypatch.setattr(importlib.import_module(module), name, lambda *args: seen.append(args))
        return seen
    return replace
