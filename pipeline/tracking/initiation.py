"""Track initiation logic (seed 000 Sec. III-B, Alg. 1, Sec. V-B): which initiation candidates become tracks.

Every detection no track took starts a candidate; a candidate takes, of the detections still left, the nearest one
(greedy NN on the Mahalanobis distance from its Kalman prediction, within the tracker's gate: Alg. 1's "check
distance between prediction and z_j", with the candidate's own uncertainty in place of a fixed radius the seed does
not give) that passes the velocity gate below, and is confirmed once it holds enough detections. A candidate missing
the deletion logic's ``tentative`` cycles in a row is dropped (Alg. 1's n_miss,max + 1). Three kinds:

* ``none``: no velocity gate; confirmed after ``n_confirm`` detections (the creating one included). The tracker's
  behaviour before the logic existed.
* ``base``: the speed from the candidate's latest detection to the new one must lie in [v_min, v_max]; confirmed
  after ``n_min`` detections (seed 000 Sec. V-B: "the basic version which just performs velocity gating on the
  latest associated detection").
* ``extended``: the speed from *every* earlier detection of the candidate must lie in [v_min, v_max] (Alg. 1: "check
  velocity between all z in Z_c and z_j"), which rejects candidates that move back and forth on the spot.

Every kind also says how a candidate starts: at its detection with zero velocity, of per-axis variance
``initial_velocity_variance`` (the prior a new track gets). An initiation logic is anything with ``needed``,
``history``, ``initial_velocity_variance`` and (with a history) ``velocity_ok``; the tracker is given one
(``NearestNeighbourTracker(initiation=...)``).

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

from ..params import param

__all__ = ["INITIATIONS", "CountInitiation", "BaseInitiation", "ExtendedInitiation"]

_VELOCITY_VARIANCE = dict(
    default=1.0, min=0.0, exclusive_min=True,
    doc="m^2/s^2, per-axis velocity variance of a new track, whose velocity is unknown: a walker at ~1.3 m/s with a "
        "uniformly random heading has E[vx^2] = 1.3^2 / 2 = 0.845 m^2/s^2, rounded up to 1.0 to cover faster walkers")


@dataclass(frozen=True)
class CountInitiation:
    """``none``: no velocity gate; a candidate is confirmed after ``n_confirm`` detections."""

    n_confirm: int = param(3, "detections that confirm a new track (the creating one included)", min=1)
    initial_velocity_variance: float = param(**_VELOCITY_VARIANCE)

    history = 0
    """Detections of each candidate the velocity gate looks back on: none, there is no gate."""

    @property
    def needed(self) -> int:
        """Detections (the creating one included) that confirm a candidate."""
        return self.n_confirm


def _speeds_ordered(p: dict):
    if not p["v_min"] < p["v_max"]:
        return "v_min", f"{p['v_min']:g}; expected below v_max ({p['v_max']:g})"


@dataclass(frozen=True)
class BaseInitiation:
    """``base``: the speed from the candidate's latest detection to the new one lies in [v_min, v_max]."""

    n_min: int = param(6, "detections that confirm a track (seed 000 Sec. V-B: 6; the velocity gate needs two)",
                       min=2)
    v_min: float = param(0.2, "m/s, slowest speed between a candidate's detections (seed 000 Sec. V-B: 0.2)", min=0.0)
    v_max: float = param(2.0, "m/s, fastest speed between a candidate's detections (seed 000 Sec. V-B: 2)", min=0.0,
                         exclusive_min=True)
    position_slack: float = param(
        0.1, "m, detection noise allowed on top of v_max * dt (seed 000 gives none). On airport_disembarkation "
             "(laser_segments, 20 s, 15,000 detections) the error of a person's detection changed from one cycle to "
             "the next by 1.6 cm (median), 4.9 cm (90 %) and 9.3 cm (99 %): 0.1 m lets 99 % of such steps through, "
             "where a walker at 1.3 m/s moves only 5.2 cm per 25 Hz cycle", min=0.0)
    initial_velocity_variance: float = param(**_VELOCITY_VARIANCE)

    CHECKS = (_speeds_ordered,)
    LATEST_ONLY = True

    @property
    def needed(self) -> int:
        """Detections (the creating one included) that confirm a candidate."""
        return self.n_min

    @property
    def history(self) -> int:
        """Detections of each candidate the velocity gate looks back on."""
        return self.n_min

    def velocity_ok(self, hist: np.ndarray, count: np.ndarray, z: np.ndarray, stamp: float) -> np.ndarray:
        """Whether each of k (candidate, detection) pairs passes the velocity gate: [k] bool.

        hist [3, L, k], count [k]: the candidate's detections (x, y) and their stamps, the first count[i] of them
        filled; z [k, 2]: the detection at ``stamp``. ``base`` checks the latest of them, ``extended`` all of them.
        """
        if self.LATEST_ONLY:
            hist, checked = hist[:, count - 1, np.arange(count.size)][:, None], np.ones((1, count.size), bool)
        else:
            checked = np.arange(hist.shape[1])[:, None] < count  # [L, k]
        dt = stamp - hist[2]
        d2 = (z[:, 0] - hist[0]) ** 2 + (z[:, 1] - hist[1]) ** 2  # squared distances, [L, k]
        ok = (d2 >= (self.v_min * dt) ** 2) & (d2 <= (self.v_max * dt + self.position_slack) ** 2)
        return (ok | ~checked).all(axis=0)


@dataclass(frozen=True)
class ExtendedInitiation(BaseInitiation):
    """``extended``: the speed from *every* earlier detection of the candidate lies in [v_min, v_max]."""

    LATEST_ONLY = False


INITIATIONS = {"none": CountInitiation, "base": BaseInitiation, "extended": ExtendedInitiation}
