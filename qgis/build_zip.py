"""Zip the QGIS plugin folder the way QGIS's "Install from ZIP" expects: one top folder (the
plugin's) holding metadata.txt and the code. Reproducible: files in sorted order, one fixed
time stamp (SOURCE_DATE_EPOCH when set, else 1980-01-01), fixed permissions, no caches.

    python qgis/build_zip.py qgis/hillshade_rt_qgis dist/hillshade_rt_qgis.zip
"""

from __future__ import annotations

import os
import sys
import time
import zipfile

SKIPPED_DIRS = {"__pycache__", ".pytest_cache"}
SKIPPED_SUFFIXES = (".pyc", ".pyo", "~")


def plugin_files(folder: str) -> list:
    """The files to ship, relative to ``folder``, sorted (POSIX separators)."""
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d not in SKIPPED_DIRS and not d.startswith("."))
        for name in files:
            if name.startswith(".") or name.endswith(SKIPPED_SUFFIXES):
                continue
            found.append(os.path.relpath(os.path.join(root, name), folder).replace(os.sep, "/"))
    return sorted(found)


def build(folder: str, target: str) -> list:
    """Write ``target`` (atomically: a temporary file renamed over it); return its names."""
    folder = os.path.normpath(folder)
    top = os.path.basename(folder)
    if not os.path.isfile(os.path.join(folder, "metadata.txt")):
        raise SystemExit(f"{folder}: no metadata.txt (not a QGIS plugin folder)")
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", "315532800"))   # 1980-01-01 00:00 UTC
    stamp = time.gmtime(max(epoch, 315532800))[:6]
    os.makedirs(os.path.dirname(os.path.abspath(target)), exist_ok=True)
    tmp = target + ".tmp"
    names = []
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for rel in plugin_files(folder):
            info = zipfile.ZipInfo(f"{top}/{rel}", date_time=stamp)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            info.create_system = 3                                        # Unix
            with open(os.path.join(folder, rel), "rb") as f:
                z.writestr(info, f.read())
            names.append(info.filename)
    os.replace(tmp, target)
    return names


def main(argv: list) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    names = build(argv[0], argv[1])
    print(f"{argv[1]}: {len(names)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
