"""How the project compiles a kernel: numba's ``njit``, cached on disk.

Why: the robot's software and the crowd work on arrays of 10-1,000 elements, where numpy's cost is its per-call
overhead, not the arithmetic (../shared/briefs/profile.md: about 5,300 numpy-level calls a tracking cycle). A path
bound by that overhead is written once, as a loop compiled here; it is the only implementation of its idea (no numpy
twin kept in step), and its tests check it against hand-worked values.

The settings: ``cache=True`` keeps the machine code next to the module (or in numba's user cache where the package
is read-only), so a process after the first loads it instead of compiling; ``error_model="numpy"`` makes a division
by zero give inf or NaN as numpy does, rather than raise; no ``fastmath``, so the arithmetic is IEEE's, in the order
written. numba checks no array bounds: the Python function that calls a kernel checks the shapes of what it was given.

numba's cache keys a kernel on its own source file: one that calls a kernel of another module (this one's
``segment_sum``, ``by_label``) keeps its old machine code when only that other module changes. After editing a kernel
that others call, clear the caches (``find . -name '*.nbi' -delete``); a fresh install has no cache to go stale.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["by_label", "elementwise", "kernel", "union_root"]


def kernel(fn):
    """``fn`` compiled (at its first call, or loaded from the cache)."""
    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)


def elementwise(fn):
    """The scalar function ``fn`` of float64 compiled as a numpy ufunc: called on numbers or arrays (broadcast, as
    numpy's own), and from inside kernels, the one implementation for both."""
    ufunc = numba.vectorize(["float64(float64)"], cache=True)(fn)
    ufunc.__doc__ = fn.__doc__
    return ufunc


@kernel
def _block(values, lo, n):
    """Numpy's pairwise sum of at most 128 values: one running sum below 8, else eight interleaved ones."""
    if n < 8:
        total = 0.0
        for i in range(lo, lo + n):
            total += values[i]
        return total
    r0, r1, r2, r3 = values[lo], values[lo + 1], values[lo + 2], values[lo + 3]
    r4, r5, r6, r7 = values[lo + 4], values[lo + 5], values[lo + 6], values[lo + 7]
    i = lo + 8
    while i < lo + n - n % 8:
        r0 += values[i]
        r1 += values[i + 1]
        r2 += values[i + 2]
        r3 += values[i + 3]
        r4 += values[i + 4]
        r5 += values[i + 5]
        r6 += values[i + 6]
        r7 += values[i + 7]
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < lo + n:
        total += values[i]
        i += 1
    return total


@kernel
def pairwise(values, lo, n):
    """The sum of ``values[lo:lo + n]`` in numpy's pairwise order: more accurate than one running sum, and the order
    numpy's reductions use. Above 128 values numpy halves the range (the first half a multiple of 8) and adds the
    halves' sums; the same tree is walked here with a stack, since numba's cache cannot hold a recursive kernel."""
    if n <= 128:
        return _block(values, lo, n)
    start, count, stage, left = np.empty(64, np.int64), np.empty(64, np.int64), np.zeros(64, np.int64), np.empty(64)
    top, start[0], count[0] = 0, lo, n
    result, returning = 0.0, False
    while True:
        if returning:
            if top < 0:
                return result
            if stage[top] == 1:  # the left half's sum: keep it, then the right half
                left[top], stage[top] = result, 2
                half = count[top] // 2 - (count[top] // 2) % 8
                top += 1
                start[top], count[top], stage[top] = start[top - 1] + half, count[top - 1] - half, 0
                returning = False
            else:  # the right half's: the range's sum is the two
                result = left[top] + result
                top -= 1
        elif count[top] <= 128:
            result, returning = _block(values, start[top], count[top]), True
            top -= 1
        else:
            stage[top] = 1
            top += 1
            start[top], count[top], stage[top] = start[top - 1], count[top - 1] // 2 - (count[top - 1] // 2) % 8, 0


@kernel
def segment_sum(values, lo, n):
    """The sum of ``values[lo:lo + n]`` as ``np.add.reduceat`` gives it: the first, plus the rest pairwise."""
    if n <= 129:
        return values[lo] + _block(values, lo + 1, n - 1)
    return values[lo] + pairwise(values, lo + 1, n - 1)


@kernel
def by_label(labels, k):
    """The elements of labels 0..k-1 (others, such as -1 or k, left out) in order of label, then of element (a counting
    sort): label c's are ``order[start[c]:start[c + 1]]``. For the clusters of a cycle, where numpy's argsort and
    unique cost their call overhead many times over."""
    start = np.zeros(k + 1, np.int64)
    for c in labels:
        if 0 <= c < k:
            start[c + 1] += 1
    for c in range(k):
        start[c + 1] += start[c]
    order, fill = np.empty(start[k], np.int64), start[:k].copy()
    for e in range(len(labels)):
        if 0 <= labels[e] < k:
            order[fill[labels[e]]] = e
            fill[labels[e]] += 1
    return start, order


@kernel
def union_root(parent, v):
    """The root of node ``v`` in a union-find forest (``parent`` [n]), each node on the way pointed at its
    grandparent (path halving)."""
    while parent[v] != v:
        parent[v] = parent[parent[v]]
        v = parent[v]
    return v
