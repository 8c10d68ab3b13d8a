"""Detection-to-detection fusion (seed 000 Sec. II-A): detections of several sensors, brought into one frame, are
merged greedily nearest first when closer than a distance, so a person seen by two lasers is one detection."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import cdist

from .frames import rotate_covariances, rotation, transform_points
from .params import param
from .types import DetectedPersons


def to_frame(dets: DetectedPersons, pose: np.ndarray, frame: str) -> DetectedPersons:
    """Detections expressed in ``frame``, given the pose of their frame in it: a planar pose (x, y, yaw) for a
    sensor that scans a horizontal plane (a laser), a 4x4 rigid transform for one that looks in 3D (a camera)."""
    pose = np.asarray(pose, float)
    if pose.shape == (4, 4):
        pos = transform_points(pose, dets.position)
    else:
        pos = dets.position.copy()
        pos[:, :2] = transform_points(pose, dets.position[:, :2])
    cov = rotate_covariances(rotation(pose, 3), dets.covariance)  # a yaw turns the x-z and y-z terms too
    return DetectedPersons(dets.stamp, frame, dets.modality, dets.detection_id, pos, cov, dets.confidence,
                           height=dets.height, appearance=dets.appearance)


def fuse(batches: dict[str, DetectedPersons], distance: float, first_id: int = 0) -> DetectedPersons:
    """One batch from the batches of several sensors (by name) in the same frame; pairs from different batches
    nearer than ``distance`` are averaged.

    Fused detections get fresh ids from ``first_id`` on, the latest stamp of the batches, and their ``originals``.
    """
    names, batches = list(batches), list(batches.values())
    frames = {b.frame for b in batches}
    if len(frames) != 1:
        raise ValueError(f"fusion needs detections in one frame, got {sorted(frames)}")
    pos = np.concatenate([b.position for b in batches])
    cov = np.concatenate([b.covariance for b in batches])
    conf = np.concatenate([b.confidence for b in batches])
    origin = np.concatenate([np.full(len(b), k) for k, b in enumerate(batches)])
    n = len(pos)
    owner = np.arange(n)
    if n > 1 and len(batches) > 1:
        d = cdist(pos[:, :2], pos[:, :2])
        d[origin[:, None] == origin[None, :]] = np.inf
        i, j = np.nonzero(np.triu(d < distance, 1))
        used = np.zeros(n, bool)
        for k in np.argsort(d[i, j], kind="stable"):  # greedy, nearest pair first; only overlap pairs loop here
            a, b = i[k], j[k]
            if not used[a] and not used[b]:
                used[a] = used[b] = True
                owner[b] = a
    _, inv = np.unique(owner, return_inverse=True)
    m = inv.max() + 1 if n else 0
    count = np.bincount(inv, minlength=m).astype(float)
    fused_pos = np.stack([np.bincount(inv, pos[:, k], m) for k in range(3)], 1) / np.maximum(count, 1)[:, None]
    fused_cov = np.zeros((m, 3, 3))
    np.add.at(fused_cov, inv, cov)
    fused_cov /= np.maximum(count, 1)[:, None, None] ** 2  # variance of the mean of independent estimates
    fused_conf = np.zeros(m)
    np.maximum.at(fused_conf, inv, conf)
    ids = np.arange(first_id, first_id + m, dtype=np.int64)
    modality = "+".join(sorted({b.modality for b in batches}))
    originals = {}
    for k, (name, batch) in enumerate(zip(names, batches)):  # a row holds at most one detection of each batch
        originals[name] = np.full(m, -1, np.int64)
        originals[name][inv[origin == k]] = batch.detection_id
    stamp = max(b.stamp for b in batches)
    return DetectedPersons(stamp, batches[0].frame, modality, ids, fused_pos, fused_cov, fused_conf, originals,
                           _mean_rows(batches, "height", inv, count), _mean_rows(batches, "appearance", inv, count))


def _mean_rows(batches: list[DetectedPersons], name: str, inv: np.ndarray, count: np.ndarray) -> np.ndarray | None:
    """A per-detection field (height, appearance) averaged over each fused row's members; None unless every batch
    has it, of one width."""
    values = [getattr(b, name) for b in batches]
    if any(v is None for v in values) or len({np.shape(v)[1:] for v in values}) != 1:
        return None
    rows = np.concatenate(values)
    out = np.zeros((len(count), *rows.shape[1:]))
    np.add.at(out, inv, rows)
    return out / np.maximum(count, 1).reshape(-1, *[1] * (rows.ndim - 1))


@dataclass(eq=False)
class NearestFusion:
    """The ``nearest`` fusion: ``fuse`` on each cycle's batches, the fused ids counted over the run."""

    distance: float = param(0.4, "m, detections of two sensors nearer than this are one person", min=0.0)

    def __post_init__(self):
        self.reset()

    def reset(self) -> None:
        self._next_id = 0

    def fuse(self, batches: dict[str, DetectedPersons]) -> DetectedPersons:
        fused = fuse(batches, self.distance, self._next_id)
        self._next_id += len(fused)
        return fused


FUSIONS: dict[str, type] = {"nearest": NearestFusion}
