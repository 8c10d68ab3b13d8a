"""The ground truth the evaluation scores against, labelled from the world and what each sensor showed.

Every person within the evaluation's range and ``GT_MARGIN`` beyond (in the tracking frame, with the true
transform), their range, laser beams and visibility tags, and per sensor and person what its latest frame showed.
Only the evaluation, the run's files and the datasets read it: the robot's software never does.
"""

from __future__ import annotations

import numpy as np

from evaluation.occlusion import seed000_visible
from pipeline.frames import inverse, rotate, transform_points
from pipeline.software import TRACKING_FRAME
from pipeline.types import GroundTruthTags, LaserScan, TrackedPersons, Visibility
from sensors.camera import on_persons

# the ground truth reaches this far beyond the evaluation's range, ignored there (neither missed nor, when a track
# matches them, a false positive): a track of a person just beyond the limit is no false positive
GT_MARGIN = 2.0  # m


class GroundTruth:
    """``sensors`` (in the order Visibility lists them) are those whose frames say what persons showed them;
    ``lasers`` by name place seed 000's visibility test; ``cycle`` (``lasers`` or a depth camera's name) is the
    sensor whose view decides who is visible."""

    def __init__(self, max_range: float, cycle: str, sensors: list, lasers: dict):
        self.max_range, self.cycle = max_range, cycle
        self.names = [s.name for s in sensors]
        self.lasers = lasers
        self.reset()

    def reset(self) -> None:
        # sensor -> (stamp, ids, amount, in view) of its latest frame, for every person alive then
        self._latest: dict[str, tuple[float, np.ndarray, np.ndarray, np.ndarray]] = {}

    def saw(self, world, sensor, frame) -> None:
        """Keep what ``frame`` of ``sensor`` showed of each person alive now."""
        shown = sensor.shown(world, frame)
        if shown is not None:
            self._latest[sensor.name] = (world.t, world.agents().id, *shown)

    def visibility(self, world) -> Visibility:
        """Per person alive and sensor: what the sensor's latest frame saw of them and whether they were in its view
        then (NaN and False before its first frame, and for persons who came after it)."""
        agents = world.agents()
        n = len(agents.id)
        stamps = np.full(len(self.names), np.nan)
        amount = np.full((n, len(self.names)), np.nan)
        in_view = np.zeros((n, len(self.names)), bool)
        for k, name in enumerate(self.names):
            if name in self._latest:
                stamps[k], ids, seen, view = self._latest[name]
                amount[:, k] = on_persons(agents.id, ids, seen, np.nan)
                in_view[:, k] = on_persons(agents.id, ids, view, False)
        return Visibility(agents.id.copy(), self.names, stamps, amount, in_view)

    def label(self, world, scans: list[LaserScan], visibility: Visibility) -> tuple[TrackedPersons, GroundTruthTags]:
        """Every person within range and the margin beyond, in the tracking frame, and their tags: range, laser
        beams of ``scans`` (this cycle's) and occlusion. With a depth camera starting the cycles, the visible are
        those it shows at least half of (KTP's labelling rule, seed 003 Sec. 2)."""
        agents, robot = world.agents(), world.robot
        distance = np.linalg.norm(agents.position - robot.pose[:2], axis=1)
        near = np.flatnonzero(distance <= self.max_range + GT_MARGIN)
        distance, xy, n = distance[near], agents.position[near], len(near)
        odom_T_world = inverse(robot.world_T_odom)
        zeros = np.zeros((n, 2, 2))
        truth = TrackedPersons(agents.stamp, TRACKING_FRAME, agents.id[near], np.ones(n, bool), np.zeros(n, bool),
                               np.full(n, -1, np.int64), transform_points(odom_T_world, xy),
                               rotate(odom_T_world, agents.velocity[near]), zeros, zeros.copy(), np.zeros(n),
                               agents.group_id[near])
        frames = {scan.frame for scan in scans}
        lasers = [k for k, name in enumerate(visibility.sensors) if name in frames]
        beams = visibility.amount[near][:, lasers].sum(axis=1).astype(np.int64) if lasers else np.zeros(n, int)
        seed000 = np.zeros(n, bool)
        for scan in scans:
            pose = self.lasers[scan.frame].pose_in(robot.pose)
            points = scan.points()
            seed000 |= seed000_visible(xy, pose[:2], transform_points(pose, points[np.isfinite(points[:, 0])]))
        visible = beams > 0 if self.cycle == "lasers" else visibility.of(self.cycle)[near] >= 0.5
        return truth, GroundTruthTags(distance, distance <= self.max_range, beams, visible, seed000)

    @staticmethod
    def target(world, visibility: Visibility, own_sensors: list[str]) -> tuple[int, bool]:
        """The tagged person's crowd id (-1: none yet, or gone) and whether one of the robot's own sensors (not a
        wall camera) showed them in its latest frame."""
        row = np.searchsorted(visibility.ids, world.tagged_id)
        if world.tagged_id < 0 or row >= len(visibility.ids) or visibility.ids[row] != world.tagged_id:
            return -1, False
        own = [k for k, name in enumerate(visibility.sensors) if name in own_sensors]
        return world.tagged_id, bool((visibility.amount[row, own] > 0).any())
