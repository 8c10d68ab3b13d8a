# my_trackers.py: a tracker of your own, a small global-nearest-neighbour one
import numpy as np
from scipy.optimize import linear_sum_assignment

from pipeline.types import TrackedPersons


class GnnTracker:
    """Each cycle the detections (DetectedPersons in odom) are matched one to one to the tracks' predicted
    positions by Munkres on the squared Mahalanobis distance, within ``gate`` (chi-square, 2 dof). A matched track
    takes its detection's position and a smoothed velocity; an unmatched one coasts, and goes after ``max_misses``
    cycles; every unmatched detection starts a track."""

    def __init__(self, gate: float = 13.82, max_misses: int = 5, smoothing: float = 0.5):
        self.gate, self.max_misses, self.smoothing = gate, max_misses, smoothing
        self.reset()

    def reset(self):
        self.ids, self.misses = np.zeros(0, np.int64), np.zeros(0, np.int64)
        self.pos, self.vel, self.born = np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0)
        self.next_id, self.stamp = 1, None

    def update(self, stamp, detections):
        dt = 0.0 if self.stamp is None else stamp - self.stamp
        self.stamp = stamp
        predicted = self.pos + dt * self.vel
        z = detections.position[:, :2]
        inv = np.linalg.inv(detections.covariance[:, :2, :2] + 0.1 * np.eye(2))  # plus 0.1 m^2 of the track's own
        gap = z[None] - predicted[:, None]  # [tracks, detections, 2]
        d2 = np.einsum("tdi,dij,tdj->td", gap, inv, gap)
        rows, cols = linear_sum_assignment(np.where(d2 < self.gate, d2, 1e6))
        inside = d2[rows, cols] < self.gate
        rows, cols = rows[inside], cols[inside]
        matched = np.zeros(len(self.ids), bool)
        matched[rows] = True
        detection = np.full(len(self.ids), -1, np.int64)
        detection[rows] = detections.detection_id[cols]
        if dt > 0:
            measured = (z[cols] - self.pos[rows]) / dt
            self.vel[rows] = self.smoothing * self.vel[rows] + (1 - self.smoothing) * measured
        self.pos = predicted
        self.pos[rows] = z[cols]
        self.misses = np.where(matched, 0, self.misses + 1)
        alive = self.misses <= self.max_misses
        new = np.setdiff1d(np.arange(len(z)), cols)
        n = len(new)
        self.ids = np.r_[self.ids[alive], np.arange(self.next_id, self.next_id + n)]
        self.next_id += n
        self.pos, self.vel = np.r_[self.pos[alive], z[new]], np.r_[self.vel[alive], np.zeros((n, 2))]
        self.misses, self.born = np.r_[self.misses[alive], np.zeros(n, np.int64)], np.r_[self.born[alive], [stamp] * n]
        matched = np.r_[matched[alive], np.ones(n, bool)]
        detection = np.r_[detection[alive], detections.detection_id[new]]
        k = len(self.ids)
        return TrackedPersons(stamp, detections.frame, self.ids.copy(), matched, ~matched, detection, self.pos.copy(),
                              self.vel.copy(), np.tile(0.1 * np.eye(2), (k, 1, 1)), np.tile(np.eye(2), (k, 1, 1)),
                              stamp - self.born)
