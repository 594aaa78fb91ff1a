"""docs/img/qgis.png (make docs-qgis): QGIS under Xvfb with the plugin installed from its zip,
the program's path set, and qgis/screenshot_in_qgis.py run at start-up (the plugin's algorithms
on the DEM, the map, the toolbox, the dialog; a picture of the screen). The picture is reduced
to 256 colours by ImageMagick so that it stays small.

Needs Debian's qgis, python3-qgis, xvfb, xauth and imagemagick (docs/qgis.md).

    python3 qgis/docs_screenshot.py --zip dist/hillshade_rt_qgis.zip \\
        --program .venv/bin/hillshade-rt --dem examples/DEM.tif --out docs/img/qgis.png
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
SIZE = (1600, 900)


def profile(base: str, program: str) -> str:
    """A fresh profiles folder: the plugin enabled, the provider's program setting, no
    first-run questions. Returns the folder for --profiles-path."""
    ini_dir = os.path.join(base, "profiles", "profiles", "default", "QGIS")
    os.makedirs(ini_dir)
    with open(os.path.join(ini_dir, "QGIS3.ini"), "w") as f:
        f.write("[PythonPlugins]\nhillshade_rt_qgis=true\n\n"
                f"[Processing]\nConfiguration\\HILLSHADE_RT_PROGRAM={program}\n\n"
                "[qgis]\ncheckVersion=false\nshowTips=false\nshowTips322=false\n"
                "allowVersionCheck=false\n\n"
                "[core]\nNewsFeed\\httpsfeedqgisorg\\disabled=true\n")
    return os.path.join(base, "profiles")


def qgis_path(path: str, qgis: str) -> str:
    """PATH for QGIS: its own folder first, no virtual environment's bin: QGIS's embedded Python
    takes its prefix from the first python3 on PATH (a venv's or pyenv's python3 there leaves it
    without its qgis module: "Couldn't load SIP module")."""
    return os.pathsep.join([os.path.dirname(qgis)] + [
        d for d in path.split(os.pathsep)
        if d and not os.path.exists(os.path.join(os.path.dirname(d), "pyvenv.cfg"))])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--zip", required=True)
    parser.add_argument("--program", required=True)
    parser.add_argument("--dem", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--timeout", type=float, default=180)
    args = parser.parse_args(argv)
    for tool in ("qgis", "xvfb-run", "convert"):
        if shutil.which(tool) is None:
            print(f"docs_screenshot: {tool} not found (apt-get install qgis python3-qgis xvfb "
                  "xauth imagemagick)", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory(prefix="hrt-qgis-shot-") as base:
        plugins = os.path.join(base, "plugins")
        with zipfile.ZipFile(args.zip) as z:
            z.extractall(plugins)
        raw, log = os.path.join(base, "screen.png"), os.path.join(base, "log.txt")
        # a copy: QGIS writes statistics (.aux.xml) beside the rasters it opens
        dem = shutil.copy(args.dem, os.path.join(base, os.path.basename(args.dem)))
        env = dict(os.environ, QGIS_PLUGINPATH=plugins, HRT_SHOT_DEM=dem,
                   HRT_SHOT_DIR=base, HRT_SHOT_PNG=raw, HRT_SHOT_LOG=log,
                   XDG_RUNTIME_DIR=base,
                   PATH=qgis_path(os.environ.get("PATH", ""), shutil.which("qgis")))
        env.pop("VIRTUAL_ENV", None)
        env.pop("QT_QPA_PLATFORM", None)
        command = ["xvfb-run", "-a", "-s", f"-screen 0 {SIZE[0]}x{SIZE[1]}x24",
                   "qgis", "--nologo", "--noversioncheck",
                   "--profiles-path", profile(base, os.path.abspath(args.program)),
                   "--code", os.path.join(HERE, "screenshot_in_qgis.py")]
        # its own session: on a timeout, QGIS, Xvfb and xvfb-run are stopped together
        child = subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            output, _ = child.communicate(timeout=args.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(child.pid, signal.SIGTERM)
            output, _ = child.communicate()
            print(f"docs_screenshot: QGIS still running after {args.timeout:g} s: stopped",
                  file=sys.stderr)
        if os.path.exists(log):
            with open(log) as f:
                sys.stderr.write(f.read())
        if not os.path.exists(raw):
            sys.stderr.write(output[-4000:])
            print("docs_screenshot: QGIS made no picture", file=sys.stderr)
            return 1
        tmp = args.out + ".tmp.png"
        subprocess.run(["convert", raw, "-strip", "-colors", "256", f"PNG8:{tmp}"], check=True)
        os.replace(tmp, args.out)
    print(f"{args.out}: {os.path.getsize(args.out) // 1024} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
