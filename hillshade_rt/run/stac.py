"""STAC in a run: the sun of a satellite scene from its item (``--sun-from-stac``) and a STAC
item written for the output (``--stac-item``); the items themselves are ``io.stac``'s."""

from __future__ import annotations

import os

from ..errors import HillshadeError, UsageProblem

# the sun options --sun-from-stac replaces (run.config.SUN_KEYS less the place's)
_GIVEN = (("azimuth", "--azimuth"), ("elevation", "--elevation"), ("time", "--time"),
          ("start", "--start"), ("end", "--end"), ("step", "--step"))
# the place and atmosphere options: for a sun computed from a time only
_TIMED = (("tz", "--tz"), ("lat", "--lat"), ("lon", "--lon"), ("pressure", "--pressure"),
          ("temperature", "--temperature"), ("no_refraction", "--no-refraction"))


def sun_from_item(sun: dict, quiet: bool = True, say=None):
    """``(sun options, ItemSun or None)``: the sun options of a run (``run.config.SUN_KEYS``)
    with ``sun_from_stac`` resolved. The item's angles become ``azimuth``/``elevation``; an
    item without angles but with a datetime becomes ``time`` (the sun computed at the DEM, as
    ``--time``; said through ``say`` unless ``quiet``). Another sun option with it is a
    ``UsageProblem`` (exit status 2), found before the item is read; a bad item (no such file,
    not JSON, no sun) a ``HillshadeError`` (1)."""
    sun = dict(sun)
    path = sun.pop("sun_from_stac", None)
    if path is None:
        return sun, None
    given = [flag for key, flag in _GIVEN if sun.get(key)]
    if given:
        raise UsageProblem(f"--sun-from-stac gives the sun: not with {', '.join(given)}")
    from ..io.stac import read_item_sun
    scene = read_item_sun(os.fspath(path))
    if scene.has_angles:
        timed = [flag for key, flag in _TIMED if sun.get(key)]
        if timed:
            raise UsageProblem(f"{', '.join(timed)} apply to a sun computed from a time; the "
                               f"STAC item {scene.id} gives the sun's angles "
                               f"({scene.keys[0]}, {scene.keys[1]})")
        sun.update(azimuth=scene.azimuth, elevation=scene.elevation)
    else:
        from ..model.times import iso
        sun["time"] = (iso(scene.time),)
        if not quiet and say is not None:
            say("note", f"{path}: item {scene.id} has no view:sun_azimuth/view:sun_elevation: "
                        f"the sun computed at the DEM for its datetime {iso(scene.time)}")
    return sun, scene


def to_grid_north(req, scene, dem):
    """The SunRequest ``req`` of an item's angles with the azimuth turned from true north (the
    view extension's) to the DEM's grid north by the meridian convergence at its centre, as
    suns from times are (``site.dem_site``); ``true_azimuth`` keeps the item's. A DEM without a
    CRS, or not on the Earth: the raster's north is taken as true north. ``dem``: anything
    with ``crs``, ``transform``, ``shape`` and ``path`` (a ``DemSource``, a ``Dem``); nothing
    is read."""
    import dataclasses
    import types

    import numpy as np

    from ..model.site import dem_site
    if scene is None or not scene.has_angles:
        return req
    conv = 0.0
    if dem.crs is not None and dem.transform is not None:
        where = types.SimpleNamespace(crs=dem.crs, transform=dem.transform, shape=dem.shape,
                                      path=dem.path, centre_height=lambda: (0.0, ""))
        try:
            site = dem_site(where)
        except HillshadeError:       # another body: no true north of the Earth's to turn from
            site = None
        if site is not None:
            rows, cols = dem.shape
            conv = float(site.convergence(np.array([(rows - 1) / 2.0]),
                                          np.array([(cols - 1) / 2.0]))[0])
    return dataclasses.replace(req, azimuth=(scene.azimuth + conv) % 360.0,
                               true_azimuth=scene.azimuth)


def note_if_apart(scene, src, say) -> None:
    """Say (a note) when the DEM ``src`` lies outside the scene's bbox: its sun is then
    probably not the one meant (another scene's item). Nothing when either has no place on
    the Earth or the bbox crosses the antimeridian."""
    if scene is None or scene.bbox is None or src.crs is None or src.transform is None:
        return
    w, s, e, n = scene.bbox
    if w > e:
        return
    from ..io.stac import footprint
    try:
        _, (dw, ds, de, dn) = footprint(src.crs, src.transform, src.shape, 4)
    except HillshadeError:
        return
    if de < w or dw > e or dn < s or ds > n:
        say("note", f"the DEM ({dw:.3f}..{de:.3f} E, {ds:.3f}..{dn:.3f} N) lies outside the "
                    f"bbox of STAC item {scene.id} ({w:.3f}..{e:.3f} E, {s:.3f}..{n:.3f} N): "
                    "its sun is that scene's, elsewhere")


def scene_tags(scene) -> dict:
    """The output's tags saying where its sun came from."""
    from ..model.times import iso
    tags = {"SUN_SOURCE": "STAC item (" + ("angles: " + ", ".join(scene.keys) if scene.has_angles
                                          else "datetime, sun computed at the DEM") + ")",
            "STAC_ITEM": scene.id}
    if scene.time is not None:
        tags["STAC_DATETIME"] = iso(scene.time)
    return tags


def check_item_output(stac_item, output, pattern, claims) -> None:
    """``--stac-item`` checked before any work: it describes one local OUTPUT file, and its
    path is no input and no other output (``claims``)."""
    if stac_item is None:
        return
    import importlib.util
    if importlib.util.find_spec("pystac") is None:
        raise HillshadeError("--stac-item needs pystac: pip install 'hillshade-rt[stac]'")
    if pattern is not None or output is None:
        raise UsageProblem("--stac-item describes one OUTPUT raster, not the files of "
                           "--output-pattern")
    from ..io.write import is_virtual
    if is_virtual(output):
        raise UsageProblem("--stac-item describes a local OUTPUT file, not "
                           f"{output}")
    claims.claim(stac_item, "--stac-item")


def write_item(path: str, output: str, suns, scene, *, kind: str, algorithm: str,
               command: str | None, overwrite: bool) -> dict:
    """Write the STAC item of the finished ``output`` at ``path`` (``io.stac.write_stac_item``):
    its datetime the sun's time (the scene's for a sun from an item's angles), null with
    start/end for a series, now without a time; the view extension's sun (one sun: the true
    azimuth where it is known); the ``hillshade_rt:`` properties (product, algorithm,
    version, the command, where the sun came from)."""
    from .. import __version__
    from ..io.stac import write_stac_item
    times = [s.time for s in suns if s.time is not None]
    when = start = end = None
    if len(suns) == 1:
        when = times[0] if times else (scene.time if scene is not None else None)
    elif times:
        start, end = min(times), max(times)
    sun = None
    if len(suns) == 1:
        s = suns[0]
        sun = (s.true_azimuth if s.true_azimuth is not None else s.azimuth, s.elevation)
    props = {"hillshade_rt:product": kind, "hillshade_rt:algorithm": algorithm,
             "hillshade_rt:version": __version__,
             "hillshade_rt:command": command or "hillshade_rt.shade (Python)",
             "hillshade_rt:sun_source": ("stac" if scene is not None
                                         else "time" if times else "given")}
    if scene is not None:
        props["hillshade_rt:sun_from_stac"] = scene.id
        props["hillshade_rt:sun_from_stac_uses"] = "angles" if scene.has_angles else "datetime"
    if len(suns) > 1:
        props["hillshade_rt:bands"] = len(suns)
    try:
        return write_stac_item(path, output, when=when, start=start, end=end, sun=sun,
                               properties=props, title=f"hillshade-rt {kind}",
                               overwrite=overwrite)
    except ImportError as exc:
        raise HillshadeError(f"--stac-item needs pystac ({exc}): pip install "
                             "'hillshade-rt[stac]'") from None
