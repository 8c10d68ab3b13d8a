"""Seed 003's RGB-D people detector (Munaro & Menegatti Sec. 3) on a robot's depth camera: the cloud in voxels, the
ground followed and removed, people candidates split at their heads, each a person where their head stands, kept
when the HOG classifier scores the image box that would hold them from head to ground above a threshold (Sec.
3.1.2), with the colour histogram of their points for the tracker's appearance classifier (Sec. 3.2.1).

The HOG model is this testbed's own, trained on the robot camera's rendered images (`crowdsim experiment train-hog
--camera robot`); its threshold is the score 97% of the validation candidates on people pass (the paper's "minimum
confidences under -1.25 work well": low, since the 3D stage has already found the candidates).

Clusters join points up to 0.15 m apart, not PCL's two voxels (0.12 m): our bodies' torso ends in a flat top wider
than the neck, and a camera below it sees a gap there that at 0.12 m cuts the head off a person 2-3 m away.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel
from pipeline.params import param
from pipeline.tracking.online_boost import BINS, colour_histogram, rgb_to_hsv
from pipeline.types import DepthFrame, DetectedPersons

from .ground import GroundTracker, head_position
from .head_clusters import ClusterLimits, candidates
from .hog import ROBOT_MODEL_FILE, integral, load_model, orientation_votes, window_features
from .point_cloud import voxel_grid

COLOUR_SPACES = ("rgb", "hsv")
OPTICAL_UP = [0.0, -1.0, 0.0]  # y is down in a camera's optical frame: a level camera's floor normal


def person_box(camera_matrix: np.ndarray, ground: np.ndarray, normal: np.ndarray, height: np.ndarray) -> np.ndarray:
    """The image boxes [n, 4] (u0, v0, u1, v1) of people of ``height`` [n] standing at the floor points ``ground``
    [n, 3] (camera frame; ``normal`` the floor's up): from the head down to the ground, half as wide as high, around
    the line from foot to head (KTP's ground-truth boxes, seed 003 Sec. 2)."""
    ground = np.asarray(ground, float).reshape(-1, 3)
    height = np.asarray(height, float).reshape(-1)
    ends = np.stack([ground, ground + height[:, None] * normal], axis=1) @ camera_matrix.T  # [n, 2, 3]
    uv = ends[..., :2] / ends[..., 2:]
    tall = uv[:, 0, 1] - uv[:, 1, 1]
    middle = uv.mean(axis=1)[:, 0]
    return np.column_stack([middle - tall / 4, uv[:, 1, 1], middle + tall / 4, uv[:, 0, 1]])


@kernel
def _pixels_around(uvw, rgb):
    """The colours [9 n, 3] of the 3 x 3 pixels round each image point ``uvw`` [n, 3] (homogeneous; its pixel the
    quotient truncated towards zero, as numpy's astype(int)), clipped to the image, column by column."""
    h, w = rgb.shape[0], rgb.shape[1]
    colours = np.empty((9 * len(uvw), 3), rgb.dtype)
    for i in range(len(uvw)):
        u, v = int(uvw[i, 0] / uvw[i, 2]), int(uvw[i, 1] / uvw[i, 2])
        for du in range(3):
            for dv in range(3):
                row, column = min(max(v + dv - 1, 0), h - 1), min(max(u + du - 1, 0), w - 1)
                for c in range(3):
                    colours[9 * i + 3 * du + dv, c] = rgb[row, column, c]
    return colours


def _up_direction(p: dict):
    if math.hypot(*p["up"]) < 1e-6:
        return "up", f"{p['up']}; expected a direction (a non-zero vector), e.g. [0, -1, 0]: y is down in the image"


@dataclass(eq=False)
class RgbdPeopleDetector:
    """The ``rgbd_people`` detector (module docstring). ``threshold`` None becomes the model's when the detector is
    made; ``hog`` False keeps every candidate (confidence 0, threshold -inf). The paper gives the head distance and
    voxels under 0.1 m (Table 7), the rest are its authors' released code's (PCL's ground-based people detection),
    see head_clusters.py."""

    voxel: float = param(0.06, "m, the voxel grid's leaf (Table 7: below 0.1; PCL's 0.06)", min=0.0,
                         exclusive_min=True, max=0.1)
    cluster_tolerance: float = param(
        0.15, "m, largest gap between neighbours of a Euclidean cluster (PCL: two voxels, 0.12 m; our bodies' torso "
              "ends in a flat top 12 cm wider than the neck all round, and from below a camera sees a gap there: at "
              "0.12 m a person 2-3 m away loses their head)", min=0.0, exclusive_min=True)
    head_distance: float = param(0.3, "m, least distance between two people's heads when a cluster is split (Table 7)",
                                 min=0.0, exclusive_min=True)
    up: list[float] = param(OPTICAL_UP, "the floor's up direction in the camera's optical frame, roughly (y is down): "
                                        "the first ground plane is searched near it", kind="point3")
    max_tilt_deg: float = param(30.0, "deg, the first ground plane's largest tilt from `up`", min=0.0, max=90.0)
    sub_clustering: bool = param(True, "split clusters at their heads (seed 003 Sec. 3.1.1; false: Table 2's \"No "
                                       "sub.\" row)")
    hog: bool = param(True, "score each candidate's box with the HOG classifier and keep those above threshold")
    model: str | None = param(None, "the HOG model: left out, the shipped one (`crowdsim experiment train-hog --camera "
                                    "robot`); or the path of the .npz it wrote with --out", kind="str")
    threshold: float | None = param(None, "least HOG score of a detection; left out: the model's (the score 97% of "
                                          "its validation people pass, as seed 003 keeps it low: Sec. 4.1.2)",
                                    kind="float")
    colour_space: str = param("rgb", "the detections' colour histograms (Tables 2-5: RGB; Table 7 recommends HSV); "
                                     "the tracker's colour_space must be the same", choices=COLOUR_SPACES)
    position_variance: float = param(0.036, "m^2 along the floor (the authors' later tracker: 30 (2 voxel)^2 / 12 at "
                                            "0.06 m)", min=0.0, exclusive_min=True)

    CHECKS = (_up_direction,)

    def __post_init__(self):
        self.limits = ClusterLimits(voxel=self.voxel, cluster_tolerance=self.cluster_tolerance,
                                    head_distance=self.head_distance)
        self.ground = GroundTracker(self.voxel, self.up, self.max_tilt_deg)
        self.hog_model = load_model(self.model, ROBOT_MODEL_FILE) if self.hog else None
        if not self.hog:
            self.threshold = -np.inf
        elif self.threshold is None:
            self.threshold = self.hog_model.threshold
        self.reset()
        self.timing: dict[str, float] | None = None  # a dict here gathers the seconds each stage took

    def reset(self) -> None:
        self.ground.reset()
        self._next_id = 0

    def _lap(self, stage: str, since: float) -> float:
        """With ``timing``, add the time since ``since`` to ``stage``'s; the time now."""
        now = time.perf_counter()
        if self.timing is not None:
            self.timing[stage] = self.timing.get(stage, 0.0) + now - since
        return now

    def people(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
        """The floor points [k, 3] (camera frame) where the people candidates of a cloud stand, their heights [k],
        and each one's voxel points."""
        t = time.perf_counter()
        cloud = voxel_grid(points, self.voxel)
        t = self._lap("voxel grid", t)
        floor = self.ground.update(cloud)
        t = self._lap("ground plane", t)
        if self.ground.plane is None:
            return np.zeros((0, 3)), np.zeros(0), []
        above = cloud[~floor]
        members = [above[c] for c in candidates(above, self.ground.plane, self.limits, self.sub_clustering)]
        t = self._lap("clusters and heads", t)
        found = [head_position(m, self.ground.plane) for m in members]
        self._lap("positions", t)
        if not found:
            return np.zeros((0, 3)), np.zeros(0), []
        return np.array([p for p, _ in found]), np.array([h for _, h in found]), members

    def score(self, rgb: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        """The HOG classifier's score of each person box [k, 4] in a colour image."""
        if not len(boxes):
            return np.zeros(0)
        table = integral(orientation_votes(rgb))
        return window_features(table, boxes) @ self.hog_model.weight.astype(float) + self.hog_model.bias

    def detect(self, frame: DepthFrame) -> DetectedPersons:
        if self.hog_model is not None and (frame.rgb is None or frame.camera_matrix is None):
            raise ValueError(f"{frame.frame}: the rgbd_people detector's HOG stage needs colour images (rgb: true)")
        where, height, members = self.people(frame.points)
        if not len(where):
            return self._batch(frame, where, height, np.zeros(0), np.zeros((0, BINS ** 3)))
        normal = self.ground.plane[:3]
        confidence = np.zeros(len(where))
        t = time.perf_counter()
        if self.hog_model is not None:
            confidence = self.score(frame.rgb, person_box(frame.camera_matrix, where, normal, height))
        t = self._lap("hog", t)
        keep = confidence > self.threshold
        appearance = np.array([self._histogram(frame, m) for m, k in zip(members, keep) if k]).reshape(-1, BINS ** 3)
        self._lap("colour histograms", t)
        return self._batch(frame, where[keep], height[keep], confidence[keep], appearance)

    def _histogram(self, frame: DepthFrame, points: np.ndarray) -> np.ndarray:
        """The colour histogram of a candidate's points, read where they fall in the image (registered colour): the
        3 x 3 pixels round each voxel's centroid, about the pixels the voxel holds at a few metres."""
        if frame.rgb is None or frame.camera_matrix is None:
            return np.zeros(BINS ** 3)
        colours = _pixels_around(points @ frame.camera_matrix.T, frame.rgb)
        return colour_histogram(rgb_to_hsv(colours) if self.colour_space == "hsv" else colours)

    def _batch(self, frame: DepthFrame, where, height, confidence, appearance) -> DetectedPersons:
        n = len(where)
        normal = self.ground.plane[:3] if self.ground.plane is not None else np.zeros(3)
        on_floor = self.position_variance * (np.eye(3) - np.outer(normal, normal)) + 1e-6 * np.outer(normal, normal)
        out = DetectedPersons(frame.stamp, frame.frame, "rgbd", np.arange(self._next_id, self._next_id + n),
                              np.asarray(where, float).reshape(-1, 3), np.repeat(on_floor[None], n, axis=0),
                              np.asarray(confidence, float), height=np.asarray(height, float),
                              appearance=appearance)
        self._next_id += n
        return out
