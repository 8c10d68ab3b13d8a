"""State that grows with the persons and tracks of a sequence, never with its frames: dense slots for ids and id
pairs, and sums that do not depend on how the frames were chunked.

Why: a run of any length is scored by streaming its frames in chunks (evaluation/stream.py). Every metric keeps its
state per id or per id pair in arrays indexed by slots that ``Slots`` hands out, and adds its per-frame values in an
order that makes the result the same, bit for bit, whatever the chunk boundaries.
"""

from __future__ import annotations

import math

import numpy as np

from pipeline.compiled import kernel

_EMPTY_I = np.zeros(0, np.int64)


def _find(ascending: np.ndarray, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each of ``keys`` is, or would go, in ``ascending``, and whether it is there."""
    at = np.searchsorted(ascending, keys)
    found = at < len(ascending)
    found[found] = ascending[at[found]] == keys[found]
    return at, found


class Slots:
    """A dense slot number for every int64 key seen so far (an id, or a ``pair_key``): slots are given in order of
    first appearance (the new keys of one call in ascending order), so per-key state lives in plain arrays."""

    def __init__(self):
        self.keys = _EMPTY_I  # [n] the key of each slot
        self._sorted = _EMPTY_I  # keys in ascending order
        self._slot = _EMPTY_I  # slot of each sorted key

    def __len__(self) -> int:
        return len(self.keys)

    def __call__(self, keys: np.ndarray, add: bool = True) -> np.ndarray:
        """The slot of each of ``keys``; unseen keys get new slots (``add``) or -1."""
        keys = np.asarray(keys, np.int64)
        if keys.size == 0:
            return _EMPTY_I
        unique, inverse = np.unique(keys, return_inverse=True)
        at, found = _find(self._sorted, unique)
        slot = np.full(len(unique), -1, np.int64)
        slot[found] = self._slot[at[found]]
        if add and not found.all():
            new = unique[~found]
            slot[~found] = len(self.keys) + np.arange(len(new))
            self._sorted = np.insert(self._sorted, at[~found], new)
            self._slot = np.insert(self._slot, at[~found], slot[~found])
            self.keys = np.concatenate([self.keys, new])
        return slot[inverse.reshape(-1)]


class Counts:
    """How often each int64 key was seen, 12 bytes a key (for the pairs of persons and tracks ever in one frame:
    more than a million in an hour-long run). The keys are kept in order in segments of up to ``2 * segment`` keys:
    a new key copies its segment only, never all of them (ids come and go, so the new keys of a stretch of frames
    fall in a few segments)."""

    def __init__(self, segment: int = 1 << 16):
        self.segment = segment
        self.keys: list[np.ndarray] = []  # per segment, ascending; each segment's keys below the next one's
        self.counts: list[np.ndarray] = []  # int32, per segment
        self._first = _EMPTY_I  # the first key of each segment but the first

    def __len__(self) -> int:
        return sum(len(k) for k in self.keys)

    def add(self, keys: np.ndarray) -> None:
        self.add_counts(*np.unique(keys, return_counts=True))

    def add_counts(self, keys: np.ndarray, counts: np.ndarray) -> None:
        """Add ``counts`` to ``keys`` (ascending, each once)."""
        counts = counts.astype(np.int32)
        if not self.keys:
            self.keys, self.counts = [keys[:0]], [counts[:0]]
        bounds = np.searchsorted(keys, self._first)  # where each segment's keys begin among ``keys``
        for s, (lo, hi) in enumerate(zip(np.r_[0, bounds], np.r_[bounds, len(keys)])):
            if lo == hi:
                continue
            k, c, seg = keys[lo:hi], counts[lo:hi], self.keys[s]
            at, found = _find(seg, k)
            self.counts[s][at[found]] += c[found]
            if not found.all():
                self.keys[s] = np.insert(seg, at[~found], k[~found])
                self.counts[s] = np.insert(self.counts[s], at[~found], c[~found])
        if max(len(k) for k in self.keys) > 2 * self.segment:
            self._split()

    def _split(self) -> None:
        keys, counts = [], []
        for k, c in zip(self.keys, self.counts):
            if len(k) > 2 * self.segment:
                keys += [k[i:i + self.segment].copy() for i in range(0, len(k), self.segment)]
                counts += [c[i:i + self.segment].copy() for i in range(0, len(k), self.segment)]
            else:
                keys.append(k)
                counts.append(c)
        self.keys, self.counts = keys, counts
        self._first = np.array([k[0] for k in keys[1:]], np.int64)


def pair_key(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """One int64 key per pair of slots (each below 2^31)."""
    return (np.asarray(a, np.int64) << 32) | np.asarray(b, np.int64)


def split_pair_key(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return key >> 32, key & 0xFFFFFFFF


def grown(a: np.ndarray, n: int) -> np.ndarray:
    """``a`` with room for at least ``n`` rows along its first axis (zero-filled, doubling), so that per-slot
    arrays grow in amortised constant time."""
    if len(a) >= n:
        return a
    out = np.zeros((max(n, 2 * len(a), 16), *a.shape[1:]), a.dtype)
    out[:len(a)] = a
    return out


class ExactSum:
    """The exactly rounded sum of every value added (Shewchuk's algorithm, as ``math.fsum``), kept as a few
    non-overlapping partials: a mean over frames that does not depend on chunking or on the order of the frames."""

    def __init__(self):
        self._partials = np.zeros(8)  # room for the partials, self._n of them in use
        self._n = 0
        self.count = 0

    def add(self, values) -> None:
        values = np.asarray(values, np.float64).reshape(-1)
        if self._n + len(values) >= len(self._partials):  # each value adds at most one partial
            self._partials = np.concatenate([self._partials, np.zeros(self._n + len(values) + 1)])
        self._n = _add_exactly(self._partials, self._n, values)
        self.count += len(values)

    @property
    def partials(self) -> list[float]:
        """The non-overlapping partials whose sum is the total, smallest first."""
        return self._partials[:self._n].tolist()

    @property
    def total(self) -> float:
        return math.fsum(self.partials)

    def mean(self) -> float | None:
        return self.total / self.count if self.count else None


@kernel
def _add_exactly(partials, n, values):
    """Shewchuk's partials ``partials[:n]`` with ``values`` added, in place; returns how many partials there are
    now. Each value runs through the partials, smallest first, keeping the round-off of each addition as a partial
    (two-sum: hi + lo is exactly x + y)."""
    for x in values:
        i = 0
        for k in range(n):
            y = partials[k]
            if abs(x) < abs(y):
                x, y = y, x
            hi = x + y
            lo = y - (hi - x)
            if lo != 0.0:
                partials[i] = lo
                i += 1
            x = hi
        partials[i] = x
        n = i + 1
    return n
