# hillshade-rt -- set-up, example run, tests, benchmarks. Needs only python3 (>= 3.10) and PyPI.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUTDIR ?= out

EXAMPLE_DEM := examples/bigtujunga_srtm30m_utm11n_1197x643.tif
EXAMPLE_OUT := $(OUTDIR)/bigtujunga_shadow.tif

.PHONY: run test test-fast install install-test bench bench-sun bench-tiling bench-big bench-gpu bench-peers bench-horizon docs-pictures docs-animation docs-viewer bench-writes bench-real bench-real-quick bench-fast bench-point bench-view bench-update bench-illumination gpu-check clean clean-cache bench-startup bench-batch bench-products help qgis-plugin docs-qgis

help:
	@echo "make run    - set up .venv, shade the bundled example DEM, print where the mask went"
	@echo "make test   - set up .venv with test extras and run the test suite"
	@echo "make test-fast - the same without the tests marked slow (a few minutes on 2 cores)"
	@echo "make bench  - run the benchmarks (writes docs/benchmarks.md figures to stdout)"
	@echo "make bench-sun - time series, per-tile suns, curvature, soft shadows, sun hours"
	@echo "make bench-tiling - Mpix/s in memory vs in windows vs Dask (2 workers)"
	@echo "make bench-writes - what the checked (atomic, fsync, GDAL-error) writes cost vs bare rasterio"
	@echo "make bench-big - a 20000 x 20000 DEM under --max-memory 1GB: peak memory, a crop checked"
	@echo "make bench-gpu - install the CUDA backend (numba-cuda) and time every algorithm on the GPU"
	@echo "make gpu-check - on a machine with a GPU: the GPU tests on the device, then make bench-gpu"
	@echo "make bench-peers - install other shadow tools into .venv and time them against ours"
	@echo "make bench-horizon - horizon/skyview in 32 directions vs one mask; SVF vs rvt-py, whitebox"
	@echo "make bench-products - SVF vs rvt-py/whitebox, horizon x32 vs one mask, irradiance (vs r.sun): targets met?"
	@echo "make bench-real - real DEMs and spectral fractals (1024-4096), 18 suns, with the peers"
	@echo "make bench-real-quick - the same with 1024 and 6 suns (a few minutes on 2 cores)"
	@echo "make bench-fast - the default's curvature cost, cost against size, geographic vs projected"
	@echo "make bench-point - the point light vs brute's directional mask (4096^2, real DEMs)"
	@echo "make bench-view - hillshade-rt view: a 1024^2 view recomputed and delivered (round trip)"
	@echo "make bench-update - a 20x20 edit re-shaded (Shader.update) vs a full render"
	@echo "make bench-illumination - illumination: 1000 subsolar positions on a 2048^2 polar DEM and Kepler (issue 21: < 10 min)"
	@echo "make docs-pictures - the pictures of docs/products.md, by the tool's --preview"
	@echo "make docs-animation - the README's GIF: the shadows of a winter day on the example DEM"
	@echo "make qgis-plugin - the QGIS plugin as dist/hillshade_rt_qgis.zip (Plugins > Install from ZIP)"
	@echo "make docs-qgis - docs/img/qgis.png: QGIS (Debian's, under Xvfb) with the plugin's shadow"
	@echo "make clean  - remove .venv and outputs"
	@echo "make clean-cache - remove numba's stale compiled kernels (hillshade-rt cache --prune)"
	@echo "make bench-startup - wall time of hillshade-rt --help, --version and an az/el run"
	@echo "make bench-batch - a Makefile of 256^2/512^2 tiles: gdaldem vs hillshade-rt standalone, server, --context, one call"

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# after installing, numba compiles every kernel the commands use, once per install, in parallel
# processes (python -m hillshade_rt.warm; about a minute on 2 cores): no command compiles at its
# first run. Nothing is compiled again while this install's kernels are cached. compileall: an
# editable install writes no bytecode, and where PYTHONDONTWRITEBYTECODE is set no run would
# (40-60 ms of every process spent compiling the package's modules).
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e .
	$(BIN)/python -m compileall -q hillshade_rt
	$(BIN)/python -m hillshade_rt.warm
	@touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q -e '.[test]'
	$(BIN)/python -m compileall -q hillshade_rt
	$(BIN)/python -m hillshade_rt.warm
	@touch $@ $(VENV)/.installed

install: $(VENV)/.installed
install-test: $(VENV)/.installed-test

run: $(VENV)/.installed
	@mkdir -p $(OUTDIR)
	$(BIN)/hillshade-rt shadow $(EXAMPLE_DEM) $(EXAMPLE_OUT) --azimuth 225 --elevation 20 \
		--overwrite --report $(OUTDIR)/bigtujunga_shadow.json
	@echo "shadow mask written to $(EXAMPLE_OUT) (report: $(OUTDIR)/bigtujunga_shadow.json)"

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

# the tests not marked slow (each under ~1.5 s): a few minutes on 2 cores; make test runs all
test-fast: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q -m "not slow"

bench: $(VENV)/.installed
	MALLOC_MMAP_THRESHOLD_=131072 $(BIN)/python benchmarks/bench_cpu.py

bench-sun: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_sun.py

# Dask comes with the test extras (and alone as hillshade-rt[dask])
bench-tiling: $(VENV)/.installed-test
	$(BIN)/python benchmarks/bench_tiling.py

bench-point: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_point.py

bench-view: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_view.py

bench-update: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_update.py

bench-writes: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_writes.py

bench-big: $(VENV)/.installed
	$(BIN)/python benchmarks/bigdem.py

# The CUDA backend: numba-cuda and the CUDA 12 toolkit libraries from PyPI; needs an NVIDIA GPU
# and driver (without one the benchmark says what is missing and exits 1).
$(VENV)/.installed-gpu: pyproject.toml | $(VENV)/.installed
	$(BIN)/python -m pip install -q -e '.[gpu]'
	@touch $@

bench-gpu: $(VENV)/.installed-gpu
	$(BIN)/python benchmarks/bench_gpu.py

# One prepared script for a lent GPU (a few minutes): the GPU tests on the device instead of the
# simulator, then the GPU benchmark (4096^2 and the real DEMs, a 100-sun series).
gpu-check: $(VENV)/.installed-gpu $(VENV)/.installed-test
	NUMBA_ENABLE_CUDASIM=0 $(BIN)/python -m pytest -q -k "gpu or cuda" tests
	$(BIN)/python benchmarks/bench_gpu.py --sizes 1024,4096

# Peers: insolation (doshade), whitebox-workflows, topocalc (needs numpy and cython at build time,
# so it is built without isolation; if it does not build, the benchmark says it was skipped).
# GRASS r.sunmask is a system package (Debian grass-core), not installed here. rvt-py (the
# Relief Visualization Toolbox's SVF) without its declared dependencies: they include GDAL's
# Python bindings (a system build) and jupyter; rvt.vis needs only numpy and scipy.
$(VENV)/.installed-peers: pyproject.toml | $(VENV)/.installed
	$(BIN)/python -m pip install -q -e '.[peers]'
	$(BIN)/python -m pip install -q wheel setuptools cython
	-$(BIN)/python -m pip install -q --no-build-isolation topocalc
	$(BIN)/python -m pip install -q --no-deps rvt_py
	@touch $@

bench-peers: $(VENV)/.installed-peers
	$(BIN)/python benchmarks/bench_peers.py

# docs/products.md's pictures (docs/img/), each made by the command's own --preview
docs-pictures: $(VENV)/.installed
	$(BIN)/python docs/pictures.py

# The README's animation (docs/img/day.gif): the winter solstice on the bundled DEM, 11 frames
# from just after sunrise to after sunset, by the tool's own animate command
docs-animation: $(VENV)/.installed
	$(BIN)/hillshade-rt animate $(EXAMPLE_DEM) docs/img/day.gif --start 2026-12-21T07:00 \
		--end 2026-12-21T17:00 --step 1h --tz America/Los_Angeles --size 400 --fps 3 \
		--overwrite

# Horizons in N directions and the sky view factor against one shadow mask, and the sky view
# factor of rvt-py and whitebox-workflows against ours (issue 20)
bench-horizon: $(VENV)/.installed-peers
	$(BIN)/python benchmarks/bench_horizon.py

# The products against their targets in one run, peers in the same run (figures for
# docs/benchmarks.md, printed as markdown): the sky view factor vs rvt-py and whitebox-workflows
# (both installed by .installed-peers: whitebox-workflows by the peers extra, rvt_py above),
# horizon --directions 32 vs one shadow mask, irradiance over a day (and a year with --year) and
# vs GRASS's r.sun where `grass` is on PATH (a system package, Debian's grass-core: not
# installed here; without it the benchmark says r.sun was skipped). Long: run it on an idle
# machine. BENCH_PRODUCTS_ARGS passes options, e.g. "--quick", "--parts C --year", "--runs 5".
bench-products: $(VENV)/.installed-peers
	$(BIN)/python benchmarks/bench_products.py $(BENCH_PRODUCTS_ARGS)

# Benchmarks that look like Earth (issue 18): real DEMs (benchmarks/data/SOURCES.md), spectral
# fractals (beta 2.4, 3.2), the smooth facet fractal labelled as such; peers in the same run.
# BENCH_REAL_ARGS passes options, e.g. BENCH_REAL_ARGS="--sizes 8192 --no-real --no-smooth".
bench-real: $(VENV)/.installed-peers
	MALLOC_MMAP_THRESHOLD_=131072 $(BIN)/python benchmarks/bench_real.py $(BENCH_REAL_ARGS)

bench-fast: $(VENV)/.installed
	MALLOC_MMAP_THRESHOLD_=131072 $(BIN)/python benchmarks/bench_fast.py

bench-real-quick: $(VENV)/.installed-peers
	MALLOC_MMAP_THRESHOLD_=131072 $(BIN)/python benchmarks/bench_real.py --quick $(BENCH_REAL_ARGS)

# the viewer's screenshot in docs/viewer.md, taken by the browser test (Debian's chromium)
docs-viewer: $(VENV)/.installed-test
	HILLSHADE_RT_DOCS_SCREENSHOT=1 $(BIN)/python -m pytest -q tests/run/test_view_browser.py

# the QGIS plugin (qgis/hillshade_rt_qgis: a Processing provider running the hillshade-rt
# program), zipped with its folder on top, reproducibly (docs/qgis.md)
QGIS_ZIP ?= dist/hillshade_rt_qgis.zip
qgis-plugin:
	$(PYTHON) qgis/build_zip.py qgis/hillshade_rt_qgis $(QGIS_ZIP)

# docs/img/qgis.png: needs Debian's qgis, python3-qgis, xvfb, xauth, imagemagick (docs/qgis.md)
docs-qgis: $(VENV)/.installed qgis-plugin
	$(PYTHON) qgis/docs_screenshot.py --zip $(QGIS_ZIP) --program $(BIN)/hillshade-rt \
		--dem $(EXAMPLE_DEM) --out docs/img/qgis.png

clean:
	rm -rf $(VENV) $(OUTDIR) .pytest_cache .hypothesis

# other versions' kernel folders and numba's stale index/data files (docs/usage.md)
clean-cache: $(VENV)/.installed
	$(BIN)/hillshade-rt cache --prune

bench-startup: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_startup.py

# A Makefile of tiles (the repository's real DEMs cut into 256^2 and 512^2 tiles): gdaldem
# hillshade, hillshade-rt standalone, with the server, with --context, one call; the start-up
# phases; the first run after the warm-up. Needs Debian's gdal-bin (gdaldem, gdalbuildvrt).
# BENCH_BATCH_ARGS passes options, e.g. BENCH_BATCH_ARGS="--no-cache --jobs 2".
bench-batch: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_batch.py $(BENCH_BATCH_ARGS)

bench-illumination: $(VENV)/.installed
	$(BIN)/python benchmarks/bench_illumination.py
