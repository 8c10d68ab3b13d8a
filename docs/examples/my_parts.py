"""A group stage, a planner and a driver of one's own (docs/extending.md), each named in a scenario as
``my_parts:ClassName`` or, for the driver, run from one's own loop."""

import numpy as np
from scipy.sparse.csgraph import connected_components

from pipeline.frames import inverse, transform_points
from pipeline.types import SocialRelations, TrackedGroups, TrackedPersons


class NearbyGroups:
    """Tracks nearer than ``distance`` m to each other are related (strength 1) and form groups of two or more."""

    def __init__(self, distance: float = 1.5):
        self.distance = distance

    def update(self, stamp: float, tracks: TrackedPersons):
        a, b = np.triu_indices(len(tracks), 1)
        near = np.hypot(*(tracks.position[a] - tracks.position[b]).T) < self.distance
        relations = SocialRelations(stamp, tracks.track_id[a[near]], tracks.track_id[b[near]], np.ones(near.sum()))
        n = len(tracks)
        adjacency = np.zeros((n, n), bool)
        adjacency[a[near], b[near]] = True
        _, label = connected_components(adjacency, directed=False)
        sizes = np.bincount(label, minlength=n)
        member = sizes[label] >= 2
        groups = np.unique(label[member])
        centroid = np.array([tracks.position[label == g].mean(axis=0) for g in groups]).reshape(-1, 2)
        return relations, TrackedGroups(stamp, tracks.frame, groups.astype(np.int64), centroid,
                                        label[member].astype(np.int64), tracks.track_id[member], np.zeros(len(groups)))

    def reset(self):
        pass


class CreepPlanner:
    """Towards the goal at ``speed`` m/s, turning on the spot first; stopped while anyone's track is within
    ``stop`` m. It gets what the robot has: its odometry pose, laser returns, tracks and the goal, all in odom."""

    def __init__(self, speed: float = 0.3, stop: float = 1.0):
        self.speed, self.stop = speed, stop

    def command(self, stamp, pose, velocity, obstacles, tracks, goal):
        g = transform_points(inverse(pose), np.asarray(goal, float).reshape(1, 2))[0]
        heading = float(np.arctan2(g[1], g[0]))
        crowded = len(tracks) and np.hypot(*(tracks.position - pose[:2]).T).min() < self.stop
        v = 0.0 if crowded or abs(heading) > 0.3 else self.speed
        return v, 1.5 * heading

    def reset(self):
        pass


def drive_in_a_circle(sim, seconds: float, v: float = 0.4, omega: float = 0.4):
    """A driver of one's own, outside the loop: the caller's (v, omega) every tick (``Simulation.step(command)``);
    the Frames of the tracking cycles come back as the loop makes them."""
    frames = []
    for _ in range(int(round(seconds / sim.dt))):
        frame = sim.step((v, omega))
        if frame is not None:
            frames.append(frame)
    return frames


class GrowingPatience:
    """A deletion logic for the NNT (``pipeline.tracker.deletion``): a confirmed track may miss ``base`` cycles,
    one more for every ``per_miss`` detections it was matched with, at most ``cap``; an unconfirmed one, one."""

    def __init__(self, base: int = 5, per_miss: int = 10, cap: int = 50):
        self.base, self.per_miss, self.cap = base, per_miss, cap

    def limits(self, confirmed: np.ndarray, hits: np.ndarray) -> np.ndarray:
        """The misses [n] at which each track goes, from whether it is confirmed [n] and its detections [n]."""
        return np.where(confirmed, np.minimum(self.base + hits // self.per_miss, self.cap), 1)
