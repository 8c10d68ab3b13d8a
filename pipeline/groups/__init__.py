"""The group stage: social relations between tracks, groups cut from them, and groups tracked by composition
(seed 000's SPENCER; ``CoherentMotionGroups`` puts the three together)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.params import param
from pipeline.types import SocialRelations, TrackedGroups, TrackedPersons

from .detection import LINKAGES, detect_groups
from .relations import LongTermRelations, RelationEstimator
from .tracking import CompositionTracker

__all__ = ["CoherentMotionGroups", "GROUP_STAGES", "LINKAGES"]


@dataclass(eq=False)
class CoherentMotionGroups:
    """``update(stamp, tracks) -> (SocialRelations, TrackedGroups)``: every pair of tracks with its strength
    (relations.py), clusters of the pairs at or above ``threshold`` (detection.py, by ``linkage``), and their ids
    kept by composition (tracking.py). ``smoothing``: SPENCER's long-term relations between the two. The defaults
    are SPENCER's group stage as released (its model, single linkage at 0.5); the airport's is ours."""

    model: str = param("spencer", "relation classifier: spencer (SPENCER's released linear SVM, "
                                  "groups_probabilistic_small.model), svm (ours: linear SVM on cubic monomials + "
                                  "Platt) or forest (ours: random forest), both trained on airport tracker output by "
                                  "`crowdsim experiment train-relations`, or the path of a model it wrote")
    threshold: float = param(0.5, "least relation strength that joins two tracks (SPENCER's tracked_groups.py: 0.5)",
                             min=0.0, max=1.0)
    linkage: str = param("single", "single: groups are the connected components (SPENCER's); complete/average: each "
                                   "component clustered again so a queue of strangers does not chain "
                                   "(pipeline/groups/detection.py)", choices=LINKAGES)
    smoothing: bool = param(False, "SPENCER's long-term relations: strengths rise and fall at limited rates")
    max_distance: float = param(3.0, "m, farther pairs get strength 0.1 (SPENCER's gate)", min=0.0)
    max_speed_difference: float = param(1.0, "m/s, pairs with speeds further apart get 0.1", min=0.0)
    max_heading_difference: float = param(math.pi / 4, "rad, pairs with headings further apart get 0.1 (SPENCER's: "
                                                       "pi/4)", min=0.0)
    min_speed: float = param(0.1, "m/s, a slower track's heading is taken as 0 (SPENCER's)", min=0.0)
    memory: int = param(300, "member sets the composition tracker remembers (SPENCER's: 300)", min=1)

    def __post_init__(self):
        self.relations = RelationEstimator(self.model, self.max_distance, self.max_speed_difference,
                                           self.max_heading_difference, self.min_speed)
        self.long_term = LongTermRelations() if self.smoothing else None
        self.tracker = CompositionTracker(self.memory)

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


GROUP_STAGES: dict[str, type] = {"coherent_motion": CoherentMotionGroups}
