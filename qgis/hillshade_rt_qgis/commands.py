"""The ``hillshade-rt`` command lines of the plugin's algorithms, finding the program, and running
it as a child process (pure Python: no qgis, no numba, no hillshade_rt import).

QGIS's own Python never imports hillshade_rt: numba (and its llvmlite) loaded into QGIS's
process breaks other plugins and QGIS itself (UMEP-processing issues #23 and #79). The program
runs in its own environment (a venv, pipx, ``pip install --user``); the plugin only builds its
argv, streams its stderr and reads its exit status. Importable without QGIS, so that the
project's tests check the command lines on any machine (tests/test_qgis_plugin.py).
"""

from __future__ import annotations

import os
import queue
import shutil
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Optional, Sequence, Union

PROGRAM = "hillshade-rt"
# the provider's setting (Processing > Providers > hillshade-rt): the program's path
SETTING_PROGRAM = "HILLSHADE_RT_PROGRAM"

# hillshade_rt.algorithms.REGISTRY's names, in its order (a test checks they agree)
ALGORITHMS = ("auto", "bounds", "brute", "smap", "horizon", "sweep")
SKYVIEW_DEFINITIONS = ("zaksek", "dozier")
SUN_MODES = ("azimuth", "time")        # the sun from --azimuth/--elevation, or --time + --tz

# variables of QGIS's own Python and GDAL/PROJ that must not reach the program: its Python
# (a venv) and rasterio's GDAL and PROJ (inside its wheel) are not QGIS's
CHILD_ENV_DROPPED = ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONEXECUTABLE",
                     "PYTHONUSERBASE", "GDAL_DATA", "GDAL_DRIVER_PATH", "PROJ_LIB",
                     "PROJ_DATA", "GDAL_SKIP")


class ProgramError(Exception):
    """A failure shown to the user as one line (the algorithms raise it as a
    QgsProcessingException)."""


def local_bin(home: Optional[str] = None) -> str:
    """``~/.local/bin``: where ``pip install --user`` and pipx put programs."""
    return os.path.join(home or os.path.expanduser("~"), ".local", "bin")


def find_program(setting: Optional[str] = None, path: Optional[str] = None,
                 home: Optional[str] = None) -> str:
    """The ``hillshade-rt`` executable: the provider setting when given (a file, or a folder
    holding it), else ``hillshade-rt`` on PATH (``path``: that search path, default the
    process's), else in ``~/.local/bin``. Raises ProgramError naming what was tried."""
    if setting and setting.strip():
        given = os.path.expanduser(setting.strip())
        if os.path.isdir(given):
            found = shutil.which(PROGRAM, path=given)
            if found:
                return found
            raise ProgramError(f"no {PROGRAM} program in {given} (the provider setting "
                               "'hillshade-rt executable')")
        if os.path.isfile(given) and os.access(given, os.X_OK):
            return given
        raise ProgramError(f"{given}: no such executable (the provider setting 'hillshade-rt "
                           "executable': Settings > Options > Processing > Providers > "
                           "hillshade-rt)")
    found = shutil.which(PROGRAM, path=path)
    if found:
        return found
    found = shutil.which(PROGRAM, path=local_bin(home))
    if found:
        return found
    raise ProgramError(f"{PROGRAM} not found on PATH nor in {local_bin(home)}: install it "
                       "(pipx install hillshade-rt) or set its path in Settings > Options > "
                       "Processing > Providers > hillshade-rt")


def _number(x: float) -> str:
    """A float as the command line writes it: no trailing zeros, no exponent for usual
    values."""
    return format(float(x), "g") if abs(float(x)) < 1e15 else repr(float(x))


def _check_choice(name: str, value: str, choices: Sequence[str]) -> str:
    if value not in choices:
        raise ProgramError(f"{name} must be one of {', '.join(choices)}, not {value!r}")
    return value


def dem_args(dem: str, output: str, band: int = 1) -> list:
    """The DEM and the output (both commands' positional arguments), the band when not the
    first."""
    if not dem:
        raise ProgramError("no DEM given")
    if not output:
        raise ProgramError("no output file given")
    return [dem, output] + (["--band", str(int(band))] if band and int(band) != 1 else [])


def sun_args(mode: str = "azimuth", azimuth: Optional[float] = None,
             elevation: Optional[float] = None, time_: Optional[str] = None,
             tz: Optional[str] = None) -> list:
    """``--azimuth A --elevation E``, or ``--time T [--tz ZONE]`` (``mode`` 'azimuth' or
    'time'). A time without a UTC offset needs a zone; without one it is taken as UTC."""
    _check_choice("the sun", mode, SUN_MODES)
    if mode == "azimuth":
        if azimuth is None or elevation is None:
            raise ProgramError("the sun by azimuth and elevation needs both")
        return ["--azimuth", _number(azimuth), "--elevation", _number(elevation)]
    if not time_:
        raise ProgramError("the sun from a date and time needs the date and time")
    return ["--time", time_, "--tz", (tz or "").strip() or "UTC"]


def common_tail(algorithm: Optional[str] = None, soft: bool = False,
                extra: Iterable[str] = ()) -> list:
    """What every command ends with: the algorithm, --soft, the user's extra options,
    --overwrite (QGIS asked where to write; the program still publishes the file whole or not
    at all)."""
    args = []
    if algorithm is not None:
        args += ["--algorithm", _check_choice("the algorithm", algorithm, ALGORITHMS)]
    if soft:
        args.append("--soft")
    return args + list(extra) + ["--overwrite"]


def split_extra(text: Optional[str]) -> list:
    """The 'additional command-line options' string as arguments (shell-like quoting, POSIX
    rules on every system so that a Windows path is quoted the same way)."""
    import shlex
    try:
        return shlex.split(text or "", posix=True)
    except ValueError as e:
        raise ProgramError(f"additional options: {e}") from None


def shadow_argv(program: str, dem: str, output: str, *, band: int = 1, sun: str = "azimuth",
                azimuth: Optional[float] = 315.0, elevation: Optional[float] = 45.0,
                time_: Optional[str] = None, tz: Optional[str] = None,
                algorithm: str = "auto", soft: bool = False, self_shadow: bool = False,
                vector: Optional[str] = None, extra: Iterable[str] = ()) -> list:
    """``hillshade-rt shadow``: the cast-shadow mask (1 shadow, 0 lit, 255 nodata) or, with
    ``soft``, the visible fraction of the sun's disk; ``vector``: also the shadow's polygons
    (a .gpkg, .geojson or .fgb file)."""
    if vector and soft:
        raise ProgramError("shadow polygons are made of the hard mask: not with soft shadows")
    return ([program, "shadow"] + dem_args(dem, output, band)
            + sun_args(sun, azimuth, elevation, time_, tz)
            + (["--self-shadow"] if self_shadow else [])
            + (["--vector", vector] if vector else [])
            + common_tail(algorithm, soft, extra))


def hillshade_argv(program: str, dem: str, output: str, *, band: int = 1,
                   sun: str = "azimuth", azimuth: Optional[float] = 315.0,
                   elevation: Optional[float] = 45.0, time_: Optional[str] = None,
                   tz: Optional[str] = None, ambient: float = 0.2,
                   algorithm: str = "auto", soft: bool = False,
                   extra: Iterable[str] = ()) -> list:
    """``hillshade-rt hillshade``: 8-bit shaded relief with cast shadows."""
    return ([program, "hillshade"] + dem_args(dem, output, band)
            + sun_args(sun, azimuth, elevation, time_, tz)
            + ["--ambient", _number(ambient)]
            + common_tail(algorithm, soft, extra))


def sun_hours_argv(program: str, dem: str, output: str, *, date: str,
                   end_date: Optional[str] = None, step_minutes: float = 10.0,
                   tz: Optional[str] = None, band: int = 1, monthly: bool = False,
                   algorithm: str = "auto", soft: bool = False,
                   extra: Iterable[str] = ()) -> list:
    """``hillshade-rt sun-hours``: hours of direct sun per cell over a day (or days up to
    ``end_date``), the sun every ``step_minutes``; days run midnight to midnight in ``tz``
    (empty: local mean solar time); ``monthly``: also one band per month after the total."""
    if not date:
        raise ProgramError("sun hours need a date")
    step = _minutes("step", step_minutes)
    args = [program, "sun-hours"] + dem_args(dem, output, band) + ["--date", date]
    if end_date:
        args += ["--end-date", end_date]
    args += ["--step", step] + (["--monthly"] if monthly else [])
    return args + _zone(tz) + common_tail(algorithm, soft, extra)


def skyview_argv(program: str, dem: str, output: str, *, band: int = 1, directions: int = 32,
                 definition: str = "zaksek", max_distance: Optional[float] = None,
                 extra: Iterable[str] = ()) -> list:
    """``hillshade-rt skyview``: the sky view factor (0..1) from each cell's exact horizon in
    ``directions`` azimuths, up to ``max_distance`` metres (None or 0: the whole DEM)."""
    args = ([program, "skyview"] + dem_args(dem, output, band)
            + ["--directions", str(int(directions)),
               "--definition", _check_choice("the definition", definition,
                                             SKYVIEW_DEFINITIONS)])
    if max_distance:
        args += ["--max-distance", _number(max_distance)]
    return args + common_tail(None, False, extra)


# one azimuth (one band), N directions, or r.horizon's --start [--end] --step (degrees)
HORIZON_MODES = ("azimuth", "directions", "range")
ANGLE_UNITS = ("degrees", "radians")
HORIZON_METHODS = ("scan", "hull")
CLEAR_SKIES = ("ineichen", "haurwitz")
QUERY_SUN_MODES = SUN_MODES + ("series",)     # also --start/--end/--step
ANIMATE_MODES = ("day", "series")             # --date, or --start/--end/--step
PROFILE_FORMATS = ("csv", "json", "geojson")  # (pvlib, pvgis, grass: one point; EXTRA)
QUERY_FORMATS = ("csv", "json", "geojson")
# the commands that take --progress (a bar over suns, frames, positions or windows)
PROGRESS_COMMANDS = ("shadow", "hillshade", "sun-hours", "horizon", "skyview", "irradiance",
                     "animate", "illumination")


def _minutes(name: str, minutes: float) -> str:
    """A step in minutes as the command line takes it: ``15min``, or ``30s``."""
    if not minutes or float(minutes) <= 0:
        raise ProgramError(f"the {name} must be more than 0 minutes")
    seconds = round(float(minutes) * 60)
    return f"{seconds // 60}min" if seconds % 60 == 0 else f"{seconds}s"


def _zone(tz: Optional[str]) -> list:
    return ["--tz", tz.strip()] if tz and tz.strip() else []


def _lift(height_above_ground: Optional[float]) -> list:
    return (["--height-above-ground", _number(height_above_ground)]
            if height_above_ground else [])


def table_format(output: str, choices: Sequence[str]) -> str:
    """A table's format from its file's extension (.geojson, .json, else csv)."""
    ext = os.path.splitext(output or "")[1].lower().lstrip(".")
    return ext if ext in choices else "csv"


def write_points_csv(path: str, points: Iterable) -> int:
    """The points of ``profile`` and ``query`` as their --points CSV: ``id,x,y`` in the DEM's
    CRS (``points``: (id, x, y) each). Returns how many."""
    import csv
    n = 0
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["id", "x", "y"])
        for pid, x, y in points:
            w.writerow([str(pid), repr(float(x)), repr(float(y))])
            n += 1
    if n == 0:
        raise ProgramError("no points given")
    return n


def horizon_argv(program: str, dem: str, output: str, *, band: int = 1,
                 mode: str = "azimuth", azimuth: float = 180.0, directions: int = 32,
                 start: float = 0.0, end: Optional[float] = None, step: float = 15.0,
                 angle_unit: str = "degrees", distance: Optional[str] = None,
                 method: str = "scan", max_distance: Optional[float] = None,
                 height_above_ground: float = 0.0, extra: Iterable[str] = ()) -> list:
    """``hillshade-rt horizon``: the horizon angle toward one azimuth (one band), toward each
    of ``directions`` azimuths, or (mode 'range', r.horizon's) every ``step`` degrees from
    ``start`` before ``end`` (None: a whole turn), one band each; in ``angle_unit``;
    ``distance``: also the distance raster."""
    _check_choice("the horizon", mode, HORIZON_MODES)
    args = [program, "horizon"] + dem_args(dem, output, band)
    if mode == "azimuth":
        args += ["--azimuth", _number(azimuth)]
    elif mode == "directions":
        args += ["--directions", str(int(directions))]
    else:
        if not step or float(step) <= 0:
            raise ProgramError("the step between azimuths must be more than 0 degrees")
        args += ["--start", _number(start or 0.0)]
        args += ["--end", _number(end)] if end is not None else []
        args += ["--step", _number(step)]
    if _check_choice("the angle unit", angle_unit, ANGLE_UNITS) != "degrees":
        args += ["--angle-unit", angle_unit]
    if distance:
        args += ["--distance", distance]
    args += ["--method", _check_choice("the method", method, HORIZON_METHODS)]
    if max_distance:
        args += ["--max-distance", _number(max_distance)]
    return args + _lift(height_above_ground) + common_tail(None, False, extra)


def profile_argv(program: str, dem: str, output: str, *, points: str, band: int = 1,
                 step: float = 1.0, height_above_ground: float = 0.0,
                 extra: Iterable[str] = ()) -> list:
    """``hillshade-rt profile``: the horizon profile of each point (``points``: a CSV or
    GeoJSON file) every ``step`` degrees, as a table in ``output`` (CSV, JSON or GeoJSON by its
    extension)."""
    if not points:
        raise ProgramError("no points given")
    if not output:
        raise ProgramError("no output file given")
    args = [program, "profile", dem or _no_dem(), "--points", points, "--step", _number(step)]
    args += _lift(height_above_ground)
    args += ["--format", table_format(output, PROFILE_FORMATS), "-o", output]
    args += ["--band", str(int(band))] if band and int(band) != 1 else []
    return args + common_tail(None, False, extra)


def _no_dem():
    raise ProgramError("no DEM given")


def query_argv(program: str, dem: str, output: str, *, points: str, band: int = 1,
               sun: str = "azimuth", azimuth: Optional[float] = 315.0,
               elevation: Optional[float] = 45.0, time_: Optional[str] = None,
               end_time: Optional[str] = None, step_minutes: float = 60.0,
               tz: Optional[str] = None, height_above_ground: float = 0.0,
               irradiance: bool = False, extra: Iterable[str] = ()) -> list:
    """``hillshade-rt query``: whether the sun reaches each point, for one sun (azimuth and
    elevation, or a time) or a series (``time_`` to ``end_time`` every ``step_minutes``), as a
    table in ``output`` (CSV, JSON or GeoJSON by its extension)."""
    _check_choice("the sun", sun, QUERY_SUN_MODES)
    if not points:
        raise ProgramError("no points given")
    if not output:
        raise ProgramError("no output file given")
    args = [program, "query", dem or _no_dem(), "--points", points]
    if sun == "series":
        if not time_ or not end_time:
            raise ProgramError("a series of suns needs its first and last time")
        args += ["--start", time_, "--end", end_time, "--step", _minutes("step", step_minutes),
                 "--tz", (tz or "").strip() or "UTC"]
    else:
        args += sun_args(sun, azimuth, elevation, time_, tz)
    args += _lift(height_above_ground) + (["--irradiance"] if irradiance else [])
    args += ["--format", table_format(output, QUERY_FORMATS), "-o", output]
    args += ["--band", str(int(band))] if band and int(band) != 1 else []
    return args + common_tail(None, False, extra)


def monthly_numbers(name: str, text: Optional[str]) -> Optional[str]:
    """A number or 12 monthly numbers (January first) as the command line takes them
    (``2.1,2.4,...``): ``text`` separated by commas, semicolons or spaces; None when empty.
    The program checks their range."""
    import re
    parts = [p for p in re.split(r"[,;\s]+", (text or "").strip()) if p]
    if not parts:
        return None
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ProgramError(f"{name}: a number or 12 monthly numbers, not {text.strip()!r}") \
            from None
    if len(values) not in (1, 12):
        raise ProgramError(f"{name}: a number or 12 monthly numbers (January first), not "
                           f"{len(values)}")
    return ",".join(_number(v) for v in values)


def sky_value(name: str, number: Optional[float], monthly: Optional[str] = None,
              raster: Optional[str] = None) -> Optional[str]:
    """An albedo's, a turbidity's or a clear-sky index's command-line value: the raster when
    given, else the monthly numbers when given, else the number (None: the number is None)."""
    if raster:
        return raster
    by_month = monthly_numbers(name, monthly)
    if by_month is not None:
        return by_month
    return None if number is None else _number(number)


def instants(text: Optional[str], date: Optional[str] = None) -> list:
    """The instants of a comma-separated list (semicolons and new lines too): each an ISO 8601
    date and time (``2026-06-21T12:00``, with or without a UTC offset), or a time of day
    (``12:00``, ``9:30:15``) on ``date``."""
    import re
    out = []
    for item in re.split(r"[,;\n]+", text or ""):
        item = item.strip()
        if not item:
            continue
        if re.fullmatch(r"\d{1,2}:\d{2}(:\d{2}(\.\d+)?)?", item):
            if not date:
                raise ProgramError(f"the time {item!r} has no date: give the date, or a date "
                                   "and time (2026-06-21T12:00)")
            hour, rest = item.split(":", 1)
            item = f"{date}T{int(hour):02d}:{rest}"
        out.append(item)
    return out


def irradiance_argv(program: str, dem: str, output: str, *, date: Optional[str] = None,
                    end_date: Optional[str] = None, step_minutes: float = 15.0,
                    tz: Optional[str] = None, band: int = 1, clear_sky: str = "ineichen",
                    linke_turbidity: Union[float, str, None] = None,
                    albedo: Union[float, str] = 0.2,
                    beam_index: Union[float, str, None] = None,
                    diffuse_index: Union[float, str, None] = None,
                    ghi: Optional[str] = None, mean: bool = False, daily_mean: bool = False,
                    monthly: bool = False, times: Sequence[str] = (), perez: bool = False,
                    skyview_directions: int = 32, height_above_ground: float = 0.0,
                    algorithm: str = "auto", soft: bool = False,
                    extra: Iterable[str] = ()) -> list:
    """``hillshade-rt irradiance``: beam, diffuse, reflected and global irradiance (4 bands,
    Wh/m2, W/m2 with ``mean``, Wh/m2 per day with ``daily_mean``; ``monthly``: one global
    band per month after them) over a day or days up to ``end_date``; or, with ``times``
    (instants, :func:`instants`), the four in W/m2 and the incidence angle at each (5 bands a
    time; the date and step are not used). ``linke_turbidity``, ``albedo``, ``beam_index`` and
    ``diffuse_index``: a number or the command line's text (:func:`sky_value`: 12 monthly
    numbers, a raster); a turbidity of None or 0 is pvlib's climatology; an index of None is
    not given (r.sun's coeff_bh, coeff_dh: the clear sky's beam and diffuse times it). With
    ``ghi`` (a measured sky) no clear-sky model is given; what the program refuses with it (a
    turbidity, an index) is passed on, for its one-line error."""
    times = list(times or ())
    if not date and not times:
        raise ProgramError("irradiance needs a date (or instants)")
    args = [program, "irradiance"] + dem_args(dem, output, band)
    if times:
        for t in times:
            args += ["--time", t]
    else:
        args += ["--date", date]
        if end_date:
            args += ["--end-date", end_date]
        args += ["--step", _minutes("step", step_minutes)]
    args += _zone(tz)
    if not ghi:
        args += ["--clear-sky", _check_choice("the clear sky", clear_sky, CLEAR_SKIES)]
    if isinstance(linke_turbidity, str) or linke_turbidity:
        args += ["--linke-turbidity", linke_turbidity if isinstance(linke_turbidity, str)
                 else _number(linke_turbidity)]
    args += ["--albedo", albedo if isinstance(albedo, str) else _number(albedo)]
    for option, index in (("--beam-index", beam_index), ("--diffuse-index", diffuse_index)):
        if index is not None and index != "":
            args += [option, index if isinstance(index, str) else _number(index)]
    if ghi:
        args += ["--ghi", ghi]
    args += (["--mean"] if mean else []) + (["--daily-mean"] if daily_mean else [])
    args += (["--monthly"] if monthly else []) + (["--perez"] if perez else [])
    args += ["--skyview-directions", str(int(skyview_directions))] + _lift(height_above_ground)
    return args + common_tail(algorithm, soft, extra)


def animate_argv(program: str, dem: str, output: str, *, band: int = 1, mode: str = "day",
                 date: Optional[str] = None, start: Optional[str] = None,
                 end: Optional[str] = None, step_minutes: float = 30.0,
                 tz: Optional[str] = None, fps: float = 12.0, size: int = 1024,
                 label: bool = True, algorithm: str = "auto",
                 extra: Iterable[str] = ()) -> list:
    """``hillshade-rt animate``: the shadows of a day (``date``, from local midnight) or of a
    series (``start`` to ``end``) every ``step_minutes`` as a GIF or MP4 (by ``output``'s
    extension)."""
    _check_choice("the animation", mode, ANIMATE_MODES)
    args = [program, "animate"] + dem_args(dem, output, band)
    if mode == "day":
        if not date:
            raise ProgramError("an animation of a day needs the date")
        args += ["--date", date]
    else:
        if not start or not end:
            raise ProgramError("an animation of a series needs its first and last time")
        args += ["--start", start, "--end", end]
    args += ["--step", _minutes("step", step_minutes)] + _zone(tz)
    args += ["--fps", _number(fps), "--size", str(int(size))]
    args += [] if label else ["--no-label"]
    return args + common_tail(algorithm, False, extra)


def illumination_argv(program: str, dem: str, output: str, *, subsolar_file: str,
                      band: int = 1, body: Optional[str] = None,
                      sun_distance: Optional[float] = None, height_above_ground: float = 0.0,
                      soft: bool = False, extra: Iterable[str] = ()) -> list:
    """``hillshade-rt illumination``: a subsolar series (CSV or JPL Horizons table) -> the
    fraction of the time lit, [the mean visible fraction of the disk with ``soft``], the
    longest shadow (hours), permanently shadowed."""
    if not subsolar_file:
        raise ProgramError("illumination needs a subsolar series file")
    args = [program, "illumination"] + dem_args(dem, output, band)
    args += ["--subsolar-file", subsolar_file]
    if body and body.strip():
        args += ["--body", body.strip()]
    if sun_distance:
        args += ["--sun-distance", _number(sun_distance)]
    return args + _lift(height_above_ground) + common_tail(None, soft, extra)


def with_progress(argv: Sequence[str]) -> list:
    """``argv`` with ``--progress json`` where its command takes it (last but --overwrite:
    after the user's extra options, since the plugin reads the lines): the program then writes
    ``{"progress": F}`` lines that :func:`parse_progress` reads."""
    argv = list(argv)
    if len(argv) > 1 and argv[1] in PROGRESS_COMMANDS:
        at = len(argv) - 1 if argv[-1] == "--overwrite" else len(argv)
        argv[at:at] = ["--progress", "json"]
    return argv


def parse_progress(line: str) -> Optional[float]:
    """The percentage (0..100) of one of the program's ``{"progress": F}`` lines; None for any
    other line."""
    text = line.strip()
    if not (text.startswith("{") and '"progress"' in text):
        return None
    import json
    try:
        value = json.loads(text)
    except ValueError:
        return None
    if not isinstance(value, dict) or set(value) != {"progress"}:
        return None
    f = value["progress"]
    if isinstance(f, bool) or not isinstance(f, (int, float)) or f != f:
        return None
    return 100.0 * min(max(float(f), 0.0), 1.0)


def child_env(environ: Optional[dict] = None) -> dict:
    """The program's environment: this process's, less QGIS's Python and GDAL/PROJ variables
    (:data:`CHILD_ENV_DROPPED`)."""
    env = dict(os.environ if environ is None else environ)
    for name in CHILD_ENV_DROPPED:
        env.pop(name, None)
    return env


def is_error_line(line: str) -> bool:
    """Whether ``line`` is the program's one-line error."""
    return line.startswith(PROGRAM + ": error:")


@dataclass
class Result:
    """How a run of the program ended."""
    returncode: int
    lines: list = field(default_factory=list)     # its stderr (and stdout), line by line
    canceled: bool = False

    def error_line(self) -> str:
        """The program's one-line error (``hillshade-rt: error: ...``), else its last line,
        else its exit status."""
        for line in reversed(self.lines):
            if is_error_line(line):
                return line
        for line in reversed(self.lines):
            if line.strip():
                return line.strip()
        return f"{PROGRAM} exited with status {self.returncode}"


def run(argv: Sequence[str], on_line: Callable[[str], None] = lambda line: None,
        is_canceled: Callable[[], bool] = lambda: False, poll: float = 0.1,
        grace: float = 5.0, env: Optional[dict] = None) -> Result:
    """Run ``argv``, handing each line it writes (stderr and stdout) to ``on_line`` as it
    comes; when ``is_canceled()`` turns true the child is terminated (SIGTERM: it removes its
    unfinished output and exits), and killed after ``grace`` seconds if still running.
    Raises ProgramError when the program cannot be started."""
    kw = {}
    if sys.platform == "win32":
        kw["creationflags"] = getattr(subprocess, "CREATE_NO_WINDOW", 0)
    try:
        child = subprocess.Popen(list(argv), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, env=child_env(env), **kw)
    except OSError as e:
        raise ProgramError(f"cannot start {argv[0]}: {e.strerror or e}") from None
    lines: list = []
    pending: "queue.Queue" = queue.Queue()

    def reader():                   # a thread: the pipe is read while the child runs
        for raw in iter(child.stdout.readline, b""):
            # tqdm's carriage returns: keep the last state of the line
            pending.put(raw.decode("utf-8", "replace").rstrip("\r\n").rsplit("\r", 1)[-1])
        child.stdout.close()

    def drain():                    # on_line runs in the caller's thread only
        while True:
            try:
                line = pending.get_nowait()
            except queue.Empty:
                return
            lines.append(line)
            on_line(line)

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    canceled = False
    while child.poll() is None:
        drain()
        if is_canceled():
            canceled = True
            child.terminate()
            deadline = time.monotonic() + grace
            while child.poll() is None and time.monotonic() < deadline:
                time.sleep(poll)
            if child.poll() is None:
                child.kill()
            break
        time.sleep(poll)
    child.wait()
    thread.join(timeout=grace)
    drain()
    return Result(child.returncode, lines, canceled)


def quote(argv: Sequence[str]) -> str:
    """The command line as one string (for the log: copy it into a shell)."""
    if sys.platform == "win32":
        return subprocess.list2cmdline(list(argv))
    import shlex
    return " ".join(shlex.quote(a) for a in argv)
