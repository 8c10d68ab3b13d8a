"""Foreground people in a fixed camera's images: Sigma-Delta background subtraction, morphology and blobs of a
person's shape (seed 001 Sec. 4.2, which names the method and cites Manzanera 2007 but gives no parameter).

Sigma-Delta (Manzanera & Richefeu 2007, "A new motion detection algorithm based on Sigma-Delta background
estimation", Pattern Recognition Letters 28(3)), per pixel and colour channel, in integer levels:

    M <- M + sgn(I - M)                      the background follows the image one level a frame
    O  = |M - I|
    V <- V + sgn(N O - V) where O != 0,      the spread follows N times the difference, within [V_min, V_max]
    foreground where O > V in any channel.

A background model needs a start: the per-pixel median of the first ``bootstrap`` frames (walkers move, so the
median is the room), with V at V_min; no detection comes before it is complete. Then an
opening removes speckle, a closing joins a person's parts, and each connected blob of ``min_area`` pixels or more
whose height is ``min_aspect``..``max_aspect`` times its width is a person (a standing person: about 3.4).
"""

from __future__ import annotations

import numpy as np


class SigmaDelta:
    """The background model of one camera; ``update(rgb)`` gives the foreground mask [h, w] (all False while the
    model starts)."""

    def __init__(self, amplification: int = 2, v_min: int = 2, v_max: int = 255, bootstrap: int = 15):
        self.amplification, self.v_min, self.v_max, self.bootstrap = amplification, v_min, v_max, bootstrap
        self.reset()

    def reset(self) -> None:
        self.frames: list[np.ndarray] = []
        self.background: np.ndarray | None = None
        self.spread: np.ndarray | None = None

    def update(self, rgb: np.ndarray) -> np.ndarray:
        image = rgb.astype(np.int16)
        if self.background is None:
            self.frames.append(image)
            if len(self.frames) < self.bootstrap:
                return np.zeros(image.shape[:2], bool)
            self.background = np.median(np.stack(self.frames), axis=0).astype(np.int16)
            self.spread = np.full(image.shape, self.v_min, np.int16)
            self.frames = []
        m = self.background
        m += np.sign(image - m)
        difference = np.abs(m - image)
        v = self.spread
        # where the difference is not 0, V moves one step towards N times it (where it is 0, V stays)
        v += np.sign(self.amplification * difference - v) * (difference != 0)
        np.clip(v, self.v_min, self.v_max, out=v)
        return (difference > v).any(axis=-1)


def person_blobs(mask: np.ndarray, min_area: int = 150, min_aspect: float = 1.2, max_aspect: float = 5.0,
                 opening: int = 3, closing: int = 7) -> np.ndarray:
    """Boxes [k, 4] (u0, v0, u1, v1; u1, v1 exclusive) of the foreground blobs of a person's shape: after an opening
    and a closing by squares of the given sizes, the connected blobs of at least ``min_area`` pixels whose box is
    ``min_aspect`` to ``max_aspect`` times as high as wide."""
    from scipy import ndimage  # imported by the wall cameras' detector only: 0.1 s off every other command's start

    # opening and closing by squares as separable minimum and maximum filters (outside the image counts as
    # background), a binary_opening and binary_closing's result at a fraction of their cost
    clean = mask.view(np.uint8)
    for size, first, second in ((opening, ndimage.minimum_filter, ndimage.maximum_filter),
                                (closing, ndimage.maximum_filter, ndimage.minimum_filter)):
        clean = second(first(clean, size, mode="constant", cval=0), size, mode="constant", cval=0)
    clean = clean.view(bool)
    labels, n = ndimage.label(clean)
    if not n:
        return np.zeros((0, 4), np.int64)
    slices = ndimage.find_objects(labels)
    area = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    boxes = np.array([[s[1].start, s[0].start, s[1].stop, s[0].stop] for s in slices], np.int64)
    height, width = boxes[:, 3] - boxes[:, 1], boxes[:, 2] - boxes[:, 0]
    aspect = height / np.maximum(width, 1)
    keep = (area >= min_area) & (aspect >= min_aspect) & (aspect <= max_aspect)
    return boxes[keep]
