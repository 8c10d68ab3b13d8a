"""Detection-to-detection fusion (seed 000 Sec. II-A): detections of several sensors, brought into one frame, are
merged greedily nearest first when closer than a distance, so a person seen by two lasers is one detection."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiled import kernel
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
    inv, count, fused_pos, fused_cov, fused_conf = _merged(
        np.ascontiguousarray(pos, np.float64), np.ascontiguousarray(cov, np.float64),
        np.ascontiguousarray(conf, np.float64), origin, float(distance))
    m = len(count)
    ids = np.arange(first_id, first_id + m, dtype=np.int64)
    modality = "+".join(sorted({b.modality for b in batches}))
    originals = {}
    for k, (name, batch) in enumerate(zip(names, batches)):  # a row holds at most one detection of each batch
        originals[name] = np.full(m, -1, np.int64)
        originals[name][inv[origin == k]] = batch.detection_id
    stamp = max(b.stamp for b in batches)
    return DetectedPersons(stamp, batches[0].frame, modality, ids, fused_pos, fused_cov, fused_conf, originals,
                           _mean_rows(batches, "height", inv, count), _mean_rows(batches, "appearance", inv, count))


@kernel
def _merged(pos, cov, conf, origin, distance):
    """``fuse``'s rows: each detection's fused row, and each row's count, mean position, covariance of the mean and
    largest confidence. Pairs from different batches (``origin``) nearer than ``distance`` on the floor merge
    greedily, nearest first (ties in the order of the pairs i < j), each detection into one pair at most; rows are
    numbered by their first detection."""
    n = len(pos)
    first, second, gap = np.empty(n * (n - 1) // 2, np.int64), np.empty(n * (n - 1) // 2, np.int64), np.empty(
        n * (n - 1) // 2)
    pairs = 0
    for i in range(n):
        for j in range(i + 1, n):
            d = np.sqrt((pos[i, 0] - pos[j, 0]) ** 2 + (pos[i, 1] - pos[j, 1]) ** 2)
            if origin[i] != origin[j] and d < distance:
                p = pairs  # a stable insertion sort by distance
                while p > 0 and gap[p - 1] > d:
                    first[p], second[p], gap[p] = first[p - 1], second[p - 1], gap[p - 1]
                    p -= 1
                first[p], second[p], gap[p] = i, j, d
                pairs += 1
    owner = np.arange(n)
    used = np.zeros(n, np.bool_)
    for p in range(pairs):
        if not used[first[p]] and not used[second[p]]:
            used[first[p]] = used[second[p]] = True
            owner[second[p]] = first[p]
    row = np.empty(n, np.int64)
    m = 0
    for k in range(n):  # an owner comes before what it owns
        if owner[k] == k:
            row[k] = m
            m += 1
        else:
            row[k] = row[owner[k]]
    count, fused_pos = np.zeros(m), np.zeros((m, 3))
    fused_cov, fused_conf = np.zeros((m, 3, 3)), np.zeros(m)
    for k in range(n):
        r = row[k]
        count[r] += 1.0
        fused_pos[r] += pos[k]
        fused_cov[r] += cov[k]
        if not fused_conf[r] >= conf[k] and not np.isnan(fused_conf[r]):  # numpy's maximum: NaN wins
            fused_conf[r] = conf[k]
    for r in range(m):
        fused_pos[r] /= max(count[r], 1.0)
        fused_cov[r] /= max(count[r], 1.0) ** 2  # the variance of the mean of independent estimates
    return row, count, fused_pos, fused_cov, fused_conf


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
