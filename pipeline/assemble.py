"""The pipeline as parts: the interfaces of detectors, fusion, trackers and the group stage, the built-in types by
name, and ``build_pipeline``, which makes the parts a scenario's (validated) ``pipeline`` section names.

A part is named by its type, a built-in one below or ``module.path:ClassName``, and made as ``cls(**params)`` with
the section's other keys; every part starts over with ``reset()``. The scenario format (scenarios/format.py) holds
each built-in type's parameters under the same names; a test keeps the two registries equal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

from scenarios.schema import ScenarioError, import_class

from .detectors.laser_segments import SegmentDetector
from .detectors.learned_segments import LearnedSegmentDetector
from .detectors.legs import LegDetector
from .detectors.rgbd import RgbdPeopleDetector
from .detectors.wall_camera import WallCameraDetector
from .fusion import NearestFusion
from .groups import CoherentMotionGroups
from .map_filter import MapFilter
from .tracking.mht import MultiHypothesisTracker
from .tracking.nnt import NearestNeighbourTracker
from .tracking.rgbd_tracker import RgbdTracker
from .tracking.rjmcmc import RjmcmcTracker
from .types import (CameraFrame, DepthFrame, DetectedPersons, LaserScan, SocialRelations, TrackedGroups,
                    TrackedPersons)


class Detector(Protocol):
    """Turns one sensor's frame into detections in that sensor's frame; never reads the frame's ground truth
    (``LaserScan.person_id``, camera segmentation). A detector with several kinds of detection gives them as named
    batches, which reach the fusion as ``sensor/name``."""

    def detect(self, frame: LaserScan | DepthFrame | CameraFrame) -> DetectedPersons | dict[str, DetectedPersons]: ...

    def reset(self) -> None: ...


class Fusion(Protocol):
    """Turns one cycle's detections, each sensor's (by name) brought into the tracking frame, into one batch that
    keeps which detections each of its rows came from (``DetectedPersons.originals``)."""

    def fuse(self, batches: dict[str, DetectedPersons]) -> DetectedPersons: ...

    def reset(self) -> None: ...


class Tracker(Protocol):
    """Turns each cycle's fused detections into tracks."""

    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons: ...

    def reset(self) -> None: ...


class GroupStage(Protocol):
    """Turns each cycle's tracks into the relations between them and the groups they form."""

    def update(self, stamp: float, tracks: TrackedPersons) -> tuple[SocialRelations, TrackedGroups]: ...

    def reset(self) -> None: ...


DETECTORS: dict[str, type] = {"laser_segments": SegmentDetector, "laser_learned": LearnedSegmentDetector,
                              "laser_legs": LegDetector, "wall_people": WallCameraDetector,
                              "rgbd_people": RgbdPeopleDetector}
FUSIONS: dict[str, type] = {"nearest": NearestFusion}
TRACKERS: dict[str, type] = {"nnt": NearestNeighbourTracker, "mht": MultiHypothesisTracker,
                             "rjmcmc": RjmcmcTracker, "rgbd": RgbdTracker}
GROUP_STAGES: dict[str, type] = {"coherent_motion": CoherentMotionGroups}


@dataclass
class Pipeline:
    """The parts, made once: ``detectors`` by the name of the sensor each reads; ``map_filter`` (None: none) drops
    their detections on the static map before fusion."""

    detectors: dict[str, Detector]
    fusion: Fusion
    tracker: Tracker
    groups: GroupStage
    map_filter: MapFilter | None = None

    def reset(self) -> None:
        """Every part starts over (ids, tracks, counters), as for a new run."""
        for part in (*self.detectors.values(), self.fusion, self.tracker, self.groups):
            part.reset()


def build_part(spec: dict, registry: dict[str, type], source: str = "<pipeline>", key: str = "pipeline"):
    """The part ``spec`` names (``type`` and the parameters), made from its built-in type or a user's class; a
    parameter the part refuses (a model file that is not there, say) is a ScenarioError of ``source`` at ``key``."""
    params = {name: value for name, value in spec.items() if name != "type"}
    cls = registry[spec["type"]] if spec["type"] in registry else import_class(spec["type"])
    try:
        return cls(**params)
    except ScenarioError:
        raise
    except ValueError as e:
        raise ScenarioError(source, key, str(e)) from None


def build_pipeline(spec: dict, lasers: Sequence[str], floor_plan: dict | None = None,
                   source: str = "<pipeline>") -> Pipeline:
    """The parts of a validated ``pipeline`` section of the scenario ``source``: ``detector`` on each of ``lasers``
    (sensor names), and each sensor that ``detectors`` names gets its own detector in its place (None: none); the
    map filter, when the section has one, on ``floor_plan`` (the scenario's ``map``: the map the robot localises in;
    None: no filter)."""
    own = spec["detectors"]

    def detector(name):
        key = f"pipeline.detectors.{name}" if name in own else "pipeline.detector"
        return build_part(own.get(name, spec["detector"]), DETECTORS, source, key)

    detectors = {name: detector(name) for name in [*lasers, *(n for n in own if n not in lasers)]
                 if own.get(name, spec["detector"]) is not None}
    map_filter = None
    if spec["map_filter"] is not None and floor_plan is not None:
        params = dict(spec["map_filter"])
        obstacles = floor_plan["obstacles"] if params.pop("obstacles", True) else []
        map_filter = MapFilter(floor_plan["walls"], obstacles, **params)
    return Pipeline(detectors, build_part(spec["fusion"], FUSIONS, source, "pipeline.fusion"),
                    build_part(spec["tracker"], TRACKERS, source, "pipeline.tracker"),
                    build_part(spec["groups"], GROUP_STAGES, source, "pipeline.groups"), map_filter)
