"""The loop: each tick, the driver's command moves the world; the sensors due capture it; when the cycle's sensor is
due, the robot's software runs on what they made, the driver plans on it, the ground truth labels the world, and one
``Frame`` comes out. Consumers (the run command, a test, a dataset writer, the scorer) decide what to keep.

The parts are the world (crowdsim/world.py), the sensors (sensors/: lasers, depth cameras, wall cameras, the tag
reader, a user's own; sensors/base.py is what they share), the robot's software (pipeline/software.py, built from
the scenario's ``pipeline`` section), the driver (crowdsim/drivers.py) and the ground truth (crowdsim/groundtruth.py).
Every random draw comes from a stream named by the part that draws it (``stream_names``), so adding a sensor does
not change the crowd.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from pipeline.assemble import build_pipeline, make_user_part
from pipeline.software import RobotSoftware
from pipeline.types import (CameraFrame, DepthFrame, DetectedPersons, GroundTruthTags, LaserScan, SocialRelations,
                            TagReading, TrackedGroups, TrackedPersons, Visibility)
from scenarios.errors import Error
from scenarios.typed import Scenario, plain
from sensors import Scene, parts_at
from sensors.base import capture_due
from sensors.camera import DepthCamera, WallCamera
from sensors.laser import Laser, LaserArray
from sensors.scene import PARTS
from sensors.tag import TagSensor

from .crowd import AgentStates
from .drivers import make_driver
from .groundtruth import GroundTruth
from .world import World

__all__ = ["Frame", "Simulation"]


@dataclass
class Frame:
    """Everything that happened at one tracking cycle."""

    index: int
    stamp: float
    robot_pose: np.ndarray  # world
    world_T_odom: np.ndarray  # the true transform, for display and scoring
    agents: AgentStates  # all persons, world frame
    scans: list[LaserScan]
    detections: DetectedPersons  # fused, odom
    tracks: TrackedPersons  # odom
    relations: SocialRelations  # between the tracks
    groups: TrackedGroups  # of the tracks, odom
    groundtruth: TrackedPersons  # persons within range and GT_MARGIN beyond, odom
    gt_tags: GroundTruthTags  # their range, beams and occlusion, for the evaluation
    visibility: Visibility  # who each sensor saw, every person alive
    depth_frames: list[DepthFrame]  # images taken since the previous Frame
    camera_frames: list[CameraFrame]
    # navigation (goals and follow drivers): the goal driven to (world; None once the last is reached, and when
    # following), the followed person's crowd id (-1: none yet or gone), the follower's track of them (-1: none),
    # whether a robot sensor (laser, depth camera) saw them, the tag reading of this cycle (None: none due, or missed),
    # and whether the robot's disc overlapped a person's or a wall at any tick since the previous Frame
    goal: np.ndarray | None = None
    target_id: int = -1
    target_track: int = -1
    target_visible: bool = False
    tag: TagReading | None = None
    collision: bool = False
    # each detector's own output since the previous Frame (sensor -> its detections, odom; after the map filter,
    # when the pipeline has one), before the fusion
    detector_outputs: dict[str, DetectedPersons] = field(default_factory=dict)


@dataclass
class Timing:
    wall_s: float = 0.0
    tracker_s: float = 0.0
    tracker_cycles: int = 0
    groups_s: float = 0.0
    sensors_s: float = 0.0
    crowd_s: float = 0.0


def stream_names(scenario: Scenario) -> list[str]:
    """The random streams, in the order they are spawned from the scenario seed: each part keeps the child stream
    it had when it was added (the third is no longer drawn from; the tag reader came last)."""
    sensors = scenario.sensors
    return ["crowd", "robot", "unused", *(f"laser:{p.name}" for p in sensors.lasers),
            *(f"depth_camera:{p.name}" for p in sensors.depth_cameras), "tag"]


class Simulation:
    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        source = scenario.source
        self.walls = scenario.map.segments
        self.dt = scenario.dt
        sensors = scenario.sensors
        radius, capacity = scenario.robot.radius, scenario.crowd.max_agents
        # the lasers' scene holds only the body parts at their heights (a ray cast costs per geom of the model);
        # cameras, which see whole people, get a scene of their own
        seen = set().union(*(parts_at(laser.height) for laser in sensors.lasers))
        self.scene = Scene(self.walls, radius, capacity, seen)
        self.camera_scene = (Scene(self.walls, radius, capacity, PARTS, plain(sensors.depth_cameras),
                                   plain(sensors.wall_cameras))
                             if sensors.depth_cameras or sensors.wall_cameras else None)
        # cameras hold GL contexts, and a user's parts may be costly to make: made once, started over at each reset
        self.depth_cameras = [DepthCamera(scene=self.camera_scene, rng=np.random.default_rng(0), **p.params)
                              for p in sensors.depth_cameras]
        self.wall_cameras = [WallCamera(scene=self.camera_scene, **p.params) for p in sensors.wall_cameras]
        self.custom_sensors = [_user_sensor(spec, source, k) for k, spec in enumerate(sensors.custom or ())]
        self.software = RobotSoftware(build_pipeline(scenario.pipeline, [p.name for p in sensors.lasers],
                                                     scenario.map, source))
        self.driver = make_driver(scenario.robot, source)
        self.cycle_sensor = scenario.pipeline.cycle
        self.reset()

    @property
    def pipeline(self):
        """The robot software's parts."""
        return self.software.parts

    # the world's, for those who look at it between steps
    robot = property(lambda self: self.world.robot)
    crowd = property(lambda self: self.world.crowd)
    collision_ticks = property(lambda self: self.world.collision_ticks)
    first_collision = property(lambda self: self.world.first_collision)
    target_id = property(lambda self: self.world.tagged_id)
    finished = property(lambda self: self.driver.finished)

    def reset(self, seed: int | None = None) -> None:
        """Start over (the scenario's seed unless ``seed`` is given): a new crowd with ids from 1, a robot at its
        start, the software's parts, the driver and the ground truth started over. The MuJoCo scenes are kept;
        nothing else carries over."""
        scenario = self.scenario
        self.seed = scenario.seed if seed is None else int(seed)
        names = stream_names(scenario)
        rng = dict(zip(names, (np.random.default_rng(s) for s in np.random.SeedSequence(self.seed).spawn(len(names)))))
        follow = scenario.robot.follow.target if scenario.robot.driver == "follow" else None
        self.world = World(scenario, self.walls, rng["crowd"], rng["robot"], follow)
        self.lasers = [Laser(scene=self.scene, rng=rng[f"laser:{p.name}"], **p.params) for p in scenario.sensors.lasers]
        self.laser_array = LaserArray(self.lasers, self.scene)  # the lasers due at a tick: one scene sync
        for camera in self.depth_cameras:
            camera.rng = rng[f"depth_camera:{camera.name}"]
        self.tag = TagSensor(rng=rng["tag"], **scenario.sensors.tag.params) if follow is not None else None
        # the capture order (cameras, then the lasers together) fixes the order in which detections
        # reach the fusion, and with them the fused detections' ids
        self.sensors = [*self.depth_cameras, *self.wall_cameras, *self.lasers, *self.custom_sensors,
                        *([self.tag] if self.tag is not None else [])]
        for sensor in self.sensors:
            sensor.start(self.world.t)
        for sensor in self.custom_sensors:
            if hasattr(sensor, "reset"):
                sensor.reset()
        self.truth = GroundTruth(scenario.evaluation.max_range, self.cycle_sensor,
                                 [*self.lasers, *self.depth_cameras, *self.wall_cameras, *self.custom_sensors],
                                 {laser.name: laser for laser in self.lasers})
        self._own_sensors = [s.name for s in (*self.lasers, *self.depth_cameras, *self.custom_sensors)]
        self.software.reset()
        self.driver.reset()
        self.timing = Timing()
        self._latest_scans: dict[str, tuple[LaserScan, np.ndarray]] = {}  # laser -> its latest scan, its mount
        self._images: list[DepthFrame | CameraFrame] = []  # since the previous Frame
        self._tag: TagReading | None = None  # the latest reading since the previous Frame
        self._collided = False  # since the previous Frame
        self._frame = 0

    def warm_up(self) -> None:
        """Crowd-only simulation for the scenario's warm-up, with the robot standing at its start."""
        self.world.warm_up(self.scenario.warmup)
        for sensor in self.sensors:
            sensor.start(self.world.t)

    def step(self, command: tuple[float, float] | None = None) -> Frame | None:
        """Advance one tick; return a Frame when a tracking cycle ran in it.

        ``command``, (v, omega) in m/s and rad/s, drives the robot this tick in place of the scenario's driver
        (None: the driver); the robot's speed and acceleration limits apply to it as to the driver's. The route
        driver's safety stop (halting for a laser return in front) does not apply to a caller's command: that is the
        caller's responsibility.
        """
        t0 = time.perf_counter()
        scans = list(self._latest_scans.values())
        v, omega = _command(command) if command is not None else self.driver.command(self.world, scans)
        world = self.world
        world.step(v, omega)
        self._collided |= world.collided
        t1 = time.perf_counter()
        self.timing.crowd_s += t1 - t0
        stamp = world.t
        captured = capture_due(self.sensors, world, stamp)
        cycle_now, new_scans = False, []
        for sensor, data in captured:
            if data is None:  # nothing came (a missed tag read)
                continue
            if sensor is self.tag:
                self._tag = data
                continue
            self.truth.saw(world, sensor, data)
            if self.software.detects(sensor.name):
                self.software.receive(data, sensor.pose_in_odom(world), world.robot.world_T_odom)
            if isinstance(data, LaserScan):
                self._latest_scans[sensor.name] = (data, sensor.mount)
                new_scans.append(data)
                cycle_now |= self.cycle_sensor == "lasers"
            elif isinstance(data, (DepthFrame, CameraFrame)):
                self._images.append(data)
                cycle_now |= sensor.name == self.cycle_sensor
        t2 = time.perf_counter()
        self.timing.sensors_s += t2 - t1
        if not cycle_now:
            self.timing.wall_s += t2 - t0
            return None
        frame = self._cycle(stamp, new_scans)
        self.timing.wall_s += time.perf_counter() - t0
        return frame

    def _cycle(self, stamp: float, scans: list[LaserScan]) -> Frame:
        """The robot's software, the driver's plan and the ground truth at a tracking cycle, as one Frame."""
        world = self.world
        images, self._images = self._images, []
        depth = [image for image in images if isinstance(image, DepthFrame)]
        cameras = [image for image in images if isinstance(image, CameraFrame)]
        software = self.software
        before = software.timing.tracker_s, software.timing.groups_s
        perception = software.cycle(stamp, cameras + depth)
        self.timing.tracker_s += software.timing.tracker_s - before[0]
        self.timing.groups_s += software.timing.groups_s - before[1]
        self.timing.tracker_cycles += 1
        visibility = self.truth.visibility(world)
        truth, tags = self.truth.label(world, scans, visibility)
        tag, self._tag = self._tag, None
        decision = self.driver.cycle(world, list(self._latest_scans.values()), perception, tag)
        target_id, target_visible = self.truth.target(world, visibility, self._own_sensors)
        frame = Frame(self._frame, stamp, world.robot.pose.copy(), world.robot.world_T_odom, world.agents(), scans,
                      perception.detections, perception.tracks, perception.relations, perception.groups, truth, tags,
                      visibility, depth, cameras, decision.goal, target_id, decision.target_track, target_visible,
                      decision.tag, self._collided, perception.detector_outputs)
        self._collided = False
        self._frame += 1
        return frame

    def frames(self, duration: float):
        """Yield the Frames of ``duration`` seconds of simulated time (after the warm-up), or until the goals driver
        has reached its last goal (the Frame where it did is the last)."""
        steps = int(round(duration / self.dt))
        for _ in range(steps):
            frame = self.step()
            if frame is not None:
                yield frame
                if self.finished:
                    return


def _user_sensor(spec, source: str, k: int):
    """A user's sensor class ``module.path:ClassName`` (``sensors.custom[k].type``) made with its keys."""
    return make_user_part(spec.type, spec.params, source, f"sensors.custom[{k}]")


def _command(command) -> tuple[float, float]:
    """A caller's (v, omega) as two floats; an Error unless it is two finite numbers."""
    try:
        values = np.asarray(command)
    except ValueError:  # a ragged sequence
        values = np.zeros(0)
    if values.shape != (2,) or values.dtype.kind not in "iuf" or not np.isfinite(values).all():
        raise Error(f"command: expected (v, omega), two finite numbers in m/s and rad/s, got {command!r}")
    return float(values[0]), float(values[1])
