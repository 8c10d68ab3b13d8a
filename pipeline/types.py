"""The plain data types every part exchanges (the SPENCER messages' equivalents, seed 000 Sec. 3.1, 4.1, 6.1).

Batches are structs of numpy arrays, one row per person, never lists of objects. Unknown covariance components get
a large finite variance (``UNKNOWN_VARIANCE``), never inf, as the SPENCER messages do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .compiled import kernel

UNKNOWN_VARIANCE = 1e6
"""Variance (m^2) given to a covariance component the producer does not know (seed 000: large, never infinite)."""


@dataclass
class LaserScan:
    """One sweep of a 2D laser, ranges in the sensor frame (x forward, angles counter-clockwise).

    A beam that returned nothing reads NaN, or ``range_max`` where the laser is configured so (``no_return``, as
    many drivers report it); ``returned`` tells them apart either way, as in ROS, where a range must lie below
    range_max to count. ``person_id`` is the ground-truth id of the person each beam hit (-1 for none); it is
    simulation-only and detectors must not read it.
    """

    stamp: float
    frame: str
    angle_min: float
    angle_increment: float
    range_max: float
    ranges: np.ndarray
    person_id: np.ndarray

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.ranges.size)

    @property
    def returned(self) -> np.ndarray:
        """The beams [n] that measured something."""
        return np.isfinite(self.ranges) & (self.ranges < self.range_max)

    def points(self) -> np.ndarray:
        """Beam endpoints [n, 2] in the sensor frame (NaN rows for no return): made at the first call and kept, read
        only (the detector, the driver's clearance and the ground truth each ask; a scan is not changed once made)."""
        points = self.__dict__.get("_points")
        if points is None:
            cos, sin = _beam_directions(self.angle_min, self.angle_increment, self.ranges.size)
            points = np.empty((self.ranges.size, 2))
            _endpoints(np.asarray(self.ranges, np.float64), float(self.range_max), cos, sin, points)
            points.flags.writeable = False
            self._points = points
        return points


@kernel
def _endpoints(ranges, range_max, cos, sin, out):
    """``LaserScan.points``: each beam's range times its direction's cos and sin, NaN where it returned nothing
    (non-finite, or not below ``range_max``)."""
    for i in range(len(ranges)):
        r = ranges[i] if math.isfinite(ranges[i]) and ranges[i] < range_max else np.nan
        out[i, 0], out[i, 1] = r * cos[i], r * sin[i]


_DIRECTIONS: dict[tuple[float, float, int], tuple[np.ndarray, np.ndarray]] = {}


def _beam_directions(angle_min: float, angle_increment: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin [n] of a laser's beam angles, made once per beam layout (a laser's scans all share one)."""
    key = (float(angle_min), float(angle_increment), int(n))
    if key not in _DIRECTIONS:
        if len(_DIRECTIONS) >= 64:  # bounded: a layout per laser, a few lasers a run
            _DIRECTIONS.clear()
        a = angle_min + angle_increment * np.arange(n)
        cos, sin = np.cos(a), np.sin(a)
        cos.flags.writeable = sin.flags.writeable = False
        _DIRECTIONS[key] = cos, sin
    return _DIRECTIONS[key]


@dataclass
class DepthFrame:
    """One depth image of an RGB-D camera, in its optical frame (x right, y down, z forward).

    ``depth`` [h, w] float32 is the z-depth in metres, NaN where the camera measured nothing. ``points`` [n, 3] are
    the valid pixels back-projected, in the same frame. ``person_id`` [h, w] is the ground-truth id of the person
    each pixel shows (-1 for none; simulation-only). ``rgb`` [h, w, 3] uint8 when the camera has colour. The
    simulation fills in, as a wall camera's frame has them, per person the image shows (rows of ``ids``): the box
    around the visible pixels, the box around the person as it would show unoccluded, and the visible fraction
    (simulation-only; None until filled). The calibration, as a wall camera's frame has it: ``camera_matrix`` (3x3
    K) and ``pose``, the optical frame in the tracking frame through the robot's odometry (the loop fills it in).
    """

    stamp: float
    frame: str
    depth: np.ndarray
    points: np.ndarray
    person_id: np.ndarray
    rgb: np.ndarray | None = None
    ids: np.ndarray | None = None
    boxes: np.ndarray | None = None
    full_boxes: np.ndarray | None = None
    visible_fraction: np.ndarray | None = None
    camera_matrix: np.ndarray | None = None
    pose: np.ndarray | None = None


@dataclass
class CameraFrame:
    """One image of a fixed wall camera, with the ground truth of who is visible and where.

    ``person_id`` [h, w] is the segmentation (-1 for none; simulation-only). Per visible person (rows of ``ids``):
    ``boxes`` [n, 4] (u0, v0, u1, v1) around the visible pixels, ``full_boxes`` [n, 4] around the person as it
    would show unoccluded, ``visible_fraction`` [n] of its unoccluded pixels that show.

    The calibration, what a camera detector may use: ``camera_matrix`` (3x3 K) and ``pose``, the optical frame in the
    tracking frame (4x4) as the robot's localisation places the fixed camera (the loop fills it in); and
    ``robot_position``, the robot's (x, y) in the tracking frame by its odometry, so that a detector can mask the robot
    out.
    """

    stamp: float
    frame: str
    rgb: np.ndarray | None
    person_id: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    full_boxes: np.ndarray
    visible_fraction: np.ndarray
    camera_matrix: np.ndarray | None = None
    pose: np.ndarray | None = None
    robot_position: np.ndarray | None = None


@dataclass
class Visibility:
    """Who each sensor could see at its latest frame, as of one tracking cycle (simulation-only ground truth, one row
    per person alive).

    ``stamps`` [k]: the time of each sensor's latest frame (NaN before its first). ``amount`` [n, k]: what that frame
    saw of the person: for a laser the number of its beams that hit them, for a camera their visible fraction (NaN
    before the sensor's first frame and for persons who came after it). ``in_view`` [n, k]: within the sensor's
    field of view and range at that frame, so a person in view whom the frame did not show is ``occluded``.
    """

    ids: np.ndarray
    sensors: list[str]
    stamps: np.ndarray
    amount: np.ndarray
    in_view: np.ndarray

    @property
    def occluded(self) -> np.ndarray:
        return self.in_view & (self.amount == 0)

    def of(self, sensor: str) -> np.ndarray:
        return self.amount[:, self.sensors.index(sensor)]


@dataclass
class GroundTruthTags:
    """What the evaluation needs to know of each ground-truth person of a tracking cycle (rows as the ground
    truth's): the true distance from the robot, whether within the evaluation's range, the laser beams that hit
    them, whether any did (``visible``: not physically occluded), and seed 000's own occlusion test
    (``visible_seed000``: a laser point within 0.3 m of the position moved 0.2 m towards that laser)."""

    range: np.ndarray  # [n] m
    in_range: np.ndarray  # [n] bool
    beams: np.ndarray  # [n] int
    visible: np.ndarray  # [n] bool
    visible_seed000: np.ndarray  # [n] bool

    @property
    def ignore(self) -> np.ndarray:
        """Rows that count neither as a miss nor, matched, as a false positive: occluded or out of range."""
        return ~self.visible | ~self.in_range


@dataclass
class DetectedPersons:
    """Detections of one detector (or one fusion stage) at one instant, in ``frame``.

    A fused batch keeps which detections each of its rows came from (seed 000 Sec. 3.1's composite detections):
    ``originals`` maps each sensor whose detections were fused to [n] ids of its detection in each row, -1 where it
    gave none; a detector's own batch has None. A detector that sees more may add each person's ``height`` (m, top of
    the head above the floor) and ``appearance`` (a normalised colour histogram per row, seed 003's Eq. 1).
    """

    stamp: float
    frame: str
    modality: str
    detection_id: np.ndarray  # [n] int64, unique per producer over a run
    position: np.ndarray  # [n, 3]
    covariance: np.ndarray  # [n, 3, 3]
    confidence: np.ndarray  # [n]
    originals: dict[str, np.ndarray] | None = None
    height: np.ndarray | None = None  # [n] m
    appearance: np.ndarray | None = None  # [n, bins]

    def __len__(self) -> int:
        return int(self.detection_id.size)

    @classmethod
    def empty(cls, stamp: float, frame: str, modality: str) -> "DetectedPersons":
        return cls(stamp, frame, modality, np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros(0))

    @classmethod
    def on_floor(cls, stamp: float, frame: str, modality: str, first_id: int, xy: np.ndarray, variance: float,
                 confidence: np.ndarray | None = None) -> "DetectedPersons":
        """Detections at points [n, 2] of a plane scan (height unknown), ``variance`` in x and y, ids from
        ``first_id`` on, confidence 1 unless given."""
        n = len(xy)
        cov = np.zeros((n, 3, 3))
        cov[:, 0, 0] = cov[:, 1, 1] = variance
        cov[:, 2, 2] = UNKNOWN_VARIANCE
        return cls(stamp, frame, modality, np.arange(first_id, first_id + n, dtype=np.int64),
                   np.concatenate([xy, np.zeros((n, 1))], axis=1), cov,
                   np.ones(n) if confidence is None else np.asarray(confidence, float))


@dataclass
class TrackedPersons:
    """People tracks (or ground truth, which uses the same shape) at one instant, in ``frame``.

    Positions and velocities are 2D (x, y) because tracking happens on the ground plane (seed 000 Sec. II-B).
    ``detection_id`` is the detection that updated the track this cycle (-1 when none). Ground truth fills
    ``group_id`` (-1 for a person walking alone); trackers leave it None. A tracker whose detections have heights
    gives each track's ``height`` (m, for its image box).
    """

    stamp: float
    frame: str
    track_id: np.ndarray  # [n] int64
    is_matched: np.ndarray  # [n] bool
    is_occluded: np.ndarray  # [n] bool
    detection_id: np.ndarray  # [n] int64
    position: np.ndarray  # [n, 2]
    velocity: np.ndarray  # [n, 2]
    position_covariance: np.ndarray  # [n, 2, 2]
    velocity_covariance: np.ndarray  # [n, 2, 2]
    age: np.ndarray  # [n] seconds since the track was started
    group_id: np.ndarray | None = None  # [n] int64, ground truth only
    height: np.ndarray | None = None  # [n] m

    def __len__(self) -> int:
        return int(self.track_id.size)

    @classmethod
    def empty(cls, stamp: float, frame: str) -> "TrackedPersons":
        z = np.zeros(0)
        return cls(stamp, frame, np.zeros(0, np.int64), z.astype(bool), z.astype(bool), np.zeros(0, np.int64),
                   np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros((0, 2, 2)), z)

    def select(self, mask: np.ndarray) -> "TrackedPersons":
        """The rows where ``mask`` holds (a boolean mask or an index array)."""
        return TrackedPersons(
            self.stamp, self.frame, self.track_id[mask], self.is_matched[mask], self.is_occluded[mask],
            self.detection_id[mask], self.position[mask], self.velocity[mask], self.position_covariance[mask],
            self.velocity_covariance[mask], self.age[mask], None if self.group_id is None else self.group_id[mask],
            None if self.height is None else self.height[mask])


@dataclass
class TagReading:
    """One reading of a tag worn by the followed person (seed 001 Sec. 3.2's RFID: a coarse range and azimuth,
    all around the robot), in ``base_link``: ``range`` (m) and ``bearing`` (rad, counter-clockwise from x), with the
    standard deviations of their errors as the sensor states them, for gating."""

    stamp: float
    range: float
    bearing: float
    range_sd: float
    bearing_sd: float


@dataclass
class SocialRelations:
    """Weighted pairs of track ids (seed 000, coherent motion indicators)."""

    stamp: float
    track_a: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    track_b: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    strength: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass
class TrackedGroups:
    """Groups as sets of track ids with a centroid; ``member_group[i]`` is the group of ``member_track[i]``;
    ``age`` (s) is how long each group's exact member set has existed (SPENCER's TrackedGroup.age)."""

    stamp: float
    frame: str
    group_id: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    centroid: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    member_group: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    member_track: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    age: np.ndarray = field(default_factory=lambda: np.zeros(0))
