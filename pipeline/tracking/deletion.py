"""Track deletion logic (seed 000 Sec. III-C, V-C): after how many cycles in a row without a detection a track goes.

* ``fixed``: a confirmed track after ``n_delete`` misses (the base NNT, seed 000 Sec. V-C: n_del = 5).
* ``young_mature``: a track matched ``mature_after`` times or more over its life (n^mat = 100) is mature and goes
  after ``mature`` misses (n_del^mat = 50); a younger one after ``young`` (n_del^yng = 20), since false-alarm tracks
  are young (seed 000 Sec. III-C; the values are Sec. V-C's).

Initiation candidates (unconfirmed tracks) go after ``tentative`` misses either way. A deletion logic is anything
with ``limits(confirmed, hits)``; the tracker is given one (``NearestNeighbourTracker(deletion=...)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import param

__all__ = ["DELETIONS", "FixedDeletion", "YoungMatureDeletion"]

_TENTATIVE = dict(min=1, doc="misses that delete an unconfirmed track (Alg. 1's n_miss,max + 1; seed 000: none)")


@dataclass(frozen=True)
class FixedDeletion:
    """``fixed``: one limit for every confirmed track."""

    n_delete: int = param(5, "misses that delete a confirmed track (seed 000 Sec. V-C: 5)", min=1)
    tentative: int = param(2, **_TENTATIVE)

    def limits(self, confirmed: np.ndarray, hits: np.ndarray) -> np.ndarray:
        """Consecutive misses [n] at which each track is deleted, from whether it is confirmed [n] and the
        detections it was matched with over its life [n] (the creating one included)."""
        return np.where(confirmed, self.n_delete, self.tentative)


@dataclass(frozen=True)
class YoungMatureDeletion:
    """``young_mature``: mature tracks are kept longer than young ones."""

    young: int = param(20, "misses that delete a young track (seed 000 Sec. V-C: 20)", min=1)
    mature: int = param(50, "misses that delete a mature track (seed 000 Sec. V-C: 50)", min=1)
    mature_after: int = param(100, "detections that make a track mature (seed 000 Sec. V-C: 100)", min=1)
    tentative: int = param(2, **_TENTATIVE)

    def limits(self, confirmed: np.ndarray, hits: np.ndarray) -> np.ndarray:
        """As ``FixedDeletion.limits``."""
        return np.where(confirmed, np.where(hits >= self.mature_after, self.mature, self.young), self.tentative)


DELETIONS = {"fixed": FixedDeletion, "young_mature": YoungMatureDeletion}
