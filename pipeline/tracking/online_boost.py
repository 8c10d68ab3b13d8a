"""Seed 003's per-track appearance classifier (Munaro & Menegatti Sec. 3.2.1): online boosting (Grabner & Bischof
2006, "On-line boosting and vision", CVPR) over features of a track's colour histogram.

A sample is the joint colour histogram of a detection's pixels, 16 bins a channel (Eq. 1), normalised to sum 1. Each
of a pool of 250 weak classifiers looks at one feature: the histogram's mass inside a random axis-aligned box of
colour space (Eq. 2), and says positive when that mass is nearer the running mean of the track's samples than of the
others' (means followed by a Kalman filter, as Grabner & Bischof's weak learners). 50 selectors each choose, from the
shared pool, the weak classifier of least importance-weighted error so far that no earlier selector took (else, after
a first sample, every selector takes the same one and the vote is all or nothing); the strong classifier's confidence is the
selectors' votes weighted by log((1 - e) / e) / 2, positive for the track's colours.

Positives are the track's own detections; negatives the other detections of the frame and random image windows
(seed 003 Fig. 8b). The boxes, as in the authors' code, span [i1, i2) with i2 uniform in 1..16 and i1 uniform below
it, per channel.
"""

from __future__ import annotations

import numpy as np

BINS = 16  # a channel (seed 003 Sec. 3.2.1)
POOL = 250  # weak classifiers (Table 7)
SELECTORS = 50  # Table 7
# the weak learners' Kalman filter on a class's mean feature: initial variance, measurement and process noise
# (Grabner & Bischof's implementation's values)
P0, R, Q = 1000.0, 0.01, 0.001


def colour_histogram(colours: np.ndarray, bins: int = BINS) -> np.ndarray:
    """The normalised joint histogram [bins ** 3] of 8-bit colours [n, 3] (all zeros for none)."""
    c = np.asarray(colours, np.int64).reshape(-1, 3) * bins // 256
    counts = np.bincount((c[:, 0] * bins + c[:, 1]) * bins + c[:, 2], minlength=bins ** 3).astype(float)
    total = counts.sum()
    return counts / total if total else counts


def rgb_to_hsv(rgb: np.ndarray) -> np.ndarray:
    """8-bit RGB [..., 3] to 8-bit HSV with all three channels on 0-255 (hue's 360 degrees over 256 values), so that
    ``colour_histogram`` bins every channel alike."""
    c = np.asarray(rgb, np.float64)
    high, low = c.max(-1), c.min(-1)
    span = high - low
    safe = np.where(span > 0, span, 1.0)
    r, g, b = np.moveaxis(c, -1, 0)
    sextant = np.where(high == r, ((g - b) / safe) % 6, np.where(high == g, (b - r) / safe + 2, (r - g) / safe + 4))
    hue = np.where(span > 0, np.minimum(np.floor(sextant * (256 / 6)), 255), 0)
    saturation = np.where(high > 0, np.rint(255 * span / np.where(high > 0, high, 1.0)), 0)
    return np.stack([hue, saturation, high], -1).astype(np.uint8)


class OnlineColourClassifier:
    """One track's classifier (module docstring)."""

    def __init__(self, rng: np.random.Generator, bins: int = BINS, pool: int = POOL, selectors: int = SELECTORS):
        self.bins = bins
        upper = rng.integers(1, bins + 1, (pool, 3))
        lower = (rng.random((pool, 3)) * upper).astype(np.int64)
        self.boxes = np.stack([lower, upper], axis=-1)  # [pool, channel, (from, to)]
        self.mean = np.zeros((2, pool))  # the negatives' and the positives' mean feature
        self.variance = np.full((2, pool), P0)
        self.seen = np.zeros(2, bool)
        self.right = np.full((selectors, pool), 1.0)  # importance-weighted counts, with a prior of 1 each
        self.wrong = np.full((selectors, pool), 1.0)
        self.chosen = np.zeros(selectors, np.int64)
        self.alpha = np.zeros(selectors)

    def features(self, histogram: np.ndarray) -> np.ndarray:
        """Each weak classifier's feature: the histogram's mass inside its colour box (Eq. 2), from the summed-volume
        table by inclusion and exclusion."""
        b = self.bins
        table = np.zeros((b + 1, b + 1, b + 1))
        table[1:, 1:, 1:] = histogram.reshape(b, b, b).cumsum(0).cumsum(1).cumsum(2)
        (r0, r1), (g0, g1), (b0, b1) = self.boxes[:, 0].T, self.boxes[:, 1].T, self.boxes[:, 2].T
        return (table[r1, g1, b1] - table[r0, g1, b1] - table[r1, g0, b1] - table[r1, g1, b0]
                + table[r0, g0, b1] + table[r0, g1, b0] + table[r1, g0, b0] - table[r0, g0, b0])

    def _votes(self, f: np.ndarray) -> np.ndarray:
        """Each weak classifier's +1 / -1 on features ``f`` (+1 until both classes have been seen)."""
        if not self.seen.all():
            return np.ones_like(f)
        return np.where(np.abs(f - self.mean[1]) <= np.abs(f - self.mean[0]), 1.0, -1.0)

    def update(self, histogram: np.ndarray, positive: bool) -> None:
        """One sample: every weak classifier's class mean moves (Kalman), then each selector in turn counts its
        classifiers right or wrong with the sample's importance, picks the best and passes the sample on with its
        importance raised where that one was wrong (Grabner & Bischof, Alg. 2)."""
        f = self.features(histogram)
        k = int(positive)
        gain = self.variance[k] / (self.variance[k] + R)
        self.mean[k] += gain * (f - self.mean[k])
        self.variance[k] = (1 - gain) * self.variance[k] + Q
        self.seen[k] = True
        correct = self._votes(f) == (1.0 if positive else -1.0)
        importance = 1.0
        taken = np.zeros(len(correct), bool)
        for n in range(len(self.chosen)):
            self.right[n] += importance * correct
            self.wrong[n] += importance * ~correct
            error = self.wrong[n] / (self.right[n] + self.wrong[n])
            best = int(np.where(taken, np.inf, error).argmin())  # each selector a feature of its own
            taken[best] = True
            e = float(error[best])
            self.chosen[n] = best
            self.alpha[n] = 0.5 * np.log((1 - e) / e) if e < 0.5 else 0.0
            importance *= 1 / (2 * (1 - e)) if correct[best] else 1 / (2 * e)

    def confidence(self, histogram: np.ndarray) -> float:
        """The strong classifier's weighted vote, normalised to [-1, 1] (positive: the track's colours)."""
        total = self.alpha.sum()
        if total <= 0:
            return 0.0
        return float(self.alpha @ self._votes(self.features(histogram))[self.chosen] / total)
