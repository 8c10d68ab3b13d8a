"""Track deletion logic (seed 000 Sec. III-C, V-C): after how many cycles in a row without a detection a track goes.

* ``fixed``: a confirmed track after ``n_delete`` misses (the base NNT, seed 000 Sec. V-C: n_del = 5).
* ``young_mature``: a track matched ``mature_after`` times or more over its life (n^mat = 100) is mature and goes
  after ``n_delete_mature`` misses (n_del^mat = 50); a younger one after ``n_delete_young`` (n_del^yng = 20), since
  false-alarm tracks are young (seed 000 Sec. III-C; the values are Sec. V-C's).

Initiation candidates (unconfirmed tracks) go after ``n_delete_tentative`` misses either way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DELETIONS", "DeletionLogic"]

DELETIONS = ("fixed", "young_mature")


@dataclass(frozen=True)
class DeletionLogic:
    """One of ``DELETIONS`` with its parameters (counts of tracking cycles and of detections)."""

    kind: str
    n_delete: int
    n_delete_tentative: int
    n_delete_young: int
    n_delete_mature: int
    mature_after: int

    def limits(self, confirmed: np.ndarray, hits: np.ndarray) -> np.ndarray:
        """Consecutive misses [n] at which each track is deleted, from whether it is confirmed [n] and the
        detections it was matched with over its life [n] (the creating one included)."""
        if self.kind == "fixed":
            kept = self.n_delete
        else:
            kept = np.where(hits >= self.mature_after, self.n_delete_mature, self.n_delete_young)
        return np.where(confirmed, kept, self.n_delete_tentative)
