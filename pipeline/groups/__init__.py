"""The group stage: social relations between tracks, groups cut from them, and groups tracked by composition
(seed 000's SPENCER; ``CoherentMotionGroups`` puts the three together)."""

from __future__ import annotations

import numpy as np

from pipeline.types import SocialRelations, TrackedGroups, TrackedPersons

from .detection import LINKAGES, detect_groups
from .relations import LongTermRelations, RelationEstimator
from .tracking import CompositionTracker

__all__ = ["CoherentMotionGroups", "LINKAGES"]


class CoherentMotionGroups:
    """``update(stamp, tracks) -> (SocialRelations, TrackedGroups)``: every pair of tracks with its strength
    (relations.py), clusters of the pairs at or above ``threshold`` (detection.py, by ``linkage``), and their ids
    kept by composition (tracking.py). ``smoothing``: SPENCER's long-term relations between the two. The defaults
    are SPENCER's group stage as released (its model, single linkage at 0.5); the airport's is ours."""

    def __init__(self, model: str = "spencer", threshold: float = 0.5, linkage: str = "single", smoothing: bool = False,
                 max_distance: float = 3.0, max_speed_difference: float = 1.0,
                 max_heading_difference: float = np.pi / 4, min_speed: float = 0.1, memory: int = 300):
        self.relations = RelationEstimator(model, max_distance, max_speed_difference, max_heading_difference,
                                           min_speed)
        self.threshold, self.linkage = threshold, linkage
        self.long_term = LongTermRelations() if smoothing else None
        self.tracker = CompositionTracker(memory)

    def reset(self) -> None:
        self.tracker.reset()
        if self.long_term is not None:
            self.long_term.reset()

    def update(self, stamp: float, tracks: TrackedPersons) -> tuple[SocialRelations, TrackedGroups]:
        i, j, strength = self.relations.strengths(tracks.position, tracks.velocity)
        a, b = tracks.track_id[i], tracks.track_id[j]
        if self.long_term is not None:
            distance = np.hypot(*(tracks.position[i] - tracks.position[j]).T)
            strength = self.long_term.smooth(stamp, a, b, strength, distance)
        labels = detect_groups(len(tracks), i, j, strength, self.threshold, self.linkage)
        groups = self.tracker.update(stamp, tracks.frame, tracks.track_id, tracks.position, labels)
        return SocialRelations(stamp, a, b, strength), groups
