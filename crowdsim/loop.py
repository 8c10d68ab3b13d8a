"""The one place that wires a scenario, the crowd, the robot, the sensors, the pipeline and the evaluation together.

``Simulation.frames`` yields one ``Frame`` per tracking cycle; whoever consumes it (the run command, a test, a
dataset writer) decides what to keep. ``Simulation.step(command)`` advances one tick, the robot driven by the
scenario's driver (``robot.driver``: its route; a planner to its goals; a planner following a person) or by a
caller's (v, omega) (a gym environment, a planner of one's own).

The goals and follow drivers run the robot's navigation (pipeline/navigation) at every tracking cycle on what the
robot has: its odometry pose and last executed (v, omega), the laser returns and the tracks in odom, the goal brought
into odom through the robot's localisation in the map (the true world_T_odom, as the route driver steers by), and
for following the tag reading; the command is held until the next cycle. The loop records, every tick, whether the
robot's disc overlaps a person's or a wall (``Simulation.collision_ticks``), and whether the last goal is reached
(``Simulation.finished``: ``frames`` ends there). The pipeline's parts are the scenario's
(``pipeline.assemble``); the loop only calls them. Every random draw comes from streams spawned from the scenario
seed, one per component, so adding a sensor does not change the crowd.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from evaluation import ClearMot, FrameResult
from evaluation.occlusion import seed000_visible
from pipeline.assemble import build_pipeline
from pipeline.fusion import to_frame
from pipeline.frames import inverse, transform_points
from pipeline.navigation.follow import PersonFollower
from pipeline.navigation.planners import build_planner
from pipeline.types import (CameraFrame, DepthFrame, DetectedPersons, GroundTruthTags, LaserScan, SocialRelations,
                            TagReading, TrackedGroups, TrackedPersons, Visibility)
from scenarios.geometry import closest_on_segments, wall_segments
from sensors import Laser, Scene, parts_at
from sensors.body import body_scale
from sensors.laser import LaserArray
from sensors.camera import DepthCamera, WallCamera, camera_pose
from sensors.scene import PARTS
from sensors.tag import TagSensor

from .crowd import AgentStates, Crowd
from .robot import Robot

TRACKING_FRAME = "odom"
# the ground truth reaches this far beyond the evaluation's range, ignored there (neither missed nor, when a track
# matches them, a false positive): a track of a person just beyond the limit is no false positive
GT_MARGIN = 2.0  # m


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
    score: FrameResult
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


class Simulation:
    def __init__(self, scenario: dict):
        self.scenario = scenario
        self.walls = wall_segments(scenario)
        sensors = scenario["sensors"]
        radius, capacity = scenario["robot"]["radius"], scenario["crowd"]["max_agents"]
        # the lasers' scene holds only the body parts at their heights (a ray cast costs per geom of the model);
        # cameras, which see whole people, get a scene of their own
        seen = set().union(*(parts_at(laser["height"]) for laser in sensors["lasers"]))
        self.scene = Scene(self.walls, radius, capacity, seen)
        self.camera_scene = (Scene(self.walls, radius, capacity, PARTS, sensors["depth_cameras"],
                                   sensors["wall_cameras"])
                             if sensors["depth_cameras"] or sensors["wall_cameras"] else None)
        # cameras hold GL contexts: made once, kept across resets (their noise streams are reset)
        self.depth_cameras = [DepthCamera(p, self.camera_scene, np.random.default_rng(0))
                              for p in sensors["depth_cameras"]]
        self.wall_cameras = [WallCamera(p, self.camera_scene) for p in sensors["wall_cameras"]]
        self.max_range = scenario["evaluation"]["max_range"]
        self.dt = scenario["dt"]
        # the parts are made once (a user's may be costly to make) and start over at every reset
        self.pipeline = build_pipeline(scenario["pipeline"], [laser["name"] for laser in sensors["lasers"]],
                                       scenario["map"], scenario.get("source", "<scenario>"))
        robot = scenario["robot"]
        self.driver = robot["driver"]
        self.goals = np.asarray(robot["goals"] or np.zeros((0, 2)), float).reshape(-1, 2)
        self.planner = (build_planner(robot["planner"], robot, scenario.get("source", "<scenario>"))
                        if self.driver in ("goals", "follow") else None)
        self.follower = (PersonFollower(self.planner, tuple(robot["follow"]["band"])) if self.driver == "follow"
                         else None)
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start over (the scenario's seed unless ``seed`` is given): a new crowd with ids from 1, a robot at its
        start, the pipeline's parts and the scores started over. The MuJoCo scene is kept; nothing else carries
        over."""
        scenario = self.scenario
        self.seed = scenario["seed"] if seed is None else int(seed)
        n_lasers = len(scenario["sensors"]["lasers"])
        # the tag reader's stream comes last: the others are what they were before it existed
        streams = np.random.SeedSequence(self.seed).spawn(3 + n_lasers + len(self.depth_cameras) + 1)
        rngs = [np.random.default_rng(s) for s in streams]
        for k, camera in enumerate(self.depth_cameras):
            camera.rng = rngs[3 + n_lasers + k]
        self.crowd = Crowd(scenario, rngs[0])
        self.robot = Robot(scenario["robot"], rngs[1])
        self.lasers = [Laser(p, self.scene, rngs[3 + k]) for k, p in enumerate(scenario["sensors"]["lasers"])]
        self.laser_array = LaserArray(self.lasers, self.scene)  # all lasers due at a tick in one ray call
        self._lasers_by_name = {laser.name: laser for laser in self.lasers}
        self.pipeline.reset()
        self.clearmot = ClearMot(scenario["evaluation"]["threshold"])
        self.timing = Timing()
        self._next_scan = np.zeros(len(self.lasers))
        self._next_depth = np.zeros(len(self.depth_cameras))
        self._next_wall = np.zeros(len(self.wall_cameras))
        self._pending_depth: list[DepthFrame] = []
        self._pending_camera: list[CameraFrame] = []
        # sensor -> (stamp, ids, amount, in view) of its latest frame: beams per person for a laser, visible share
        # for a camera, for every person alive then
        self._latest_seen: dict[str, tuple[float, np.ndarray, np.ndarray, np.ndarray]] = {}
        self._latest_scan: dict[str, LaserScan] = {}
        # sensor -> its latest detections since the last tracking cycle, in the tracking frame
        self._pending: dict[str, DetectedPersons] = {}
        self._frame = 0
        # navigation
        if self.planner is not None:
            (self.follower or self.planner).reset()
        self.tag = TagSensor(scenario["sensors"]["tag"], rngs[-1]) if self.driver == "follow" else None
        self.goal_index = 0  # the goal driven to (goals driver)
        self.finished = False  # the last goal reached (goals driver)
        self.target_id = -1  # the followed person's crowd id, once placed
        self._target_placed = False
        self._nav_command = (0.0, 0.0)  # held between tracking cycles
        self.collision_ticks = 0  # ticks the robot's disc overlapped a person's or a wall
        self.first_collision: float | None = None  # the stamp of the first
        self._collided = False  # since the previous Frame

    def warm_up(self) -> None:
        """Crowd-only simulation for the scenario's warm-up, with the robot standing at its start."""
        steps = int(round(self.scenario["warmup"] / self.dt))
        for _ in range(steps):
            self.crowd.step(self.dt, self.robot.pose[:2], self.robot.p["radius"])
        self._next_scan[:] = self.crowd.t
        self._next_depth[:] = self.crowd.t
        self._next_wall[:] = self.crowd.t

    def _front_clearance(self) -> float:
        """Distance to the nearest laser return in the robot's path (a corridor as wide as the robot)."""
        best = np.inf
        for laser in self.lasers:
            scan = self._latest_scan.get(laser.name)
            if scan is None:
                continue
            pts = transform_points(laser.mount, scan.points())
            ahead = (pts[:, 0] > 0) & (np.abs(pts[:, 1]) < self.robot.p["radius"] + 0.1)
            if ahead.any():
                best = min(best, float(pts[ahead, 0].min()) - self.robot.p["radius"])
        return best

    def _groundtruth(self, agents: AgentStates) -> tuple[TrackedPersons, np.ndarray]:
        """Every person within range and a margin beyond (``GT_MARGIN``), and which persons of ``agents`` they
        are (a mask)."""
        near = np.linalg.norm(agents.position - self.robot.pose[:2], axis=1) <= self.max_range + GT_MARGIN
        odom_T_world = inverse(self.robot.world_T_odom)
        pos = transform_points(odom_T_world, agents.position[near])
        c, s = np.cos(odom_T_world[2]), np.sin(odom_T_world[2])
        vel = agents.velocity[near] @ np.array([[c, s], [-s, c]])
        n = int(near.sum())
        zeros = np.zeros((n, 2, 2))
        return TrackedPersons(agents.stamp, TRACKING_FRAME, agents.id[near], np.ones(n, bool), np.zeros(n, bool),
                              np.full(n, -1, np.int64), pos, vel, zeros, zeros.copy(), np.zeros(n),
                              agents.group_id[near]), near

    def _tags(self, agents: AgentStates, near: np.ndarray, scans: list[LaserScan],
              visibility: Visibility) -> GroundTruthTags:
        """Range, laser beams and occlusion of the ground-truth persons (``near`` of ``agents``). With a depth camera
        starting the cycles, the visible are those it shows at least half of (KTP's labelling rule, seed 003 Sec. 2)."""
        xy = agents.position[near]
        distance = np.linalg.norm(xy - self.robot.pose[:2], axis=1)
        lasers = [k for k, name in enumerate(visibility.sensors) if name in {scan.frame for scan in scans}]
        beams = visibility.amount[near][:, lasers].sum(axis=1).astype(np.int64) if lasers else np.zeros(len(xy), int)
        seed000 = np.zeros(len(xy), bool)
        for scan in scans:
            pose = self._lasers_by_name[scan.frame].pose_in(self.robot.pose)
            points = scan.points()
            seed000 |= seed000_visible(xy, pose[:2], transform_points(pose, points[np.isfinite(points[:, 0])]))
        cycle = self.scenario["pipeline"]["cycle"]
        visible = beams > 0 if cycle == "lasers" else visibility.of(cycle)[near] >= 0.5
        return GroundTruthTags(distance, distance <= self.max_range, beams, visible, seed000)

    def step(self, command: tuple[float, float] | None = None) -> Frame | None:
        """Advance one tick; return a Frame when a tracking cycle ran in it.

        ``command``, (v, omega) in m/s and rad/s, drives the robot this tick in place of the scenario's route driver
        (None: the driver); the robot's speed and acceleration limits apply to it as to the driver's. The safety
        stop (halting for a laser return in front) belongs to the route driver: a caller's command is the caller's
        responsibility, and nothing stops it.
        """
        t0 = time.perf_counter()
        if command is not None:
            v, omega = _command(command)
        elif self.driver == "route":
            v, omega = self.robot.drive_command(self._front_clearance())
        elif self.driver == "script":
            v, omega = self.robot.script_command()
        else:
            v, omega = self._nav_command
        if self.driver == "follow" and not self._target_placed:
            self._place_target()
        self.crowd.step(self.dt, self.robot.pose[:2], self.robot.p["radius"])
        self.robot.step(v, omega, self.dt)
        self._check_collision()
        t1 = time.perf_counter()
        self.timing.crowd_s += t1 - t0
        stamp = self.crowd.t
        due = [k for k in range(len(self.lasers)) if self._next_scan[k] <= stamp + 1e-9]
        depth_due = [k for k in range(len(self.depth_cameras)) if self._next_depth[k] <= stamp + 1e-9]
        wall_due = [k for k in range(len(self.wall_cameras)) if self._next_wall[k] <= stamp + 1e-9]
        if not (due or depth_due or wall_due):
            self.timing.wall_s += t1 - t0
            return None
        agents = self.crowd.states()
        person = (agents.id, agents.position, agents.velocity, agents.walked, body_scale(agents.id, agents.radius))
        if due:
            self.scene.sync(self.robot.pose, *person)
        if depth_due or wall_due:
            self.camera_scene.sync(self.robot.pose, *person)
        self._capture_images(stamp, depth_due, wall_due, agents)
        scans = self.laser_array.scan(stamp, self.robot.pose, due) if due else []
        for k, scan in zip(due, scans):
            self._next_scan[k] += self.lasers[k].period
            self._detect(scan)
        for k, scan in zip(due, scans):
            self._latest_scan[scan.frame] = scan
            hit = np.searchsorted(agents.id, scan.person_id[scan.person_id >= 0])
            beams = np.bincount(hit, minlength=len(agents.id)).astype(float)
            self._latest_seen[scan.frame] = (stamp, agents.id, beams, self._laser_view(self.lasers[k], agents))
        cycle = self.scenario["pipeline"]["cycle"]
        if not (due if cycle == "lasers" else [k for k in depth_due if self.depth_cameras[k].name == cycle]):
            self.timing.sensors_s += time.perf_counter() - t1
            self.timing.wall_s += time.perf_counter() - t0
            return None
        t2 = time.perf_counter()
        self.timing.sensors_s += t2 - t1
        outputs, self._pending = self._pending, {}
        detections = (self.pipeline.fusion.fuse(outputs) if outputs  # no detector ran since the last cycle: none
                      else DetectedPersons.empty(stamp, TRACKING_FRAME, "none"))
        t3 = time.perf_counter()
        if (self._pending_camera or self._pending_depth) and hasattr(self.pipeline.tracker, "see"):
            self.pipeline.tracker.see(self._pending_camera + self._pending_depth)  # a tracker that weighs colour
        tracks = self.pipeline.tracker.update(stamp, detections)
        self.timing.tracker_s += time.perf_counter() - t3
        self.timing.tracker_cycles += 1
        t4 = time.perf_counter()
        relations, groups = self.pipeline.groups.update(stamp, tracks)
        self.timing.groups_s += time.perf_counter() - t4
        gt, near = self._groundtruth(agents)
        visibility = self._visibility(agents)
        tags = self._tags(agents, near, scans, visibility)
        score = self.clearmot.update(gt.track_id, gt.position, tracks.track_id, tracks.position, tags.ignore)
        frame = Frame(self._frame, stamp, self.robot.pose.copy(), self.robot.world_T_odom, agents, scans,
                      detections, tracks, relations, groups, gt, tags, score, visibility, self._pending_depth,
                      self._pending_camera, collision=self._collided, detector_outputs=outputs)
        if self.planner is not None:
            self._navigate(frame)
        self._pending_depth, self._pending_camera, self._collided = [], [], False
        self._frame += 1
        self.timing.wall_s += time.perf_counter() - t0
        return frame

    def _place_target(self) -> None:
        """The person to follow joins the crowd at its start, on its route, at its speed (when recording starts)."""
        target = self.scenario["robot"]["follow"]["target"]
        self.target_id = int(self.crowd.add_walkers(np.array([target["start"]], float), target["route"],
                                                    target["speed"], agent_type=target["agent_type"])[0])
        self._target_placed = True

    def _check_collision(self) -> None:
        """Whether the robot's disc overlaps a person's or a wall now (the navigation metrics' collision test)."""
        xy, radius = self.robot.pose[:2], self.robot.p["radius"]
        gap = np.inf
        if len(self.crowd.pos):
            gap = float((np.hypot(*(self.crowd.pos - xy).T) - self.crowd.radius).min()) - radius
        if len(self.walls):
            gap = min(gap, float(closest_on_segments(xy[None], self.walls)[1].min()) - radius)
        if gap < 0:
            self.collision_ticks += 1
            self._collided = True
            if self.first_collision is None:
                self.first_collision = self.crowd.t

    def _navigate(self, frame: Frame) -> None:
        """The goals or follow driver at a tracking cycle: the command held until the next, from what the robot has
        (odometry pose and velocity, laser returns and tracks in odom, the goal through the localisation, the tag);
        what it decided goes into ``frame``."""
        robot = self.robot
        obstacles = [transform_points(self._lasers_by_name[name].pose_in(robot.odom_pose), scan.points())
                     for name, scan in self._latest_scan.items()]
        obstacles = np.concatenate(obstacles) if obstacles else np.zeros((0, 2))
        if self.driver == "goals":
            radius = self.scenario["robot"]["goal_radius"]
            while (self.goal_index < len(self.goals)
                   and np.hypot(*(self.goals[self.goal_index] - robot.pose[:2])) <= radius):
                self.goal_index += 1
            if self.goal_index >= len(self.goals):
                self.finished = True
                self._nav_command = (0.0, 0.0)
                return
            goal = self.goals[self.goal_index]
            frame.goal = goal.copy()
            in_odom = transform_points(inverse(robot.world_T_odom), goal[None])[0]
            command = self.planner.command(frame.stamp, robot.odom_pose.copy(), robot.velocity.copy(), obstacles,
                                           frame.tracks, in_odom)
        else:
            agents = frame.agents
            row = np.searchsorted(agents.id, self.target_id)
            alive = row < len(agents.id) and agents.id[row] == self.target_id
            frame.target_id = self.target_id if alive else -1
            frame.tag = self.tag.read(frame.stamp, robot.pose, agents.position[row] if alive else None)
            command = self.follower.command(frame.stamp, robot.odom_pose.copy(), robot.velocity.copy(), obstacles,
                                            frame.tracks, frame.tag)
            frame.target_track = int(self.follower.target_track)
            if alive:  # a robot's own sensor (a laser, a depth camera) saw the person in its latest frame
                v = frame.visibility
                own = [k for k, name in enumerate(v.sensors) if name not in {c.name for c in self.wall_cameras}]
                frame.target_visible = bool((v.amount[row, own] > 0).any())
        self._nav_command = (float(command[0]), float(command[1]))

    def _detect(self, data: LaserScan | DepthFrame | CameraFrame) -> None:
        """The sensor's detector, if it has one, on a frame the sensor made: its detections, brought into the
        tracking frame and, with a map filter, rid of those on the map (placed there through the localisation, as
        the cameras are), wait for the next tracking cycle (a sensor's latest replace its earlier ones). A detector
        that gives several named batches (a camera's foreground blobs and HOG windows) has each wait as
        ``sensor/name``."""
        detector = self.pipeline.detectors.get(data.frame)
        if detector is None:
            return
        laser = self._lasers_by_name.get(data.frame)
        pose = laser.pose_in(self.robot.odom_pose) if laser is not None else self._camera_in_odom(data.frame)
        found = detector.detect(data)
        named = found.items() if isinstance(found, dict) else ((None, found),)
        for name, batch in named:
            detections = to_frame(batch, pose, TRACKING_FRAME)
            if self.pipeline.map_filter is not None:
                detections = self.pipeline.map_filter.filter(detections, self.robot.world_T_odom)
            self._pending[data.frame if name is None else f"{data.frame}/{name}"] = detections

    def _camera_in_odom(self, name: str) -> np.ndarray:
        """The camera's optical frame in odom (a 4x4 transform), placed through the robot's localisation in the map
        (the true world_T_odom, as the route driver steers by): for a camera on the robot, its mount on the odometry
        pose."""
        origin, rot = camera_pose(self.camera_scene, name)
        x, y, yaw = inverse(self.robot.world_T_odom)
        c, s = np.cos(yaw), np.sin(yaw)
        odom_R_world = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        pose = np.eye(4)
        pose[:3, :3] = odom_R_world @ rot
        pose[:3, 3] = odom_R_world @ origin + [x, y, 0.0]
        return pose

    def _capture_images(self, stamp: float, depth_due: list[int], wall_due: list[int], agents: AgentStates) -> None:
        for k in depth_due:
            camera = self.depth_cameras[k]
            self._next_depth[k] += camera.period
            image = camera.capture(stamp)
            image.pose = self._camera_in_odom(image.frame)
            self._detect(image)
            self._pending_depth.append(image)
            camera.visibility(image)
            self._latest_seen[image.frame] = (stamp, agents.id, _on(agents.id, image.ids, image.visible_fraction),
                                              self._camera_view(camera, agents))
        for k in wall_due:
            camera = self.wall_cameras[k]
            self._next_wall[k] += camera.period
            image = camera.capture(stamp)
            image.pose = self._camera_in_odom(image.frame)
            image.robot_position = self.robot.odom_pose[:2].copy()
            self._detect(image)
            self._pending_camera.append(image)
            self._latest_seen[image.frame] = (stamp, agents.id, _on(agents.id, image.ids, image.visible_fraction),
                                              self._camera_view(camera, agents))

    def _visibility(self, agents: AgentStates) -> Visibility:
        """Per person alive and sensor: what the sensor's latest frame saw of them and whether they were in its view
        then (NaN and False before its first frame, and for persons who came after it)."""
        n = len(agents.id)
        names = [laser.name for laser in self.lasers] + [c.name for c in self.depth_cameras + self.wall_cameras]
        stamps = np.full(len(names), np.nan)
        amount = np.full((n, len(names)), np.nan)
        in_view = np.zeros((n, len(names)), bool)
        for k, name in enumerate(names):
            if name in self._latest_seen:
                stamps[k], ids, seen, view = self._latest_seen[name]
                amount[:, k] = _on(agents.id, ids, seen, np.nan)
                in_view[:, k] = _on(agents.id, ids, view, False)
        return Visibility(agents.id.copy(), names, stamps, amount, in_view)

    def _laser_view(self, laser: Laser, agents: AgentStates) -> np.ndarray:
        """Who is within the laser's field of view and range."""
        pose = laser.pose_in(self.robot.pose)
        rel = agents.position - pose[:2]
        bearing = np.arctan2(rel[:, 1], rel[:, 0]) - pose[2]
        return (np.linalg.norm(rel, axis=1) <= laser.p["range_max"]) & (
            np.abs(np.arctan2(np.sin(bearing), np.cos(bearing))) <= np.radians(laser.p["fov_deg"]) / 2)

    def _camera_view(self, camera: DepthCamera | WallCamera, agents: AgentStates) -> np.ndarray:
        """Who has the middle of their body (1 m up) in the camera's image, within its range."""
        n = len(agents.id)
        origin, rot = camera_pose(self.camera_scene, camera.name)
        cam = (np.column_stack([agents.position, np.full(n, 1.0)]) - origin) @ rot
        ahead = (cam[:, 2] > 0.05) & (cam[:, 2] <= camera.p.get("range_max", np.inf))
        size = camera.intrinsics
        uv = size.project(np.where(ahead[:, None], cam, [0.0, 0.0, 1.0]))
        return ahead & (uv >= 0).all(axis=1) & (uv[:, 0] < size.width) & (uv[:, 1] < size.height)

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


def _command(command) -> tuple[float, float]:
    """A caller's (v, omega) as two floats; ValueError unless it is two finite numbers."""
    try:
        values = np.asarray(command)
    except ValueError:  # a ragged sequence
        values = np.zeros(0)
    if values.shape != (2,) or values.dtype.kind not in "iuf" or not np.isfinite(values).all():
        raise ValueError(f"command: expected (v, omega), two finite numbers in m/s and rad/s, got {command!r}")
    return float(values[0]), float(values[1])


def _on(agent_ids: np.ndarray, ids: np.ndarray, values: np.ndarray, missing=0.0) -> np.ndarray:
    """``values`` of persons ``ids`` laid out over ``agent_ids`` (sorted); ``missing`` for those not among them."""
    out = np.full(len(agent_ids), missing, np.result_type(missing, np.asarray(values)))
    rows = np.searchsorted(agent_ids, ids)
    keep = rows < len(agent_ids)  # and, below, the person found there (nobody is found among no one)
    keep[keep] = agent_ids[rows[keep]] == ids[keep]
    out[rows[keep]] = np.asarray(values)[keep]
    return out
