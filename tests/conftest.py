import math
import os
import warnings

# GPU kernels run through numba's CUDA simulator unless the caller says otherwise: on a machine
# with a GPU, `NUMBA_ENABLE_CUDASIM=0 make test` runs the same tests on the device. Set before
# anything imports numba (it reads the variable once).
os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")

import numpy as np
import pytest

DATA = os.path.join(os.path.dirname(__file__), "data")
EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(__file__)), "examples")


def data_path(name: str) -> str:
    return os.path.join(DATA, name)


def write_geotiff(path, z, transform=None, crs=None, nodata=None, count=1):
    """Write array ``z`` (2-D, or 3-D bands-first) as a GeoTIFF."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning

    z = np.asarray(z)
    if z.ndim == 2:
        z = z[None]
    prof = dict(driver="GTiff", width=z.shape[2], height=z.shape[1], count=z.shape[0],
                dtype=str(z.dtype), nodata=nodata)
    if transform is not None:
        prof["transform"] = transform
    if crs is not None:
        prof["crs"] = crs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(path, "w", **prof) as dst:
            dst.write(z)
    return str(path)


def read_band(path, band=1):
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(path) as ds:
            return ds.read(band)


def box_terrain(rows=80, cols=80, h=10.0, r0=38, r1=42, c0=38, c1=42):
    z = np.zeros((rows, cols), np.float32)
    z[r0:r1, c0:c1] = h
    return z


def fractal_terrain(rows, cols, seed, relief=100.0, octaves=4):
    """Smooth-ish random terrain: a sum of bilinearly upsampled noise octaves."""
    rng = np.random.default_rng(seed)
    z = np.zeros((rows, cols))
    for o in range(octaves):
        n = 2 ** (o + 1) + 1
        coarse = rng.standard_normal((n, n)) / (2 ** o)
        ri = np.linspace(0, n - 1, rows)
        ci = np.linspace(0, n - 1, cols)
        r0 = np.minimum(np.floor(ri).astype(int), n - 2)
        c0 = np.minimum(np.floor(ci).astype(int), n - 2)
        fr = (ri - r0)[:, None]
        fc = (ci - c0)[None, :]
        z += ((1 - fr) * (1 - fc) * coarse[r0][:, c0] + (1 - fr) * fc * coarse[r0][:, c0 + 1]
              + fr * (1 - fc) * coarse[r0 + 1][:, c0] + fr * fc * coarse[r0 + 1][:, c0 + 1])
    z = (z - z.min()) / (z.max() - z.min()) * relief
    return z.astype(np.float32)


def reference_mask(z, dx, dy, azimuth, elevation, col_sign=1, row_sign=-1):
    """The terrain model written out plainly, independently of hillshade_rt's kernels.

    dx, dy: scalars or one value per row. The ray from the centre of cell (r, c) travels a ground
    distance t toward the sun; it is sampled at every t where it crosses a grid line of its
    dominant pixel axis; the terrain there is interpolated between the two nearest cell centres
    on that line; strictly-below means shadow; outside the raster there is no terrain; NaN cells
    are voids (never shadowed or lit: 255; a ray skips them).
    """
    z = np.asarray(z, dtype=np.float64)
    rows, cols = z.shape
    dxs = np.broadcast_to(np.asarray(dx, dtype=np.float64), (rows,))
    dys = np.broadcast_to(np.asarray(dy, dtype=np.float64), (rows,))
    a = math.radians(azimuth % 360.0)
    east, north = math.sin(a), math.cos(a)
    tan_e = math.tan(math.radians(elevation))
    out = np.zeros((rows, cols), np.uint8)

    def near_int(x):
        return abs(x - round(x)) < 1e-9

    for r in range(rows):
        vc = col_sign * east / dxs[r]    # columns per metre
        vr = row_sign * north / dys[r]   # rows per metre
        dom = max(abs(vc), abs(vr))
        for c in range(cols):
            if math.isnan(z[r, c]):
                out[r, c] = 255
                continue
            k = 1
            while True:
                t = k / dom
                pc, pr = c + vc * t, r + vr * t
                if near_int(pc):
                    pc = round(pc)
                if near_int(pr):
                    pr = round(pr)
                if not (0 <= pc <= cols - 1 and 0 <= pr <= rows - 1):
                    break
                if pc == int(pc) and pr == int(pr):
                    terrain = z[int(pr), int(pc)]
                elif pc == int(pc):          # on a column line: interpolate along rows
                    i = int(math.floor(pr)); f = pr - i
                    terrain = (1 - f) * z[i, int(pc)] + f * z[i + 1, int(pc)]
                else:                        # on a row line: interpolate along columns
                    i = int(math.floor(pc)); f = pc - i
                    terrain = (1 - f) * z[int(pr), i] + f * z[int(pr), i + 1]
                if terrain > z[r, c] + t * tan_e:
                    out[r, c] = 1
                    break
                k += 1
    return out


@pytest.fixture
def runner():
    from click.testing import CliRunner

    return CliRunner()
