"""Many unrelated DEMs in one call (``--each``): each DEM its own run, into its own output named
by ``--output-pattern``'s ``{stem}`` (the input's file name without its extension).

``hillshade-rt shadow tiles/*.tif --each --output-pattern 'out/{stem}_shadow.tif' ...``: the DEMs
may lie on different grids, in different CRSs, with different sizes and value types; each is
opened, lit and written exactly as the single-DEM call ``shadow tiles/a.tif out/a_shadow.tif ...``
would (the same run function, the same config with that DEM and that output), in one process:
the imports, numba's kernels and their warm-up (once per process: ``shading.Shader.warm_up``)
are paid once, not per DEM.
Without ``--each`` several DEMs stay one mosaic (``run.shade``), as before.

Before any work: the options are checked once (a bad one is a usage error, exit status 2, as for
one DEM), no two inputs may have the same stem, and every output is claimed together
(``io.write.Claims`` through ``batch_claims``: no output is an input, the report or another
DEM's output). Then DEM after DEM: a DEM that fails (unreadable, corrupt, no such band, ...) is
named on one line and the others go on; one whose every cell is nodata (sea) gets an
all-nodata output and a note, and counts as done. The report lists every input with its
outputs, its status (``ok``, ``empty``, ``failed`` and the message) and its own run's report;
the summary line says how many succeeded and failed; :class:`BatchFailed` (exit status 1) at
the end when any failed, after the report. An interruption stops the batch: the outputs
finished stay, the one in progress is removed (``io.write.atomic_path``).
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import os
import string
from dataclasses import dataclass
from typing import Callable

from .. import __version__
from ..errors import AllNodata, HillshadeError, UsageProblem

STEM = "stem"


class BatchFailed(HillshadeError):
    """Some DEMs of a batch failed (the others are written). ``report``: the batch's report
    (each input's status and message)."""

    def __init__(self, message: str, report: dict):
        super().__init__(message)
        self.report = report


# ---------------------------------------------------------------------------------------------
# the pattern

def _fields(pattern: str) -> list[tuple[str, str, str | None, str | None]]:
    try:
        return list(string.Formatter().parse(pattern))
    except ValueError as exc:
        raise UsageProblem(f"--output-pattern {pattern!r}: {exc}") from None


def field_names(pattern: str) -> set[str]:
    """The fields of ``pattern`` by their names (``time`` of ``{time:%H%M}``)."""
    return {f.split(".")[0].split("[")[0] for _, f, _, _ in _fields(pattern) if f is not None}


def stem_of(path: str) -> str:
    """``{stem}`` of an input: its file name without the extension (an archive member's, as
    ``{tile}``)."""
    from .outputs import tile_name
    return tile_name(path)


def fill_stem(pattern: str, stem: str) -> str:
    """``pattern`` with its ``{stem}`` fields filled in, every other field and brace kept for
    the run's own pattern (``{time:%H%M}`` stays, a literal brace stays escaped)."""
    out = []
    fmt = string.Formatter()
    for literal, name, spec, conv in _fields(pattern):
        out.append(literal.replace("{", "{{").replace("}", "}}"))
        if name is None:
            continue
        if name == STEM:
            try:
                text = fmt.format_field(fmt.convert_field(stem, conv), spec or "")
            except (ValueError, TypeError) as exc:
                raise UsageProblem(f"--output-pattern {pattern!r}: {exc}") from None
            out.append(text.replace("{", "{{").replace("}", "}}"))
        else:
            out.append("{" + name + (f"!{conv}" if conv else "") + (f":{spec}" if spec else "")
                       + "}")
    return "".join(out)


def check_pattern(pattern: str | None, each: bool, others: tuple = ()) -> None:
    """The usage errors of ``--each`` and ``{stem}`` (exit status 2): ``--each`` needs a
    pattern with ``{stem}``; ``{stem}`` needs ``--each``; ``{tile}`` (a mosaic's tiles) does not
    go with it; ``others``: the pattern's other fields the command fills per output."""
    if not each:
        if pattern is not None and STEM in field_names(pattern):
            raise UsageProblem("--output-pattern: {stem} names each DEM's own output: add "
                               "--each to shade each DEM on its own (or use {tile} for the "
                               "tiles of one mosaic)")
        return
    if pattern is None:
        raise UsageProblem("--each needs --output-pattern with {stem}, e.g. "
                           "--output-pattern 'out/{stem}_shadow.tif' (one output per DEM)")
    names = field_names(pattern)
    if STEM not in names:
        raise UsageProblem(f"--output-pattern {pattern!r}: with --each it needs {{stem}} (the "
                           "input's file name without its extension), so that each DEM has "
                           "its own output")
    if "tile" in names:
        raise UsageProblem("--each and {tile} do not go together: {tile} cuts one mosaic into "
                           "its tiles; with --each use {stem}")
    bad = names - {STEM} - set(others)
    if bad:
        allowed = ", ".join((STEM,) + tuple(others))
        raise UsageProblem(f"--output-pattern {pattern!r}: unknown field(s) "
                           f"{', '.join(sorted(bad))} with --each (use {allowed})")


def refuse_with_each(given: dict) -> None:
    """A usage error naming the first option of ``given`` (flag -> given) that names one file
    or needs one DEM and so does not go with ``--each``."""
    for flag, on in given.items():
        if on:
            raise UsageProblem(f"--each and {flag} do not go together ({flag} names one file; "
                               "with --each every DEM has its own outputs)")


# ---------------------------------------------------------------------------------------------
# the claims of the batch

class BatchClaims:
    """Every path a batch writes, with the DEM that writes it (``owner``): a run's
    ``io.write.Claims`` passes each of its paths here (``batch_claims``), so no output of one
    DEM is an input, the report, or another DEM's output."""

    def __init__(self, inputs, overwrite: bool):
        from ..io.write import Claims
        self.inputs = [os.fspath(p) for p in inputs]
        self._own = Claims(self.inputs, overwrite)    # outside the batch: plain checks
        self.owners: dict[str, str] = {}
        self.owner: str | None = None                 # the DEM whose run claims now

    def claim(self, path: str, what: str) -> None:
        from ..io.write import same_file
        path = os.fspath(path)
        for p in self.inputs:      # before "already exists": an input always does
            if p != "-" and same_file(path, p):
                raise UsageProblem(f"{path}: {self._whose(self.owner)} is also an input "
                                   f"({p}); give another path")
        for q, who in self.owners.items():
            if same_file(path, q):
                if who == self.owner:
                    return      # claimed again by the same DEM's run (checked before the run)
                raise UsageProblem(f"{path}: {self._whose(who)} and {self._whose(self.owner)} "
                                   "name the same file; give paths that tell them apart")
        self._own.claim(path, what)
        self.owners[path] = self.owner or what

    @staticmethod
    def _whose(owner: str | None) -> str:
        return owner if owner is None or owner.startswith("--") else f"the output of {owner}"


# ---------------------------------------------------------------------------------------------
# the batch

@dataclass
class Each:
    """What a command does with one DEM of a batch. ``run(dem, out, as_pattern, say)``: the
    single-DEM run, into ``out`` (a path; with ``as_pattern`` a pattern of the command's own
    fields), saying its messages through ``say``, returning its report;
    ``empty(dem, out, as_pattern)``: write the all-nodata output(s) of a DEM whose every cell
    is nodata; ``fields``: the pattern's fields the single run fills (``{time}``, ...), empty
    for one output per DEM."""

    command: str
    run: Callable[[str, str, bool, Callable[[str, str], None]], dict]
    empty: Callable[[str, str, bool], None]
    fields: tuple = ()


def _label(path: str) -> str:
    from ..io import input_label
    return input_label(path)


def _is_empty(exc_or_report) -> bool:
    """A run that ended on a DEM whose every cell is nodata, or whose report says so."""
    if isinstance(exc_or_report, BaseException):
        return isinstance(exc_or_report, AllNodata)
    rep = exc_or_report
    cells = rep.get("cells") if isinstance(rep, dict) else None
    return bool(rep.get("empty")) or (isinstance(cells, dict) and cells.get("valid") == 0)


def _one_line(dem: str, exc: BaseException) -> str:
    """The failure of ``dem`` in one line, naming it."""
    msg = str(exc).splitlines()[0] if str(exc) else ""
    if isinstance(exc, MemoryError):
        msg = "out of memory (the DEM is too large for this machine)"
    elif isinstance(exc, OSError) and not isinstance(exc, HillshadeError):
        msg = f"{exc.filename + ': ' if exc.filename else ''}{exc.strerror or exc}"
    elif not isinstance(exc, HillshadeError):
        msg = (f"internal error ({type(exc).__name__}{': ' + msg if msg else ''}); please "
               "report it, HILLSHADE_RT_DEBUG=1 shows the traceback")
    return msg if dem in msg or _label(dem) in msg else f"{dem}: {msg}"


def _shown(names: list[str]) -> str:
    return ", ".join(names) if len(names) <= 4 else f"{names[0]}, {names[1]} ... {names[-1]}"


def run_each(files, pattern: str, each: Each, ro) -> dict:
    """Each DEM of ``files`` through ``each.run`` into ``pattern`` (``{stem}`` filled). ``ro``:
    the command's ``RunOptions`` (its report path, overwrite, quiet, say). Returns the batch's
    report; raises :class:`BatchFailed` after it when any DEM failed."""
    from ..io import write as writes
    from .report import Timer

    files = [os.fspath(f) for f in files]
    if not files:
        raise UsageProblem("give at least one DEM")
    check_pattern(pattern, True, each.fields)
    timer = Timer()
    # every input's stem tells its output apart
    stems: dict[str, str] = {}
    for f in files:
        s = stem_of(f)
        if s in stems:
            raise UsageProblem(f"--each: inputs {stems[s]} and {f} have the same file name "
                               f"{s!r}, so {{stem}} cannot tell their outputs apart: rename one")
        stems[s] = f
    claims = BatchClaims(files, ro.overwrite)
    if ro.report_path is not None:
        claims.owner = "--report"
        claims.claim(ro.report_path, "--report")
    plan = []
    for f in files:
        out = fill_stem(pattern, stem_of(f))
        as_pattern = bool(field_names(out))
        if not as_pattern:          # one known file: claimed now, before any work
            claims.owner = f
            claims.claim(out, "--output-pattern")
        plan.append((f, out, as_pattern))

    entries, done = [], []
    first_compile = [True]

    def say_for(dem):
        def say(kind, message):
            if kind == "compile":       # numba compiling: said once (the first DEM)
                if first_compile[0]:
                    ro.say(kind, message)
                return
            if kind == "note" and not message.startswith(_label(dem)):
                message = f"{_label(dem)}: {message}"
            ro.say(kind, message)
        return say

    token_c = writes.batch_claims.set(claims)
    try:
        for dem, out, as_pattern in plan:
            claims.owner = dem
            writes.reset()
            entry = {"input": _label(dem), "stem": stem_of(dem)}
            try:
                try:
                    rep = each.run(dem, out, as_pattern, say_for(dem))
                except HillshadeError as exc:
                    if not _is_empty(exc):
                        raise
                    writes.reset()      # whatever the failed run published (nothing) aside
                    each.empty(dem, out, as_pattern)
                    rep = None
                finally:
                    first_compile[0] = False
            except Exception as exc:   # noqa: BLE001 -- one DEM's failure, the others go on
                if os.environ.get("HILLSHADE_RT_DEBUG") and not isinstance(exc, HillshadeError):
                    writes.completed[:0] = done
                    raise
                line = _one_line(dem, exc)
                outs = list(writes.completed)     # files it finished before it failed stay
                entry.update(status="failed", message=line,
                             outputs=[p if writes.is_virtual(p) else os.path.abspath(p)
                                      for p in outs])
                done.extend(outs)
                ro.say("error", f"hillshade-rt: error: {line}")
            except BaseException:
                # interrupted: what the finished DEMs wrote stays and is said so
                writes.completed[:0] = done
                raise
            else:
                outs = list(writes.completed)
                if rep is None or _is_empty(rep):
                    note = (f"{_label(dem)}: every cell is nodata: wrote all-nodata "
                            f"{_shown(outs)}")
                    entry.update(status="empty", message=note)
                    if rep is None and not ro.quiet:     # (a run that wrote it said so)
                        ro.say("note", note)
                else:
                    entry["status"] = "ok"
                entry["outputs"] = [p if writes.is_virtual(p) else os.path.abspath(p)
                                    for p in outs]
                if rep is not None:
                    entry["report"] = rep
                done.extend(outs)
            entries.append(entry)
    finally:
        writes.batch_claims.reset(token_c)
    writes.completed[:] = done
    counts = {k: sum(1 for e in entries if e["status"] == k) for k in ("ok", "empty", "failed")}
    rep = {"command": each.command, "mode": "each", "output_pattern": pattern,
           "count": dict(inputs=len(entries), **counts), "inputs": entries,
           "seconds": {"total": timer.total()}, "version": __version__,
           "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}
    if ro.report_path is not None:
        writes.write_json(ro.report_path, rep, ro.overwrite)
    failed = [e["input"] for e in entries if e["status"] == "failed"]
    empty = [e["input"] for e in entries if e["status"] == "empty"]
    if not ro.quiet:
        line = (f"hillshade-rt: {each.command} --each: {counts['ok'] + counts['empty']} of "
                f"{len(entries)} DEM(s) done"
                + (f" ({len(empty)} all nodata: {_shown(empty)})" if empty else "")
                + (f", {len(failed)} failed ({_shown(failed)})" if failed else "")
                + f", {len(done)} file(s) written; total {timer.total():.2f} s")
        ro.say("summary", line)
    if failed:
        raise BatchFailed(f"{len(failed)} of {len(entries)} DEM(s) failed: {_shown(failed)}",
                          rep)
    return rep


# ---------------------------------------------------------------------------------------------
# the commands

def _nodata_files(dem: str, read, paths_bands, dtype: str, nodata, tags: dict, descriptions,
                  ro, cog: bool = False, resampling: str = "nearest") -> None:
    """Write each (path, bands) of ``paths_bands`` all nodata on the grid of ``dem`` (opened,
    not read)."""
    import numpy as np

    from ..io import BandWriter
    with read.open([dem]) as src:
        band = np.full(src.shape, nodata, dtype=dtype)
        for path, count in paths_bands:
            with BandWriter(path, src, count, dtype, nodata, tags, cog, resampling,
                            overwrite=ro.overwrite, fmt=ro.fmt, co=ro.creation_options) as w:
                for b in range(count):
                    w.write(b + 1, band, description=descriptions[b % len(descriptions)])


def _empty_tags(what: str) -> dict:
    return {"HILLSHADE_RT_VERSION": __version__, "VALUES": what,
            "EMPTY": "every cell of the DEM is nodata"}


def shade_each(cfg) -> dict:
    """``shadow``/``hillshade`` ``--each``: ``cfg`` (a ``ShadeConfig``) with its DEMs in
    ``files`` and ``output_pattern`` holding ``{stem}``; each DEM shaded by ``run.shade`` as
    the single-DEM call would (a pattern left with no field is that call's OUTPUT: one band
    per sun; one with ``{time}``, ``{index}``, ... its ``--output-pattern``)."""
    from ..model.sun import SunRequest
    from .config import parse_window_size
    from .outputs import OutputPattern
    from ..engine.windows import parse_size
    from .shade import shade
    from .stac import sun_from_item

    if cfg.output is not None:
        raise UsageProblem("--each writes one output per DEM: give --output-pattern with "
                           "{stem}, not -o/--output")
    check_pattern(cfg.output_pattern, True, OutputPattern.FIELDS[:-1])
    refuse_with_each({"--stac-item": cfg.stac_item is not None,
                      "--preview": cfg.run.preview is not None,
                      "--vector": cfg.vector is not None})
    # the options checked once, before any DEM (as the single run checks them first)
    cfg.check()
    sun, _ = sun_from_item(cfg.sun, True, cfg.run.say)
    try:
        SunRequest.from_options(**sun, default_sun=cfg.default_sun)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    parse_window_size(cfg.window_size)
    if cfg.max_memory is not None:
        try:
            parse_size(cfg.max_memory)
        except HillshadeError as exc:
            raise UsageProblem(f"--max-memory: {exc}") from None

    def one(dem, out, as_pattern, say):
        run = dataclasses.replace(cfg.run, report_path=None, say=say)
        return shade(dataclasses.replace(cfg, files=[dem], run=run,
                                         output=None if as_pattern else out,
                                         output_pattern=out if as_pattern else None))

    def empty(dem, out, as_pattern):
        from ..engine.products import product
        prod = product(cfg.kind, cfg.soft)
        s, _ = sun_from_item(cfg.sun, True, cfg.run.say)
        req = SunRequest.from_options(**s, default_sun=cfg.default_sun)
        with cfg.read.open([dem]) as src:
            suns, _ = req.suns(src)
        if as_pattern:
            paths = [(p[0], 1) for p in OutputPattern(out).paths(suns)]
        else:
            paths = [(out, len(suns))]
        _nodata_files(dem, cfg.read, paths, prod.dtype, prod.nodata,
                      dict(_empty_tags(prod.values), ALGORITHM=cfg.algorithm),
                      [prod.what], cfg.run, cfg.cog, prod.resampling)

    return run_each(cfg.files, cfg.output_pattern,
                    Each(cfg.kind if cfg.kind != "classes" else "shadow", one, empty,
                         OutputPattern.FIELDS[:-1]), cfg.run)


def split_files(files, each: bool, pattern: str | None, command: str):
    """The paths of a command that takes ``DEM OUTPUT``: ``(dem, output)``; with ``each`` every
    path is a DEM (``(files, None)``) and ``pattern`` names the outputs. Usage errors for
    anything else."""
    files = [os.fspath(f) for f in files]
    if each:
        check_pattern(pattern, True)
        return files, None
    check_pattern(pattern, False)
    if pattern is not None:
        raise UsageProblem(f"{command}: --output-pattern goes with --each (one output per DEM, "
                           "named by {stem}); for one DEM give DEM OUTPUT")
    if len(files) != 2:
        raise UsageProblem(f"{command}: give DEM OUTPUT (or several DEMs with --each "
                           "--output-pattern 'PATTERN_{stem}.tif')")
    return files[0], files[1]


def single_each(command: str, cfg, dems, pattern, run_one, bands: Callable[[], int],
                what: str, preflight: Callable[[], None] | None = None, dtype: str = "float32",
                nodata=-9999.0) -> dict:
    """``--each`` of a command with one output per DEM (``sun-hours``, ``horizon``,
    ``skyview``, ``irradiance``): ``cfg`` its config (``dem`` and ``output`` replaced per DEM),
    ``run_one(cfg)`` its run, ``preflight()`` its option checks (before any DEM); a DEM whose
    every cell is nodata gets ``bands()`` bands of ``nodata``."""
    check_pattern(pattern, True)
    refuse_with_each({"--preview": cfg.run.preview is not None})
    if preflight is not None:
        preflight()

    def one(dem, out, as_pattern, say):
        run = dataclasses.replace(cfg.run, report_path=None, say=say)
        return run_one(dataclasses.replace(cfg, dem=dem, output=out, run=run))

    def empty(dem, out, as_pattern):
        _nodata_files(dem, cfg.read, [(out, bands())], dtype, nodata, _empty_tags(what),
                      [what], cfg.run)

    return run_each(dems, pattern, Each(command, one, empty), cfg.run)


def sun_hours_each(cfg, dems, pattern) -> dict:
    """``sun-hours --each``: each DEM's hours of direct sun, its own sun from its own place."""
    from ..model.sun import SunRequest
    from ..model.times import parse_date, parse_step
    from .sun_hours import sun_hours

    def preflight():
        cfg.check()
        try:
            first = parse_date(cfg.date, "--date")
            last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
            parse_step(cfg.step)
            SunRequest.at_place([], **cfg.place)
        except HillshadeError as exc:
            raise UsageProblem(str(exc)) from None
        if last < first:
            raise UsageProblem("--end-date is before --date")
    return single_each("sun-hours", cfg, dems, pattern, sun_hours, lambda: 1,
                       "hours of direct sun", preflight)


def horizon_each(cfg, dems, pattern) -> dict:
    """``horizon --each``: each DEM's horizon angles (one band per azimuth)."""
    from .horizon import horizon
    refuse_with_each({"--distance": cfg.distance is not None})
    azimuths = cfg.azimuths()
    return single_each("horizon", cfg, dems, pattern, horizon, lambda: len(azimuths),
                       "horizon angle, degrees above the horizontal")


def skyview_each(cfg, dems, pattern) -> dict:
    """``skyview --each``: each DEM's sky view factor (or openness)."""
    from .skyview import skyview
    return single_each("skyview", cfg, dems, pattern, skyview, lambda: 1,
                       "openness, degrees" if cfg.openness else "sky view factor")


def irradiance_each(cfg, dems, pattern) -> dict:
    """``irradiance --each``: each DEM's four irradiance bands, its sun from its own place."""
    from .irradiance_instant import irradiance_or_instants as irradiance
    if cfg.sky_view is not None or cfg.sky_view_out is not None:
        raise UsageProblem("--sky-view and --sky-view-out name one DEM's sky view: run each "
                           "DEM on its own to read or write one")
    return single_each("irradiance", cfg, dems, pattern, irradiance, lambda: 4,
                       "irradiance (beam, diffuse, reflected, global)", cfg.check)
