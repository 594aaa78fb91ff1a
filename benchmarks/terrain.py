"""Benchmark terrains the benchmarks share: spectral (power-law) fractals, the smooth facet
fractal, and the real DEMs in the repo.

Spectral fractal (:func:`spectral`): white Gaussian noise shaped in the Fourier domain so that
its 2-D power spectrum falls as ``|k|^-beta`` (amplitude ``|k|^-beta/2``), i.e. fractional
Brownian surfaces with Hurst exponent ``H = (beta - 2) / 2``: beta 2.4 is rough (H 0.2), 3.2 is
smoother (H 0.6); real landscapes measure about 2-4 (Perron et al. 2008). The result is periodic
(it tiles seamlessly, see :func:`tiled`) and is scaled to ``relief`` metres (min 0, max relief).

Smooth fractal (:func:`smooth`): ``tests/conftest.fractal_terrain``, a few noise octaves
upsampled bilinearly: planar facets tens of cells wide. No real DEM is that smooth; the old
``make bench`` figures come from it. Label it "smooth (facets)" wherever it is used.
"""

import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..")

# real DEMs: (path, label); see benchmarks/data/SOURCES.md, tests/data/SOURCES.md, examples/
REAL_DEMS = [
    (os.path.join(ROOT, "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif"),
     "Big Tujunga SRTM 1″, UTM 30 m"),
    (os.path.join(HERE, "data", "everest_srtm3_N27E086_voids_1201.tif"),
     "Everest SRTM 3″ tile, geographic, 9 % voids"),
    (os.path.join(HERE, "data", "nz_elev_1km_nztm_sea_nodata_1115x1450.tif"),
     "New Zealand 1 km, NZTM, 83 % sea"),
    (os.path.join(HERE, "data", "moon_kepler_crater_lola_ortho_804x804.tif"),
     "Moon Kepler crater LOLA, 47.7 m"),
    (os.path.join(ROOT, "tests", "data", "jacksboro_fault_srtm3_mpl_403x344.tif"),
     "Jacksboro SRTM 3″, geographic"),
]


def spectral(n: int, beta: float, seed: int = 0, relief: float = 2000.0,
             cols: int | None = None) -> np.ndarray:
    """Power-law fractal, ``n`` rows x ``cols`` (default n) columns, float32 metres 0..relief.

    2-D power spectrum ``~ |k|^-beta``. Built with a real FFT in float32 (numpy >= 2 keeps the
    precision), so an 8192² surface takes about 4 s and 1.1 GB at its peak."""
    cols = n if cols is None else cols
    rng = np.random.default_rng(seed)
    ky = np.fft.fftfreq(n).astype(np.float32)
    kx = np.fft.rfftfreq(cols).astype(np.float32)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    k2[0, 0] = 1.0
    amp = k2 ** np.float32(-beta / 4.0)        # |k|^-beta/2
    del k2
    amp[0, 0] = 0.0                            # no mean
    spec = rng.standard_normal(amp.shape, dtype=np.float32) * amp \
        + 1j * (rng.standard_normal(amp.shape, dtype=np.float32) * amp)
    del amp
    z = np.fft.irfft2(spec.astype(np.complex64), s=(n, cols))
    del spec
    z = z.astype(np.float32, copy=False)
    lo, hi = float(z.min()), float(z.max())
    z -= np.float32(lo)
    z *= np.float32(relief / (hi - lo))
    return z


def tiled(z: np.ndarray, n: int) -> np.ndarray:
    """``z`` (periodic, e.g. :func:`spectral`) repeated to n x n: the same terrain at a larger
    size, for cost-versus-size comparisons (seamless, since the spectral surface is periodic)."""
    r, c = z.shape
    return np.ascontiguousarray(np.tile(z, (-(-n // r), -(-n // c)))[:n, :n])


def fractal(n: int, beta: float = 2.2, seed: int = 3) -> np.ndarray:
    """``bench_writes``' power-law fractal (moved here unchanged), n x n, 0..2000 m.

    Its ``beta`` is the exponent of a 1-D profile: the 2-D power spectrum falls as
    ``|k|^-(beta + 1)``, so ``fractal(n, b)`` has the statistics of ``spectral(n, b + 1)``."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n)
    kk = np.sqrt(k[:, None] ** 2 + k[None, :] ** 2)
    kk[0, 0] = 1.0
    spec = (rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n))) / kk ** (beta / 2 + 0.5)
    z = np.fft.ifft2(spec).real
    return ((z - z.min()) / (z.max() - z.min()) * 2000).astype(np.float32)


def smooth(n: int, seed: int | None = None, relief: float = 1500.0) -> np.ndarray:
    """The smooth facet fractal of the old benchmarks (tests/conftest.fractal_terrain)."""
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from conftest import fractal_terrain
    return fractal_terrain(n, n, seed=n if seed is None else seed, relief=relief,
                           octaves=6).astype(np.float32)


def roughness(z: np.ndarray, cell: float) -> dict:
    """A few figures that tell smooth from rough terrain: mean slope (degrees) and the share of
    cells whose slope differs from their east neighbour's by more than 5 degrees."""
    gy, gx = np.gradient(z.astype(np.float64), cell)
    s = np.degrees(np.arctan(np.hypot(gx, gy)))
    ds = np.abs(np.diff(s, axis=1))
    return {"mean_slope": float(np.nanmean(s)),
            "kinks": float(np.nanmean(ds > 5.0))}
