"""The notes a run has for people (through ``RunOptions.say``): numba about to compile kernels,
and an algorithm's note where the user can act on it."""

from __future__ import annotations

import os


def compile_note(algorithm: str, backend: str, relief: bool = False) -> str | None:
    """The line to say before numba compiles kernels that are not in its cache yet (a first
    run, or the first use of an algorithm: seconds to a minute with nothing else on screen);
    None when they are cached or the run is not on the CPU. (The command line shows it on a
    terminal only, like the progress bar: logs and pipelines keep their one summary line.)"""
    if backend != "cpu":
        return None
    from ..algorithms import lookup
    from ..algorithms._jitcache import cache_dir, cached
    # the modules whose kernels the algorithm runs (the registry's: auto, bounds, brute also
    # march over the pyramid)
    names = list(lookup(algorithm).kernel_modules)
    missing = [m for m in names + (["relief"] if relief else []) if not cached(m)]
    if not missing:
        return None
    where = cache_dir().replace(os.path.expanduser("~"), "~", 1)
    return (f"compiling the {' and '.join(missing)} kernels (first run only: cached in "
            f"{where})")


def note_to_show(algo_stats: dict, algorithm: str, options: dict, explicit: bool) -> str | None:
    """The algorithm's note, once per run, where it tells the user something they can act on: a
    method they asked for did not run (horizon's hull replaced by the scan). SMap marching every
    cell like brute on a DEM with per-row spacing (every geographic DEM, e.g. each SRTM tile) is
    said only when SMap was asked for by name (``explicit``) or with its options: with the
    default algorithm the result is the same and the note would be noise. The report keeps the
    note always."""
    note = algo_stats.get("note")
    if not note:
        return None
    if algorithm == "smap" and not options and not explicit:
        return None
    return note
