"""The products of a lighting run, one :class:`Product` each: what a cell's value means, its
type and nodata, the tag that says so, the band's description, how overviews resample it, its
statistics for the report and its share of shadow for the preview. Adding a product is one
entry of ``PRODUCTS`` (and its kind in ``engine.shader.render``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import UsageProblem


@dataclass(frozen=True)
class Product:
    """One product: ``kind`` ("shadow", "classes", "hillshade") and ``soft`` (the visible
    fraction of the sun's disk instead of hard shadows)."""

    kind: str
    soft: bool
    dtype: str
    nodata: float
    values: str          # the VALUES tag: what the values mean
    what: str            # the band's description (a series: each band's time instead)
    resampling: str      # overviews and COGs: "nearest" (codes) or "average" (continuous)

    @property
    def continuous(self) -> bool:
        """Whether the values are continuous (lossy formats and 16-bit PNG allowed)."""
        return self.resampling == "average"

    def stats(self, arr: np.ndarray) -> dict:
        """Cell counts of this product: shadow (cast or self) / lit / nodata (``product_stats``)."""
        return product_stats(self.kind, self.soft, arr)

    def shade(self, arr: np.ndarray, ambient: float) -> np.ndarray:
        """0..1 'in shadow' per cell, for the preview."""
        return shade_of(self.kind, self.soft, arr, ambient)


PRODUCTS = {(p.kind, p.soft): p for p in (
    Product("shadow", False, "uint8", 255, "1=shadow 0=lit 255=nodata", "cast shadow",
            "nearest"),
    Product("shadow", True, "float32", -9999.0,
            "visible fraction of the solar disk 0..1, -9999=nodata",
            "visible fraction of the sun", "average"),
    Product("classes", False, "uint8", 255, "0=lit 1=self-shadow 2=cast shadow 255=nodata",
            "shadow classes", "nearest"),
    Product("hillshade", False, "uint8", 0,
            "1..255 shaded relief with cast shadows, 0=nodata", "shaded relief", "average"),
    Product("hillshade", True, "uint8", 0,
            "1..255 shaded relief with soft shadows, 0=nodata", "shaded relief", "average"),
)}


def product(kind: str, soft: bool = False) -> Product:
    """The product of ``kind`` (hard or ``soft``); classes are hard only (a usage error)."""
    if kind == "classes" and soft:
        raise UsageProblem("--classes and --soft do not go together (classes are hard)")
    return PRODUCTS[kind, bool(soft)]


def mask_stats(mask: np.ndarray) -> dict:
    """Counts of shadow / lit / nodata cells of a uint8 mask (1 / 0 / 255)."""
    from ..algorithms.counts import code_counts
    counts = code_counts(mask)
    shadow, lit, nodata = int(counts[1]), int(counts[0]), int(counts[255])
    valid = shadow + lit
    return {"shadow_cells": shadow, "lit_cells": lit, "nodata_cells": nodata,
            "shadow_fraction": (shadow / valid) if valid else None}


def product_stats(kind: str, soft: bool, arr: np.ndarray) -> dict:
    """Cell counts of one product: shadow (cast or self) / lit / nodata, as ``mask_stats``."""
    if kind == "shadow" and not soft:
        return mask_stats(arr)
    if kind == "classes":
        from ..algorithms.counts import code_counts
        counts = code_counts(arr)
        shadow, lit, nodata = int(counts[1] + counts[2]), int(counts[0]), int(counts[255])
        valid = shadow + lit
        return {"shadow_cells": shadow, "lit_cells": lit, "nodata_cells": nodata,
                "shadow_fraction": (shadow / valid) if valid else None,
                "self_shadow_cells": int(counts[1]), "cast_shadow_cells": int(counts[2])}
    if kind == "hillshade":
        nodata = int(np.count_nonzero(arr == 0))
        return {"shadow_cells": 0, "lit_cells": int(arr.size - nodata), "nodata_cells": nodata,
                "shadow_fraction": None}
    valid = ~np.isnan(arr)
    n = int(np.count_nonzero(valid))
    mean = float(np.mean(arr[valid], dtype=np.float64)) if n else None
    return {"shadow_cells": None, "lit_cells": None, "nodata_cells": int(arr.size - n),
            "valid_cells": n, "shadow_fraction": (1.0 - mean) if mean is not None else None}


def merge_stats(a: dict | None, b: dict) -> dict:
    """The ``product_stats`` of two parts of one product taken together."""
    if a is None:
        return dict(b)
    out = {}
    for k in ("shadow_cells", "lit_cells", "nodata_cells", "valid_cells", "self_shadow_cells",
              "cast_shadow_cells"):
        if k in a or k in b:
            va, vb = a.get(k), b.get(k)
            out[k] = None if va is None or vb is None else va + vb
    if out.get("shadow_cells") is not None:
        # no part with a fraction (a hillshade's: none, as product_stats says): none merged
        known = a.get("shadow_fraction") is not None or b.get("shadow_fraction") is not None
        valid = out["shadow_cells"] + out["lit_cells"]
        out["shadow_fraction"] = out["shadow_cells"] / valid if valid and known else None
    else:   # float products: the shadow fraction is 1 - the mean, weighted by valid cells
        na, nb = a.get("valid_cells") or 0, b.get("valid_cells") or 0
        fa, fb = a.get("shadow_fraction"), b.get("shadow_fraction")
        parts = [(n, f) for n, f in ((na, fa), (nb, fb)) if n and f is not None]
        out["shadow_fraction"] = (sum(n * f for n, f in parts) / sum(n for n, _ in parts)
                                  if parts else None)
    return out


def shade_of(kind, soft, arr, ambient):
    """0..1 'in shadow' per cell of one product, for the preview."""
    if kind == "hillshade":
        base = 1.0 + np.rint(254.0 * ambient)
        return ((arr > 0) & (arr <= base)).astype(np.float32)
    if soft:
        return np.nan_to_num(1.0 - arr, nan=0.0).astype(np.float32)
    if kind == "classes":
        return ((arr == 1) | (arr == 2)).astype(np.float32)
    return (arr == 1).astype(np.float32)
