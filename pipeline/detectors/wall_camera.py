"""People in a fixed wall camera's colour images, on the floor (seed 001 Sec. 4.2-4.3): foreground blobs of
Sigma-Delta background subtraction (``fseg``) and HOG windows (``hog``), each a person at the foot point of its box
(the middle of its bottom edge) projected to the floor through the camera's calibration.

The two kinds come as named batches (``{"fseg": ..., "hog": ...}``), so a fusing tracker can weigh them apart, as
seed 001's Table 1 does (k_d 0.22 and 0.2 per camera). A detection whose floor point is within ``robot_radius`` of
the robot (its odometry position, ``CameraFrame.robot_position``) is the robot, masked out as seed 001's are. A
detection's point is on the floor (z = 0 in the tracking frame), given in the camera's optical frame as every
detector gives its own frame's; its covariance is ``position_variance`` along the floor (seed 001 Table 1: Sigma =
diag(0.09, 0.09) m^2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.camera_geometry import image_to_floor
from pipeline.frames import rotate_covariances, rotation, to_frame
from pipeline.params import param
from pipeline.types import DetectedPersons

from .background import SigmaDelta, person_blobs
from .hog import load_model

HOG_SCALES = [float(1.2 ** k) for k in range(8)]  # windows 128-458 px high: a person 2.2 to 8 m away at f 579


def _foreground_or_hog(p: dict):
    if not (p["foreground"] or p["hog"]):
        return "hog", "false with foreground false too; expected at least one of foreground and hog on"


@dataclass(eq=False)
class WallCameraDetector:
    """The ``wall_people`` detector: ``foreground`` and ``hog`` switch the two kinds on and off. Seed 001 Sec.
    4.2-4.3 names the methods (Sigma-Delta, morphology, an aspect ratio; HOG) but gives no parameter."""

    foreground: bool = param(True, "Sigma-Delta foreground blobs (the batch `fseg`)")
    hog: bool = param(True, "HOG person windows (the batch `hog`)")
    model: str | None = param(None, "the HOG model: left out, the shipped one (`crowdsim experiment train-hog`); or "
                                    "the path of the .npz it wrote with --out", kind="str")
    hog_scales: list[float] = param(HOG_SCALES, "window scales searched (1: 64 x 128 pixels); the default covers a "
                                                "person 2.2-8 m from a 640 x 480 camera at 45 degrees",
                                    item=dict(min=0.1), min_items=1)
    bootstrap: int = param(15, "frames whose median starts the background model (no detection before)", min=1)
    min_area: int = param(150, "pixels, least foreground blob", min=1)
    min_aspect: float = param(1.2, "least height / width of a foreground blob", min=0.0)
    max_aspect: float = param(5.0, "largest height / width of a foreground blob", min=0.0)
    robot_radius: float = param(0.5, "m, a detection whose floor point is this near the robot is the robot, masked "
                                     "out (Rackham's 0.26 m and a margin for the foot point's error)", min=0.0)
    position_variance: float = param(0.09, "m^2 along the floor (seed 001 Table 1: Sigma = diag(0.09, 0.09))",
                                     min=0.0, exclusive_min=True)

    CHECKS = (_foreground_or_hog,)

    def __post_init__(self):
        self.hog_model = load_model(self.model) if self.hog else None
        self.background = SigmaDelta(bootstrap=self.bootstrap)
        self.reset()

    def reset(self) -> None:
        self.background.reset()
        self._next_id = 0

    def detect(self, frame) -> dict[str, DetectedPersons]:
        if frame.rgb is None or frame.camera_matrix is None or frame.pose is None:
            raise ValueError(f"{frame.frame}: the wall_people detector needs colour images (rgb: true) with their "
                             "calibration (camera_matrix, pose)")
        out = {}
        if self.foreground:
            boxes = person_blobs(self.background.update(frame.rgb), min_area=self.min_area, min_aspect=self.min_aspect,
                                 max_aspect=self.max_aspect)
            out["fseg"] = self._on_floor(frame, boxes, "fseg", np.ones(len(boxes)))
        if self.hog:
            boxes, scores = self.hog_model.detect(frame.rgb, np.asarray(self.hog_scales, float))
            out["hog"] = self._on_floor(frame, boxes, "hog", scores)
        return out

    def _on_floor(self, frame, boxes: np.ndarray, modality: str, confidence: np.ndarray) -> DetectedPersons:
        """Detections at the floor points under the boxes' foot points, in the optical frame."""
        feet = np.column_stack([(boxes[:, 0] + boxes[:, 2]) / 2, boxes[:, 3]]) if len(boxes) else np.zeros((0, 2))
        xy = image_to_floor(frame.camera_matrix, frame.pose, feet)
        seen = np.isfinite(xy).all(axis=1)
        if frame.robot_position is not None:  # the robot masked out (seed 001 Sec. 4.2): no person stands in it
            seen &= ~(np.hypot(*(xy - frame.robot_position).T) < self.robot_radius)
        xy, confidence = xy[seen], np.asarray(confidence, float)[seen]
        n = len(xy)
        position = to_frame(frame.pose, np.column_stack([xy, np.zeros(n)]))  # the floor point in the optical frame
        floor_cov = np.diag([self.position_variance, self.position_variance, 1e-6])
        cov = np.repeat(rotate_covariances(rotation(frame.pose).T, floor_cov)[None], n, axis=0)
        ids = np.arange(self._next_id, self._next_id + n, dtype=np.int64)
        self._next_id += n
        return DetectedPersons(frame.stamp, frame.frame, modality, ids, position, cov, confidence)
