"""Histograms of oriented gradients and a linear person classifier over them (Dalal & Triggs 2005, "Histograms of
oriented gradients for human detection", CVPR; seed 001 Sec. 4.3 runs it on its wall cameras).

Dalal & Triggs's default detector: a 64 x 128 window of 8 x 8-pixel cells, 9 orientation bins over 0-180 degrees,
blocks of 2 x 2 cells every cell, L2-Hys block normalisation (clipped at 0.2), centred [-1, 0, 1] gradients taken in
the colour channel of the largest magnitude, votes split linearly between the two nearest orientation bins; 3,780
features. Two simplifications, both for speed: a vote goes to its pixel's cell only (no spatial interpolation), and
the scales of the search share one gradient image: the cells of scale s are 8 s pixels wide, summed from one
integral image of the orientation votes (the feature pyramid of Dollar et al. 2014, "Fast feature pyramids for object
detection", PAMI, approximated with its gradients at full resolution). Training and detection compute features the
same way, so the classifier learns these features.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ORIENTATIONS = 9
CELL = 8  # pixels at scale 1
WINDOW_CELLS = (16, 8)  # rows, columns: 128 x 64 pixels at scale 1
BLOCK = 2  # cells
PERSON_SHARE = 96 / 128  # Dalal & Triggs's windows hold a person 96 pixels high in 128
L2HYS_CLIP = 0.2
MODELS_DIR = Path(__file__).parent / "models"
MODEL_FILE = "hog_person.npz"  # the wall cameras': `crowdsim experiment train-hog` makes it
ROBOT_MODEL_FILE = "hog_robot_camera.npz"  # the robot's depth camera's: `crowdsim experiment train-hog --camera robot`
MODEL_FORMAT = "crowdsim-hog/1"
GRADIENT_MAX = 255  # of a centred difference of 8-bit channels


def orientation_votes(rgb: np.ndarray) -> np.ndarray:
    """[h, w, 9] float32: each pixel's gradient magnitude split between its two nearest orientation bins (unsigned,
    0-180 degrees; bin k centred at (k + 0.5) 20 degrees), the gradient from the channel where it is largest.

    ``rgb`` is 8-bit, so a gradient (gx, gy) is a pair of integers in [-255, 255]: its votes are looked up in a table
    computed once with the same float32 arithmetic (``_vote_table``), the same numbers without an arctan2 per pixel."""
    if rgb.dtype != np.uint8:
        raise ValueError(f"rgb: expected an 8-bit image; got {rgb.dtype}")
    h, w = rgb.shape[:2]
    image = rgb.reshape(h, w * 3)  # channels interleaved: pixel x's channel c in column 3 x + c
    gx = np.zeros((h, w * 3), np.int16)
    gy = np.zeros((h, w * 3), np.int16)
    np.subtract(image[:, 6:], image[:, :-6], out=gx[:, 3:-3], dtype=np.int16)
    np.subtract(image[2:], image[:-2], out=gy[1:-1], dtype=np.int16)
    strength = (np.multiply(gx, gx, dtype=np.int32) + np.multiply(gy, gy, dtype=np.int32)).reshape(h, w, 3)
    row = (np.multiply(gy, 2 * GRADIENT_MAX + 1, dtype=np.int32) + gx).reshape(h, w, 3)  # table row less its offset
    # the row of the strongest channel, the first of equals (as argmax)
    pick = np.where(strength[..., 1] > strength[..., 0], row[..., 1], row[..., 0])
    pick = np.where(strength[..., 2] > np.maximum(strength[..., 0], strength[..., 1]), row[..., 2], pick)
    pick += GRADIENT_MAX * (2 * GRADIENT_MAX + 1) + GRADIENT_MAX
    return np.take(_vote_table(), pick, axis=0)


@functools.cache
def _vote_table() -> np.ndarray:
    """[511 * 511, 9] float32, read-only: the votes of the gradient (gx, gy), integers in [-255, 255], in row
    (gy + 255) 511 + gx + 255."""
    g = np.arange(-GRADIENT_MAX, GRADIENT_MAX + 1, dtype=np.float32)
    gy, gx = np.repeat(g, g.size), np.tile(g, g.size)
    magnitude = np.sqrt(gx * gx + gy * gy)
    position = (np.arctan2(gy, gx) % np.pi) * (ORIENTATIONS / np.pi) - 0.5  # in bin widths from bin 0's centre
    lower = np.floor(position)
    upper_share = position - lower
    lower = lower.astype(np.int64) % ORIENTATIONS
    table = np.zeros((g.size * g.size, ORIENTATIONS), np.float32)
    gradient = np.arange(len(table))
    table[gradient, lower] = magnitude * (1 - upper_share)
    table[gradient, (lower + 1) % ORIENTATIONS] = magnitude * upper_share  # the other bin of the same gradient
    table.flags.writeable = False
    return table


def integral(votes: np.ndarray) -> np.ndarray:
    """[h + 1, w + 1, 9] float64 sums of the votes above and left of each pixel corner (float64: a cell is the
    difference of corner sums far larger than it). Along the rows by cumsum, then down the image row by row, several
    times faster than numpy's cumsum along a leading axis."""
    h, w, n = votes.shape
    out = np.zeros((h + 1, w + 1, n))
    out[1:, 1:] = votes
    np.cumsum(out, axis=1, out=out)
    for v in range(1, h + 1):
        out[v] += out[v - 1]
    return out


def cells(table: np.ndarray, origin: tuple[float, float], size: float, shape: tuple[int, int]) -> np.ndarray:
    """[rows, cols, 9] cell histograms of cells ``size`` pixels wide, the first with its top-left corner at
    ``origin`` (u, v), edges rounded to whole pixels and clipped to the image."""
    h, w = table.shape[0] - 1, table.shape[1] - 1
    v = np.clip(np.rint(origin[1] + size * np.arange(shape[0] + 1)).astype(np.int64), 0, h)
    u = np.clip(np.rint(origin[0] + size * np.arange(shape[1] + 1)).astype(np.int64), 0, w)
    corner = table[v[:, None], u]
    return corner[1:, 1:] - corner[:-1, 1:] - corner[1:, :-1] + corner[:-1, :-1]


def blocks(cell_histograms: np.ndarray) -> np.ndarray:
    """[rows - 1, cols - 1, 36]: each 2 x 2 block of cells, L2-Hys normalised (L2, clipped at 0.2, L2 again)."""
    c = cell_histograms
    b = np.concatenate([c[:-1, :-1], c[:-1, 1:], c[1:, :-1], c[1:, 1:]], axis=-1)
    b /= np.sqrt(np.einsum("...k,...k->...", b, b) + 1e-6)[..., None]
    np.minimum(b, L2HYS_CLIP, out=b)
    b /= np.sqrt(np.einsum("...k,...k->...", b, b) + 1e-6)[..., None]
    return b


def window_features(table: np.ndarray, box: np.ndarray) -> np.ndarray:
    """[n, 3780] the features of windows around person boxes [n, 4] (u0, v0, u1, v1): the window 4/3 the box's height
    and half as wide, centred on it (Dalal & Triggs's margins), at the scale that makes it 128 pixels high."""
    box = np.asarray(box, float).reshape(-1, 4)
    height = (box[:, 3] - box[:, 1]) / PERSON_SHARE
    size = height / WINDOW_CELLS[0]
    centre_u, centre_v = (box[:, 0] + box[:, 2]) / 2, (box[:, 1] + box[:, 3]) / 2
    out = [blocks(cells(table, (cu - size_k * WINDOW_CELLS[1] / 2, cv - size_k * WINDOW_CELLS[0] / 2), size_k,
                        WINDOW_CELLS)).ravel()
           for cu, cv, size_k in zip(centre_u, centre_v, size)]
    return np.array(out).reshape(len(box), -1)


@dataclass(frozen=True)
class HogModel:
    """A linear classifier on the window features: score = features . weight + bias; a person where it exceeds
    ``threshold``."""

    weight: np.ndarray  # [3780]
    bias: float
    threshold: float

    def score_map(self, table: np.ndarray, size: float) -> np.ndarray:
        """The score of every window of cells ``size`` pixels wide on the cell grid from the image's corner: [rows,
        cols], window (r, c) covering pixels from (c size, r size), 64 size wide and 128 size high."""
        h, w = table.shape[0] - 1, table.shape[1] - 1
        grid = (int(h // size), int(w // size))
        rows, cols = grid[0] - WINDOW_CELLS[0] + 1, grid[1] - WINDOW_CELLS[1] + 1
        if rows <= 0 or cols <= 0:
            return np.zeros((0, 0))
        b = blocks(cells(table, (0.0, 0.0), size, grid))  # [rows + 14, cols + 6, 36]
        # Each block against the weights of each of the 15 x 7 block places of a window. b stays 3-d, so numpy makes
        # one product per block row, small enough for OpenBLAS to keep to one thread (one large product goes
        # multi-threaded, several times slower on a busy machine).
        places = (WINDOW_CELLS[0] - 1, WINDOW_CELLS[1] - 1)
        part = b @ self.weight.reshape(-1, b.shape[-1]).T.astype(np.float64)  # [rows + 14, cols + 6, 105]
        # window (r, c) sums part[r + i, c + j, 7 i + j] over its block places (i, j): a strided view of those
        sr, sc, sk = part.strides
        windows = np.lib.stride_tricks.as_strided(part, (rows, cols) + places, (sr, sc, sr + places[1] * sk, sc + sk),
                                                  writeable=False)
        return self.bias + np.einsum("rcij->rc", windows)

    def detect(self, rgb: np.ndarray, scales: np.ndarray, overlap: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
        """Person boxes [k, 4] (u0, v0, u1, v1 of the person, 3/4 of the window's height) and scores [k] over the
        given scales, greedy non-maximum suppression at ``overlap`` (intersection over union), best first."""
        table = integral(orientation_votes(rgb))
        found, scores = [], []
        for scale in scales:
            size = CELL * scale
            score = self.score_map(table, size)
            r, c = np.nonzero(score > self.threshold)
            u0, v0 = c * size, r * size
            found.append(person_in_window(u0, v0, WINDOW_CELLS[1] * size, WINDOW_CELLS[0] * size))
            scores.append(score[r, c])
        boxes, scores = np.concatenate(found).reshape(-1, 4), np.concatenate(scores)
        keep = non_maximum_suppression(boxes, scores, overlap)
        return boxes[keep], scores[keep]


def person_in_window(u0, v0, width, height) -> np.ndarray:
    """The person boxes [n, 4] (u0, v0, u1, v1) in detection windows from (u0, v0), ``width`` by ``height``: the
    middle ``PERSON_SHARE`` of the window's height and the middle half of its width (Dalal & Triggs's margins)."""
    margin_u, margin_v = width / 4, height * (1 - PERSON_SHARE) / 2
    return np.column_stack([u0 + margin_u, v0 + margin_v, u0 + width - margin_u, v0 + height - margin_v])


def load_model(path: str | Path | None = None, shipped: str = MODEL_FILE) -> HogModel:
    """The shipped model (``shipped``, the wall cameras' unless named), or the .npz at ``path`` that `crowdsim
    experiment train-hog --out` wrote."""
    path = Path(path) if path is not None else MODELS_DIR / shipped
    try:
        with np.load(path) as data:
            header = json.loads(str(data["header"]))
            model = HogModel(data["weight"], float(data["bias"]), float(data["threshold"]))
    except (OSError, ValueError, KeyError) as e:
        raise ValueError(f"model: {path} is not a HOG model ({e}); expected an .npz written by `crowdsim experiment "
                         "train-hog`") from None
    if header.get("format") != MODEL_FORMAT:
        raise ValueError(f"model: {path} has format {header.get('format')!r}; expected {MODEL_FORMAT}")
    return model


def box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union [n, m] of boxes a [n, 4] and b [m, 4] (u0, v0, u1, v1)."""
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, 2:], b[None, :, 2:])
    inter = np.prod(np.clip(hi - lo, 0, None), axis=-1)
    area_a = np.prod(a[:, 2:] - a[:, :2], axis=-1)
    area_b = np.prod(b[:, 2:] - b[:, :2], axis=-1)
    return inter / np.maximum(area_a[:, None] + area_b[None] - inter, 1e-12)


def non_maximum_suppression(boxes: np.ndarray, scores: np.ndarray, overlap: float) -> np.ndarray:
    """Indices of the boxes kept: the best first, then each one overlapping no kept one by more than ``overlap``."""
    order = np.argsort(-scores, kind="stable")
    keep: list[int] = []
    for k in order.tolist():
        if not keep or box_iou(boxes[k:k + 1], boxes[keep]).max() <= overlap:
            keep.append(k)
    return np.array(keep, np.int64)
