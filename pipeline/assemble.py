"""The pipeline as parts: the interfaces of detectors, fusion, trackers and the group stage, the built-in types by
name, and ``build_pipeline``, which makes the parts a scenario's (validated) ``pipeline`` section names.

A part is named by its type, a built-in one below or ``module.path:ClassName``, and made as ``cls(**params)`` with
the section's other keys; every part starts over with ``reset()``. The built-in detectors, fusions and group stages
are their packages' (``pipeline.detectors.DETECTORS``, ``pipeline.fusion.FUSIONS``, ``pipeline.groups.GROUP_STAGES``),
each declaring its parameters on its class, where the scenario format (scenarios/format.py) reads them.
"""

from __future__ import annotations

import math
import traceback
from dataclasses import dataclass
from typing import Protocol, Sequence

from scenarios.schema import ScenarioError, import_class
from scenarios.typed import plain

from .detectors import DETECTORS
from .fusion import FUSIONS
from .groups import GROUP_STAGES
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


TRACKERS: dict[str, type] = {"nnt": NearestNeighbourTracker, "mht": MultiHypothesisTracker,
                             "rjmcmc": RjmcmcTracker, "rgbd": RgbdTracker}


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


def _detections(out) -> bool:
    return isinstance(out, DetectedPersons) or (isinstance(out, dict) and bool(out) and all(
        isinstance(k, str) and isinstance(v, DetectedPersons) for k, v in out.items()))


def _command(out) -> bool:
    try:
        return len(out) == 2 and all(math.isfinite(float(c)) for c in out)
    except (TypeError, ValueError, OverflowError):
        return False


# what each role's method must return: (method, test, what to say was expected)
RETURNS = {
    "detector": ("detect", _detections,
                 "DetectedPersons, or a dict of named DetectedPersons batches (pipeline.types)"),
    "fusion": ("fuse", lambda out: isinstance(out, DetectedPersons), "DetectedPersons (pipeline.types)"),
    "tracker": ("update", lambda out: isinstance(out, TrackedPersons), "TrackedPersons (pipeline.types)"),
    "groups": ("update", lambda out: isinstance(out, tuple) and len(out) == 2 and isinstance(out[0], SocialRelations)
               and isinstance(out[1], TrackedGroups), "a tuple (SocialRelations, TrackedGroups) (pipeline.types)"),
    "planner": ("command", lambda out: _command(out), "(v, omega), two finite numbers in m/s and rad/s"),
}


def user_failure(e: Exception, what: str, source: str, key: str) -> ScenarioError:
    """A user's part that raised ``e``, as one error naming the part, the exception and the line of the user's code
    it came from."""
    frames = traceback.extract_tb(e.__traceback__)
    where = f" at {frames[-1].filename}:{frames[-1].lineno}" if frames else ""
    return ScenarioError(source, key, f"{what} {type(e).__name__}: {e}{where}; expected the part to run without "
                                      "an exception")


def check_outputs(part, role: str, source: str, key: str):
    """``part`` (a user's) with its role's method checked: a wrong return type is one ScenarioError naming the
    part's key and what was expected, not an AttributeError deep in the next part. The check is laid on the instance,
    so the part keeps its own class."""
    method, test, expected = RETURNS[role]
    call = getattr(part, method)
    name = f"{type(part).__module__}:{type(part).__qualname__}.{method}"

    def checked(*args, **kwargs):
        try:
            out = call(*args, **kwargs)
        except ScenarioError:
            raise
        except Exception as e:  # the user's code failed: one error naming the part and where, not our traceback
            raise user_failure(e, f"{name} raised", source, f"{key}.type") from None
        if not test(out):
            raise ScenarioError(source, f"{key}.type", f"{name} returned {type(out).__name__}; expected {expected}")
        return out

    try:
        setattr(part, method, checked)
    except AttributeError:  # a class with __slots__: left as it is
        pass
    return part


def make_user_part(path: str, params: dict, source: str, key: str):
    """A user's class ``module.path:ClassName`` made as ``Class(**params)``; whatever its constructor raises is one
    error naming the key."""
    try:
        return import_class(path)(**params)
    except ScenarioError:
        raise
    except Exception as e:
        raise user_failure(e, f"{path}(...) raised", source, f"{key}.type") from None


def build_part(spec: dict, registry: dict[str, type], source: str = "<pipeline>", key: str = "pipeline"):
    """The part ``spec`` names (``type`` and the parameters), made from its built-in type or a user's class (its
    outputs checked, ``check_outputs``); a parameter the part refuses (a model file that is not there, say) is a
    ScenarioError of ``source`` at ``key``. ``spec`` may be a loaded scenario's section or its plain data."""
    spec = plain(spec)
    params = {name: value for name, value in spec.items() if name != "type"}
    if spec["type"] in registry:
        try:
            return registry[spec["type"]](**params)
        except ScenarioError:
            raise
        except ValueError as e:  # a parameter the part refuses (a model file that is not there, say)
            raise ScenarioError(source, key, str(e)) from None
    part = make_user_part(spec["type"], params, source, key)
    role = next(role for role, known in (("detector", DETECTORS), ("fusion", FUSIONS), ("tracker", TRACKERS),
                                         ("groups", GROUP_STAGES)) if known is registry)
    return check_outputs(part, role, source, key)


def build_pipeline(spec: dict, lasers: Sequence[str], floor_plan: dict | None = None,
                   source: str = "<pipeline>") -> Pipeline:
    """The parts of a validated ``pipeline`` section of the scenario ``source``: ``detector`` on each of ``lasers``
    (sensor names), and each sensor that ``detectors`` names gets its own detector in its place (None: none); the
    map filter, when the section has one, on ``floor_plan`` (the scenario's ``map``: the map the robot localises in;
    None: no filter). Both may be a loaded scenario's sections or the plain data of one."""
    spec, floor_plan = plain(spec), plain(floor_plan)
    own = spec["detectors"]

    def detector(name):
        key = f"pipeline.detectors.{name}" if name in own else "pipeline.detector"
        return build_part(own.get(name, spec["detector"]), DETECTORS, source, key)

    detectors = {name: detector(name) for name in [*lasers, *(n for n in own if n not in lasers)]
                 if own.get(name, spec["detector"]) is not None}
    map_filter = None
    if spec["map_filter"] is not None and floor_plan is not None:
        map_filter = MapFilter(floor_plan["walls"], floor_plan["obstacles"], **spec["map_filter"])
    return Pipeline(detectors, build_part(spec["fusion"], FUSIONS, source, "pipeline.fusion"),
                    build_part(spec["tracker"], TRACKERS, source, "pipeline.tracker"),
                    build_part(spec["groups"], GROUP_STAGES, source, "pipeline.groups"), map_filter)
