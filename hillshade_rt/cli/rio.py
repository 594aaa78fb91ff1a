"""hillshade-rt inside rasterio's ``rio``: the ``rasterio.rio_plugins`` entry points
(``pyproject.toml``) name the objects of this module, which ``rio`` adds to its commands
(click-plugins' ``with_plugins``, rasterio/rio/main.py).

- ``rio hillshade-rt COMMAND ...``: every command, ``info`` included, under one group (no name
  can clash with rio's own or another plugin's);
- ``rio shadow``, ``rio hillshade``, ``rio sun-hours``, ``rio horizon``, ``rio skyview``,
  ``rio irradiance``: the lighting commands, DEM in and raster out as rio's own commands are, at
  the top. ``info``, ``profile``, ``query``, ``view``, ``animate`` and ``illumination`` stay in
  the group: ``rio info`` is rasterio's (``with_plugins`` adds the plugins after rio's own
  commands and a plugin of the same name would replace it), and the others' names are too
  general for rio's top level.

Each is the ``hillshade-rt`` command itself (``in_rio``): the same parameters, callback and
subcommands, not copies; only the class differs, so that a failure inside ``rio`` is still one
line with hillshade-rt's exit status (rio invokes a plugin's ``make_context`` and ``invoke``,
never the ``main`` where ``OneLineErrors`` does that).
"""

from __future__ import annotations

import click

from . import cli as _cli
from .errors import InAnotherGroup
from .horizon import horizon as _horizon
from .irradiance import irradiance as _irradiance
from .shadow import hillshade as _hillshade
from .shadow import shadow as _shadow
from .skyview import skyview as _skyview
from .sun_hours import sun_hours as _sun_hours

GROUP_NAME = "hillshade-rt"


def in_rio(command: click.Command, name: str | None = None) -> click.Command:
    """``command`` as a subcommand of another program's group: an object of a subclass of its
    class (``InAnotherGroup`` first) holding the same attributes (parameters, callback, help,
    a group's commands: the objects themselves), under ``name`` if given."""
    base = type(command)
    cls = type(f"InRio{base.__name__}", (InAnotherGroup, base), {})
    view = cls.__new__(cls)
    view.__dict__.update(command.__dict__)
    if name is not None:
        view.name = name
    return view


# the entry points (pyproject.toml, [project.entry-points."rasterio.rio_plugins"])
hillshade_rt = in_rio(_cli, GROUP_NAME)
shadow = in_rio(_shadow)
hillshade = in_rio(_hillshade)
sun_hours = in_rio(_sun_hours)
horizon = in_rio(_horizon)
skyview = in_rio(_skyview)
irradiance = in_rio(_irradiance)

TOP_LEVEL = (shadow, hillshade, sun_hours, horizon, skyview, irradiance)
