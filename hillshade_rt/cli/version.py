"""``hillshade-rt --version``: this version and what it runs on (numba, GDAL, rasterio, numpy,
the backends), for bug reports. Cheap: the versions come from the installed packages' metadata,
GDAL's from the name of the library rasterio's wheel carries (else from rasterio), and the GPU line from the files of
the NVIDIA driver; CUDA is never initialised (``--backend gpu`` and ``hillshade-rt info`` do
that)."""

from __future__ import annotations

import glob
import os
import platform
import sys

import click

from .. import __version__


def _installed(dist: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version(dist)
    except PackageNotFoundError:
        return None


def cpu_threads() -> tuple[int, str]:
    """numba's thread count as numba sets it: NUMBA_NUM_THREADS, else the CPUs this process may
    run on."""
    if os.environ.get("NUMBA_NUM_THREADS", "").strip().isdigit():
        return int(os.environ["NUMBA_NUM_THREADS"]), "NUMBA_NUM_THREADS"
    try:
        return len(os.sched_getaffinity(0)), "CPUs available"
    except AttributeError:
        return os.cpu_count() or 1, "CPUs"


def gpus_seen() -> list[str] | None:
    """The NVIDIA GPUs the loaded driver lists (``/proc/driver/nvidia/gpus/*/information``,
    Linux), without CUDA: [] with no driver, None where that cannot be told this way."""
    if not sys.platform.startswith("linux"):
        return None
    names = []
    for info in sorted(glob.glob("/proc/driver/nvidia/gpus/*/information")):
        try:
            with open(info, encoding="utf-8", errors="replace") as fh:
                model = next((ln.split(":", 1)[1].strip() for ln in fh
                              if ln.startswith("Model:")), "NVIDIA GPU")
        except OSError:
            model = "NVIDIA GPU"
        names.append(model)
    if not names and os.path.exists("/dev/dxg"):      # WSL: the driver lives in Windows
        return None
    return names


def gdal_version() -> str:
    """GDAL's version: from the name of the libgdal a rasterio wheel carries
    (``rasterio.libs/libgdal-<hash>.so.<soversion>.<major>.<minor>.<patch>``) without loading it;
    else from rasterio, imported (a tenth of a second: a rasterio built on the system's GDAL)."""
    import re
    try:
        from importlib.metadata import distribution
        libs = str(distribution("rasterio").locate_file("rasterio.libs"))
        for name in sorted(glob.glob(os.path.join(libs, "libgdal*"))):
            m = re.search(r"\.so\.\d+\.(\d+\.\d+\.\d+)$", name)
            if m:
                return m.group(1)
    except Exception:     # noqa: BLE001 -- then rasterio says
        pass
    try:
        import rasterio
        return rasterio.__gdal_version__
    except Exception as exc:   # noqa: BLE001 -- a broken GDAL is worth reporting, not a crash
        return f"not loadable ({type(exc).__name__})"


def version_text() -> str:
    """The lines of ``--version``."""
    threads, why = cpu_threads()
    lines = [f"hillshade-rt {__version__}",
             f"python {platform.python_version()} ({sys.executable})",
             f"numba {_installed('numba')}, llvmlite {_installed('llvmlite')}",
             f"GDAL {gdal_version()} (rasterio {_installed('rasterio')})",
             f"numpy {_installed('numpy')}",
             f"backend cpu: numba, {threads} threads ({why})"]
    cuda = _installed("numba-cuda")
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        gpu = "numba's CUDA simulator (NUMBA_ENABLE_CUDASIM=1)"
    elif cuda is None:
        gpu = "not installed (pip install 'hillshade-rt[gpu]': numba-cuda)"
    else:
        seen = gpus_seen()
        found = ("GPU not looked for on this system" if seen is None else
                 "no NVIDIA driver loaded, no GPU" if not seen else
                 f"{len(seen)} GPU(s) listed by the driver: {', '.join(seen)}")
        gpu = f"numba-cuda {cuda}; {found}"
    lines.append(f"backend gpu: {gpu}")
    return "\n".join(lines)


def show_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    """``--version``'s callback (an eager flag, like click's ``version_option``)."""
    if not value or ctx.resilient_parsing:
        return
    click.echo(version_text(), color=ctx.color)
    ctx.exit()


version_option = click.option(
    "--version", is_flag=True, expose_value=False, is_eager=True, callback=show_version,
    help="Show the version, with numba's, GDAL's, rasterio's, numpy's and the backends', "
         "and exit.")
