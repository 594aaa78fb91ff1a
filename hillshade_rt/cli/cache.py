"""``hillshade-rt cache``: where numba keeps the compiled kernels, and ``--prune``: remove what
no run of this install will load again (other versions' folders, stale index and data files);
the same for the ``--context`` block statistics (``run.statscache``: entries whose files
changed or are gone)."""

from __future__ import annotations

import click

from .errors import errors_to_click


def _mb(n: int) -> str:
    return f"{n / 1e6:.1f} MB"


@click.command("cache")
@click.option("--prune", is_flag=True,
              help="Remove the folders of other versions of the kernels (or of numba) and the "
                   "stale files of this one, and the --context statistics whose files changed.")
@errors_to_click
def cache(prune):
    """Show where the compiled kernels are cached (NUMBA_CACHE_DIR, else
    $XDG_CACHE_HOME/hillshade-rt/numba or ~/.cache/hillshade-rt/numba) and how much of it is
    stale; with --prune, remove the stale part.

    Each version of the kernels compiles into its own folder, named after a digest of their
    sources and numba's version, and the old ones stay behind. Another installed version of
    hillshade-rt sharing the folder (another virtual environment) compiles its kernels again on
    its next run after a --prune.

    Also the block statistics of --context rasters kept between runs (HILLSHADE_RT_STATS_DIR,
    else $XDG_CACHE_HOME/hillshade-rt/stats): --prune removes the entries whose files changed
    or are gone; removing the folder clears them all."""
    from ..algorithms._jitcache import prune as prune_cache
    from ..algorithms._jitcache import survey
    found = prune_cache() if prune else survey()
    others = found["other_versions"]
    stale = found["stale"]
    verb = "removed" if prune else "stale"
    click.echo(f"kernel cache: {found['root']}")
    click.echo(f"this version: {found['current']} ({_mb(found['bytes'])})")
    click.echo(f"other versions' folders, {verb}: {len(others)} "
               f"({_mb(sum(s for _, s in others))})")
    click.echo(f"stale files of this version, {verb}: {len(stale)} "
               f"({_mb(sum(s for _, s in stale))})")
    from ..run.statscache import survey as stats_survey
    st = stats_survey(prune)
    if st["root"] is None:
        click.echo("context statistics cache: off (HILLSHADE_RT_STATS_DIR)")
    else:
        click.echo(f"context statistics cache: {st['root']}")
        click.echo(f"entries: {st['entries']} ({_mb(st['bytes'])}); whose files changed or "
                   f"are gone, {verb}: {len(st['stale'])} "
                   f"({_mb(sum(s for _, s in st['stale']))})")
    if not prune and (others or stale or st["stale"]):
        click.echo("hillshade-rt cache --prune removes them")
