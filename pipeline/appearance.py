"""Colour appearance: HSV histograms and the Bhattacharyya distance (seed 001 Sec. 4.3 and 5.2.5, after Perez, Hue,
Vermaak & Gangnet 2002, "Color-based probabilistic tracking", ECCV).

A histogram has 8 x 8 hue-saturation bins for the pixels with colour (saturation above 0.1 and value above 0.2, Perez
et al.'s limits) and 8 value bins for the rest (greys, black and white, whose hue means nothing): 72 bins, seed 001's
"8x8 HS bin, 8 V bin" (Table 1). An image is turned into one bin index per pixel once (``bin_image``); the histogram of
any box is then a count over it.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

HS_BINS, V_BINS = 8, 8
BINS = HS_BINS * HS_BINS + V_BINS
UNKNOWN = 255  # in the colour table: a colour whose bin is not known yet (bins are 0-71)
MIN_SATURATION, MIN_VALUE = 0.1, 0.2  # Perez et al. 2002: below either, a pixel's hue is unreliable


def hsv(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue (in [0, 1), a turn), saturation and value (in [0, 1]) of 8-bit RGB pixels [..., 3]."""
    c = rgb.astype(np.float32) / 255.0
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    value = c.max(axis=-1)
    chroma = value - c.min(axis=-1)
    safe = np.where(chroma > 0, chroma, 1.0)
    hue = np.where(value == r, (g - b) / safe, np.where(value == g, 2.0 + (b - r) / safe, 4.0 + (r - g) / safe))
    hue = np.where(chroma > 0, (hue / 6.0) % 1.0, 0.0)
    saturation = np.where(value > 0, chroma / np.where(value > 0, value, 1.0), 0.0)
    return hue, saturation, value


def bin_image(rgb: np.ndarray) -> np.ndarray:
    """Each pixel's histogram bin [h, w] (uint8): hue x 8 + saturation for coloured pixels, 64 + value for the rest.
    Looked up in a table of every 24-bit colour's bin, filled as colours first appear (a camera's images share most
    of theirs), at a tenth of the arithmetic's cost."""
    rgb = rgb.astype(np.int32)
    packed = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
    table = _bin_table()
    bins = table[packed]
    unknown = bins == UNKNOWN
    if unknown.any():
        colours = np.unique(packed[unknown])
        table[colours] = _bins(np.stack([colours >> 16, (colours >> 8) & 255, colours & 255], axis=-1).astype(np.uint8))
        bins[unknown] = table[packed[unknown]]
    return bins


@lru_cache(maxsize=1)
def _bin_table() -> np.ndarray:
    """The bin of each 24-bit colour r << 16 | g << 8 | b seen so far in this process (16 MiB)."""
    return np.full(1 << 24, UNKNOWN, np.uint8)


def _bins(rgb: np.ndarray) -> np.ndarray:
    """bin_image by arithmetic."""
    hue, saturation, value = hsv(rgb)
    h = np.minimum((hue * HS_BINS).astype(np.int64), HS_BINS - 1)
    s = np.minimum((saturation * HS_BINS).astype(np.int64), HS_BINS - 1)
    v = np.minimum((value * V_BINS).astype(np.int64), V_BINS - 1)
    coloured = (saturation > MIN_SATURATION) & (value > MIN_VALUE)
    return np.where(coloured, h * HS_BINS + s, HS_BINS * HS_BINS + v).astype(np.uint8)


def histogram(bins: np.ndarray, box=None) -> np.ndarray:
    """The normalised histogram [72] of the pixels of ``bins`` in ``box`` (u0, v0, u1, v1; u1, v1 exclusive; the
    whole image when None); all zeros when the box holds no pixel."""
    if box is not None:
        u0, v0, u1, v1 = (int(round(x)) for x in box)
        bins = bins[max(v0, 0):max(v1, 0), max(u0, 0):max(u1, 0)]
    counts = np.bincount(bins.ravel(), minlength=BINS).astype(float)
    total = counts.sum()
    return counts / total if total else counts


def bhattacharyya(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The Bhattacharyya distance sqrt(1 - sum_u sqrt(p_u q_u)) between normalised histograms (last axis), 0 for
    equal ones and 1 for disjoint ones (Perez et al. 2002, Eq. 3)."""
    coefficient = np.sqrt(np.asarray(p) * np.asarray(q)).sum(axis=-1)
    return np.sqrt(np.maximum(1.0 - coefficient, 0.0))


def blend(model: np.ndarray, current: np.ndarray, alpha: float = 0.9) -> np.ndarray:
    """Seed 001 Eq. 6: the colour model moved towards the current histogram, alpha h + (1 - alpha) h_new (Table 1:
    alpha 0.9)."""
    return alpha * np.asarray(model) + (1.0 - alpha) * np.asarray(current)
