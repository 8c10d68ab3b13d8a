"""Duplicate tracks: the two guards of the SPENCER NNT against two tracks on one person, which seed 000 does not
describe but its tracker runs in every cycle (``srl_nearest_neighbor_tracker``, ``nearest_neighbor_tracker.cpp``:
``deleteDuplicateTracks`` and ``checkForClosebyExistingTrack``; the values are its defaults).

* **Duplicate deletion**: two tracks whose positions were within ``distance`` (0.15 m) of each other in at least
  ``must_match`` (7) of their last ``history`` (10) cycles follow one person (we compare the predicted positions,
  which the gating computes anyway; SPENCER the estimates before prediction); the one matched fewer times over its
  life goes (on a tie, the younger). Without it a track that lost its person and converged onto a neighbour's
  detections (NN with several tracks per detection does this, seed 000 Sec. V-A) stays for good, a false positive
  every cycle.
* **Clearance of new tracks**: a detection no track took starts no new track within ``clearance`` (0.25 m) of a
  track matched in the last ``recent`` (5) cycles: a person seen twice in one cycle (two legs, two lasers) is one.

The tracker is given the guards as a part (``NearestNeighbourTracker(duplicates=DuplicateGuard())``; none: neither
guard), named ``spencer`` in a scenario.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import param

__all__ = ["DUPLICATES", "DuplicateGuard"]


def _must_match_within_history(p: dict):
    if p["must_match"] > p["history"]:
        return "must_match", f"{p['must_match']}; expected at most history ({p['history']})"


@dataclass(frozen=True)
class DuplicateGuard:
    """The two guards with their parameters (metres, cycles); a distance of 0 turns its guard off."""

    distance: float = param(0.15, "m, two tracks this close in must_match of their last history cycles are one "
                                  "person's, and the one matched fewer times goes (SPENCER's duplicate deletion: "
                                  "0.15); 0: off", min=0.0)
    history: int = param(10, "cycles of each track's positions compared (SPENCER's: 10)", min=1)
    must_match: int = param(7, "of them, how many must be this close (SPENCER's: 7)", min=1)
    clearance: float = param(0.25, "m, no new candidate this close to a track matched in the last recent cycles "
                                   "(SPENCER's close-by check: 0.25); 0: off", min=0.0)
    recent: int = param(5, "a track missed fewer cycles in a row than this blocks new candidates (SPENCER's: 5)",
                        min=1)

    CHECKS = (_must_match_within_history,)

    def duplicates(self, past: np.ndarray, filled: np.ndarray, hits: np.ndarray) -> np.ndarray:
        """Which tracks go as duplicates: [n] bool.

        ``past`` [history, 2, n]: each track's positions at its last ``history`` cycles, the latest last; ``filled``
        [n]: how many of them it has (a track needs all of them to be compared); ``hits`` [n]: detections matched
        over its life. Rows are in creation order (a later row is younger).
        """
        full = np.flatnonzero(filled >= self.history)
        if self.distance <= 0.0 or full.size < 2:
            return np.zeros(hits.size, bool)
        p = past if full.size == hits.size else past[:, :, full]  # [H, 2, k]
        # Close in must_match of the last H cycles means close in one of the latest H - must_match + 1 at least, so
        # now nearer than distance plus how far either moved since then: only those pairs (few, found by sorting)
        # are counted over all H.
        recent = p[self.must_match - 1:]
        moved = np.sqrt(((recent - recent[-1]) ** 2).sum(axis=1).max(axis=0))  # [k]
        i, j = _close_pairs(p[-1, 0], p[-1, 1], self.distance + 2.0 * float(moved.max()))
        near = ((p[-1, :, i] - p[-1, :, j]) ** 2).sum(axis=-1) < (self.distance + moved[i] + moved[j]) ** 2
        i, j = i[near], j[near]
        if i.size == 0:
            return np.zeros(hits.size, bool)
        d2 = ((p[:, :, i] - p[:, :, j]) ** 2).sum(axis=1)  # [H, pairs]
        dup = np.count_nonzero(d2 < self.distance ** 2, axis=0) >= self.must_match
        i, j = i[dup], j[dup]
        gone = np.zeros(hits.size, bool)
        older_weaker = hits[full[i]] < hits[full[j]]
        gone[np.where(older_weaker, full[i], full[j])] = True
        return gone

    def blocked(self, z: np.ndarray, xy: np.ndarray, misses: np.ndarray) -> np.ndarray:
        """Which detections z [m, 2] start no track: within ``clearance`` of a track at xy [2, n] that has missed
        fewer than ``recent`` cycles in a row (``misses`` [n]): [m] bool."""
        near = xy[:, misses < self.recent]
        if self.clearance <= 0.0 or near.shape[1] == 0 or z.shape[0] == 0:
            return np.zeros(z.shape[0], bool)
        d2 = (z[:, 0, None] - near[0]) ** 2 + (z[:, 1, None] - near[1]) ** 2
        return (d2 < self.clearance ** 2).any(axis=1)


DUPLICATES = {"spencer": DuplicateGuard}


def _close_pairs(x: np.ndarray, y: np.ndarray, r: float) -> np.ndarray:
    """The pairs (a, b), a < b, of points (x, y) [k] nearer than r: [2, pairs]. Sorted by x, each point is compared
    only with those after it within r in x."""
    k = x.size
    order = np.argsort(x, kind="stable")
    xs = x[order]
    counts = np.searchsorted(xs, xs + r, side="left") - np.arange(1, k + 1)  # later points within r in x
    counts = np.maximum(counts, 0)
    first = np.repeat(np.arange(k), counts)
    offset = np.arange(first.size) - np.repeat(np.cumsum(counts) - counts, counts)
    a, b = order[first], order[first + 1 + offset]
    near = (x[a] - x[b]) ** 2 + (y[a] - y[b]) ** 2 < r * r
    return np.stack([np.minimum(a, b)[near], np.maximum(a, b)[near]])
