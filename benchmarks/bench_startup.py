"""Start-up of the command line (issue 23, item 6): the wall time of ``hillshade-rt --help`` and
of an az/el ``shadow`` run on the bundled DEM (kernels already cached), median of 5 fresh
processes each, ``--version``, and ``rio --help`` of the ``rio`` beside each script (rio loads
every plugin's command at start: hillshade-rt's command line is imported by every rio command).

    .venv/bin/python benchmarks/bench_startup.py [HILLSHADE_RT ...]

times the ``hillshade-rt`` next to this interpreter, or each script given (e.g. another
checkout's ``.venv/bin/hillshade-rt``: before and after a change, in one run, alternating).
Figures go to docs/benchmarks.md ("Start-up").
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time

from hillshade_rt.testing import real_dems

EXAMPLE = real_dems(["bigtujunga_srtm30m_utm11n_1197x643.tif"])[0][0]
REPEAT = 5


def wall(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main(exes: list[str]) -> None:
    out = os.path.join(tempfile.mkdtemp(), "m.tif")
    cases = {"--help": ["--help"], "--version": ["--version"],
             "shadow az/el": ["shadow", EXAMPLE, out, "--azimuth", "225", "--elevation", "20",
                              "--overwrite", "-q"]}
    for exe in exes:                      # once each first: kernels compiled and cached
        subprocess.run([exe, *cases["shadow az/el"]], check=True)
    times = {(exe, case): [] for exe in exes for case in cases}
    for _ in range(REPEAT):
        for case, args in cases.items():
            for exe in exes:
                times[exe, case].append(wall([exe, *args]))
        for exe in exes:
            rio = os.path.join(os.path.dirname(exe), "rio")
            if os.path.exists(rio):
                times.setdefault((exe, "rio --help"), []).append(wall([rio, "--help"]))
    for exe in exes:
        print(exe)
        for case in [*cases, "rio --help"]:
            t = times.get((exe, case))
            if not t:
                continue
            print(f"  {case:14s} median {statistics.median(t):.3f} s  "
                  f"(min {min(t):.3f}, max {max(t):.3f}, n={len(t)})")


if __name__ == "__main__":
    main(sys.argv[1:] or [os.path.join(os.path.dirname(sys.executable), "hillshade-rt")])
