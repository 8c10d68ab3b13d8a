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

import numpy as np

from pipeline.camera_geometry import image_to_floor
from pipeline.frames import rotate_covariances, rotation, to_frame
from pipeline.types import DetectedPersons

from .background import SigmaDelta, person_blobs
from .hog import load_model

HOG_SCALES = [float(1.2 ** k) for k in range(8)]  # windows 128-458 px high: a person 2.2 to 8 m away at f 579


class WallCameraDetector:
    """The ``wall_people`` detector: ``foreground`` and ``hog`` switch the two kinds on and off."""

    def __init__(self, foreground: bool = True, hog: bool = True, model: str | None = None,
                 hog_scales: list = HOG_SCALES, bootstrap: int = 15, min_area: int = 150, min_aspect: float = 1.2,
                 max_aspect: float = 5.0, robot_radius: float = 0.5, position_variance: float = 0.09):
        if not (foreground or hog):
            raise ValueError("foreground, hog: expected at least one of them on")
        self.foreground, self.hog = foreground, hog
        self.model = load_model(model) if hog else None
        self.hog_scales = np.asarray(hog_scales, float)
        self.background = SigmaDelta(bootstrap=bootstrap)
        self.blob_limits = {"min_area": min_area, "min_aspect": min_aspect, "max_aspect": max_aspect}
        self.robot_radius = robot_radius
        self.position_variance = position_variance
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
            boxes = person_blobs(self.background.update(frame.rgb), **self.blob_limits)
            out["fseg"] = self._on_floor(frame, boxes, "fseg", np.ones(len(boxes)))
        if self.hog:
            boxes, scores = self.model.detect(frame.rgb, self.hog_scales)
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
