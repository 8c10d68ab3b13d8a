"""Track initiation logic (seed 000 Sec. III-B, Alg. 1, Sec. V-B): which initiation candidates become tracks.

Every detection no track took starts a candidate; a candidate takes, of the detections still left, the nearest one
(greedy NN on the Mahalanobis distance from its Kalman prediction, within the tracker's gate: Alg. 1's "check
distance between prediction and z_j", with the candidate's own uncertainty in place of a fixed radius the seed does
not give) that passes the velocity gate below, and is confirmed once it holds enough detections. A candidate missing
``n_delete_tentative`` cycles in a row is dropped (Alg. 1's n_miss,max + 1). Three kinds:

* ``none``: no velocity gate; confirmed after ``n_confirm`` detections (the creating one included). The tracker's
  behaviour before the logic existed.
* ``base``: the speed from the candidate's latest detection to the new one must lie in [v_min, v_max]; confirmed
  after ``n_min`` detections (seed 000 Sec. V-B: "the basic version which just performs velocity gating on the
  latest associated detection").
* ``extended``: the speed from *every* earlier detection of the candidate must lie in [v_min, v_max] (Alg. 1: "check
  velocity between all z in Z_c and z_j"), which rejects candidates that move back and forth on the spot.

Alg. 1 tests |Z_c| >= n_min before adding the new detection, which would confirm at the (n_min + 1)-th; here the
candidate is confirmed at its n_min-th detection, as Sec. V-B words it ("requiring at least n_min = 6 matches").

The speed test between detections (z_a, t_a) and (z_b, t_b) is v_min (t_b - t_a) <= |z_b - z_a| <= v_max (t_b - t_a)
+ ``position_slack``: detection noise moves a detection by several centimetres from one cycle to the next, as much
as a walker moves in one cycle at 25 Hz, so the upper bound has to allow for it. The lower bound has none: what keeps
standing persons (and pillars) out is that they do not get further than noise from where they were first seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["INITIATIONS", "InitiationLogic"]

INITIATIONS = ("none", "base", "extended")


@dataclass(frozen=True)
class InitiationLogic:
    """One of ``INITIATIONS`` with its parameters (units: metres, seconds)."""

    kind: str
    n_confirm: int
    n_min: int
    v_min: float
    v_max: float
    position_slack: float

    @property
    def needed(self) -> int:
        """Detections (the creating one included) that confirm a candidate."""
        return self.n_confirm if self.kind == "none" else self.n_min

    @property
    def history(self) -> int:
        """Detections of each candidate the velocity gate looks back on (0: no gate)."""
        return 0 if self.kind == "none" else self.n_min

    def velocity_ok(self, hist: np.ndarray, count: np.ndarray, z: np.ndarray, stamp: float) -> np.ndarray:
        """Whether each of k (candidate, detection) pairs passes the velocity gate: [k] bool.

        hist [3, L, k], count [k]: the candidate's detections (x, y) and their stamps, the first count[i] of them
        filled; z [k, 2]: the detection at ``stamp``. ``base`` checks the latest of them, ``extended`` all of them.
        """
        if self.kind == "base":
            hist, checked = hist[:, count - 1, np.arange(count.size)][:, None], np.ones((1, count.size), bool)
        else:
            checked = np.arange(hist.shape[1])[:, None] < count  # [L, k]
        dt = stamp - hist[2]
        d2 = (z[:, 0] - hist[0]) ** 2 + (z[:, 1] - hist[1]) ** 2  # squared distances, [L, k]
        ok = (d2 >= (self.v_min * dt) ** 2) & (d2 <= (self.v_max * dt + self.position_slack) ** 2)
        return (ok | ~checked).all(axis=0)
