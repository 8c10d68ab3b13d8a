"""2D laser scanners ray-cast with MuJoCo: one ``mj_multiRay`` call (every beam at once) per scan, and the range error of the
datasheets: a bias fixed per laser (the systematic error: a calibration offset, the same on every beam, so a flat wall
stays flat) plus Gaussian noise per return (the statistical error), both by range band (see
scenarios/laser_presets.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel
from pipeline.frames import compose
from pipeline.params import REQUIRED, param
from pipeline.types import LaserScan

from .base import Periodic
from .scene import Scene

# the SICK LMS 500's range error, the default laser's (scenarios/laser_presets.py's sick_lms500 gives its source)
SICK_LMS500_NOISE = [{"up_to": 10.0, "systematic": 0.025, "statistical": 0.007},
                     {"up_to": 20.0, "systematic": 0.035, "statistical": 0.009}]


def beam_count(fov_deg: float, resolution_deg: float) -> float:
    """A scan's beams: one per step of the resolution over the field of view, and one at its end unless it is a
    full circle (whose last beam would repeat the first); inf where the resolution is too fine to count them."""
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        ratio = np.radians(fov_deg) / np.radians(resolution_deg)
    if not math.isfinite(ratio):
        return math.inf
    return int(round(ratio)) + (0 if fov_deg >= 360.0 else 1)


def _two_beams(p: dict):
    beams = beam_count(p["fov_deg"], p["resolution_deg"])
    if beams < 2:
        return "resolution_deg", (f"{p['resolution_deg']:g} deg over fov_deg {p['fov_deg']:g} gives {beams:.0f} beam; "
                                  "expected at least 2 beams (a finer resolution or a wider field of view)")


@dataclass(kw_only=True, eq=False)
class NoiseBand:
    """One range band of a laser's error (its ``noise``, nearest band first)."""

    up_to: float = param(REQUIRED, "m, the band covers ranges up to this", kind="float", min=0.0, exclusive_min=True)
    systematic: float = param(0.0, "m, +- bound of the laser's offset (drawn uniformly once per laser, the same on "
                                   "every beam)", min=0.0)
    statistical: float = param(0.0, "m, 1-sigma Gaussian noise drawn anew for every return", min=0.0)


@dataclass(kw_only=True, eq=False)
class Laser(Periodic):
    """A planar laser mounted on the robot (``mount`` is its pose in base_link, ``height`` above the floor); a
    ``Sensor`` (sensors/base.py) whose ``batch``, when a ``LaserArray`` holds it, casts it with the others. Made as
    ``Laser(scene=..., rng=..., **params)``; the scenario format fills the values of a ``preset`` in (in Python, pass
    them: ``preset`` only names the model)."""

    name: str = param(REQUIRED, "the laser's frame name", kind="str")
    preset: str | None = param(None, "a datasheet model whose values fill the keys not given "
                                     "(scenarios/laser_presets.py)", kind="str")
    mount: np.ndarray = param(REQUIRED, "m, m, rad: pose in base_link", kind="pose")
    height: float = param(0.70, "m above the floor (seed 000: two lasers at 70 cm)", min=0.0)
    fov_deg: float = param(190.0, "deg (SICK LMS500)", min=0.0, exclusive_min=True, max=360.0)
    resolution_deg: float = param(0.5, "deg between beams (SICK LMS500)", min=0.0, exclusive_min=True)
    range_min: float = param(0.0, "m, nearer returns are no-returns", min=0.0)
    range_max: float = param(20.0, "m (seed 000: detections up to 20 m)", min=0.0, exclusive_min=True)
    rate: float = param(25.0, "Hz (SICK LMS500: 25 or 50 Hz), at most the simulation's steps per second (1 / dt)",
                        min=0.0, exclusive_min=True)
    noise: list = param(SICK_LMS500_NOISE, "range error bands, nearest first; beyond the last, the last applies "
                                           "(SICK LMS5xx HR)", item=NoiseBand)
    no_return: str = param("nan", "what a beam without a return reads: NaN, or range_max as many drivers report",
                           choices=("nan", "range_max"))
    scene: Scene
    rng: np.random.Generator

    CHECKS = (_two_beams,)
    batch = None

    def __post_init__(self):
        self.mount = np.array(self.mount, float)
        fov = np.radians(self.fov_deg)
        full_circle = self.fov_deg >= 360.0
        self.n_beams = beam_count(self.fov_deg, self.resolution_deg)
        self.angle_min = -fov / 2
        self.angle_increment = fov / (self.n_beams if full_circle else self.n_beams - 1)
        self.angles = self.angle_min + self.angle_increment * np.arange(self.n_beams)
        self.period = 1.0 / self.rate
        bands = [NoiseBand(**b) for b in self.noise]
        self._band_edges = np.array([b.up_to for b in bands[:-1]])
        self._systematic = np.array([b.systematic for b in bands] or [0.0])
        self._statistical = np.array([b.statistical for b in bands] or [0.0])
        # where this laser's offset lies within +- the systematic bound: drawn once, the same for every beam and scan
        self._bias_share = float(self.rng.uniform(-1.0, 1.0))
        self._vec = np.zeros((self.n_beams, 3))
        self._dist = np.zeros(self.n_beams)
        self._geom = np.zeros(self.n_beams, np.int32)
        self._groups = self.scene.groups_at(self.height)  # only the body parts at the laser's height

    def pose_in(self, base_pose: np.ndarray) -> np.ndarray:
        """The laser's pose in the frame ``base_pose`` is given in."""
        return compose(base_pose, self.mount)

    def capture(self, world, stamp: float) -> LaserScan:
        self.scene.follow(world)
        return self.scan(stamp, world.robot.pose)

    def pose_in_odom(self, world) -> np.ndarray:
        """Its mount on the odometry pose."""
        return self.pose_in(world.robot.odom_pose)

    def shown(self, world, scan: LaserScan) -> tuple[np.ndarray, np.ndarray]:
        """The beams that hit each person, and who was within the field of view and range."""
        agents = world.agents()
        pose = self.pose_in(world.robot.pose)
        beams, in_view = np.zeros(len(agents.id)), np.empty(len(agents.id), np.bool_)
        _shown(agents.id, agents.position, scan.person_id, pose[0], pose[1], pose[2], self.range_max,
               np.radians(self.fov_deg) / 2, beams, in_view)
        return beams, in_view

    def rays(self, robot_pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The beams' common origin [3] and directions [n, 3] in the world, from the laser's true pose."""
        pose = self.pose_in(robot_pose)
        a = pose[2] + self.angles
        self._vec[:, 0] = np.cos(a)
        self._vec[:, 1] = np.sin(a)
        return np.array([pose[0], pose[1], self.height]), self._vec

    def scan(self, stamp: float, robot_pose: np.ndarray) -> LaserScan:
        """Cast every beam from the laser's true pose; the scene must be synced to the same instant."""
        origin, vec = self.rays(robot_pose)
        self.scene.cast(origin, vec, self._groups, self.scene.robot_body, self.range_max, self._geom, self._dist)
        return self.reading(stamp, self._dist, self._geom)

    def reading(self, stamp: float, dist: np.ndarray, geom: np.ndarray) -> LaserScan:
        """The scan from the beams' true distances (-1 or beyond range: no return) and hit geoms: range errors,
        range limits, the no-return value and the ground-truth person per beam."""
        noise = self.rng.standard_normal(self.n_beams)
        ranges, person = np.empty(self.n_beams), np.empty(self.n_beams, np.int64)
        scene = self.scene
        _reading(dist, geom, noise, self._band_edges, self._statistical, self._systematic * self._bias_share,
                 self.range_min, self.range_max, np.nan if self.no_return == "nan" else self.range_max,
                 scene._geom_slot, scene.slot_person_id, ranges, person)
        return LaserScan(stamp, self.name, self.angle_min, self.angle_increment, self.range_max, ranges, person)


@kernel
def _shown(ids, position, beam_person, x, y, yaw, range_max, half_fov, beams, in_view):
    """``Laser.shown`` for persons ``ids`` (sorted) at ``position``: each one's count of the beams that hit them, and
    whether they lie within ``range_max`` of the laser at (x, y) and within ``half_fov`` of its heading ``yaw``."""
    for b in range(len(beam_person)):
        if beam_person[b] >= 0:
            beams[np.searchsorted(ids, beam_person[b])] += 1.0
    for i in range(len(ids)):
        rx, ry = position[i, 0] - x, position[i, 1] - y
        bearing = math.atan2(ry, rx) - yaw
        in_view[i] = (math.sqrt(rx * rx + ry * ry) <= range_max
                      and abs(math.atan2(math.sin(bearing), math.cos(bearing))) <= half_fov)


@kernel
def _reading(dist, geom, noise, band_edges, statistical, offset, range_min, range_max, no_return, geom_slot,
             slot_person, ranges, person):
    """Each beam's reading: its true distance plus the error of its range band (the first band whose upper edge is
    not below the distance; fresh noise times the band's statistical error, plus the laser's offset within its
    systematic error), clipped to the range limits; ``no_return`` where the beam met nothing within them. The
    person it hit from the geom (-1 for walls, the robot or nothing)."""
    for i in range(len(dist)):
        d = dist[i]
        if not (range_min <= d <= range_max):
            ranges[i], person[i] = no_return, -1
            continue
        band = 0
        while band < len(band_edges) and band_edges[band] < d:
            band += 1
        r = d + (noise[i] * statistical[band] + offset[band])
        ranges[i] = min(max(r, range_min), range_max)
        slot = geom_slot[geom[i]]
        person[i] = slot_person[slot] if slot >= 0 else -1


class LaserArray:
    """The lasers of one scene, cast together at a tick: the scene synced once, then one ``mj_multiRay`` per laser.
    MuJoCo's batched ray call (``mujoco.batch``) reads exactly the same, but on two cores it costs more CPU than the
    calls it replaces (it copies five model fields into its copies of the scene each time): 1,970 against 1,650 us a
    cycle for the airport's two lasers (``crowdsim bench sensors`` measures both)."""

    def __init__(self, lasers: list[Laser], scene: Scene):
        self.lasers, self.scene = lasers, scene
        for laser in lasers:
            laser.batch = self

    def capture(self, lasers: list[Laser], world, stamp: float) -> list[LaserScan]:
        """The scans of ``lasers`` (some of this array's) of ``world`` now."""
        self.scene.follow(world)
        return self.scan(stamp, world.robot.pose, [self.lasers.index(laser) for laser in lasers])

    def scan(self, stamp: float, robot_pose: np.ndarray, which: list[int]) -> list[LaserScan]:
        """Scans of the lasers ``which`` (indices) at the scene's current state."""
        return [self.lasers[k].scan(stamp, robot_pose) for k in which]
