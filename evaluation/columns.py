"""The columns of every CSV a run writes, declared once: ``crowdsim run`` (crowdsim/run.py) writes each file's columns
in this order, and the readers (evaluation/io.py, group_score.py, navigation.py, report.py) name the ones they need
from here, so a writer and its reader cannot drift apart.

The kinds of column are declared here too, as the writer formats them and the reader checks them: ``WHOLE`` ids,
frame numbers and counts, ``FLAGS`` 0/1 tags, ``SHARES`` numbers in [0, 1]; every other column is a real number.
"""

from __future__ import annotations

# whole numbers: written as integers, read back as whole numbers a float64 holds exactly (evaluation/io.py)
WHOLE = frozenset({"frame", "id", "group", "track_a", "track_b", "target_track", "target_visible", "beams"})
# yes/no flags, 0 or 1 (a ground truth's visibility and range tags); written as integers too
FLAGS = frozenset({"visible", "visible_seed000", "in_range", "in_view", "occluded"})
# shares in [0, 1]
SHARES = frozenset({"strength"})


class Columns(tuple):
    """A file's column names in the order they are written; ``pick`` names a reader's subset, checked against the
    declaration."""

    def __new__(cls, file: str, *names: str):
        self = super().__new__(cls, names)
        self.file = file
        return self

    @property
    def header(self) -> str:
        """The file's header row (without its newline)."""
        return ",".join(self)

    def pick(self, *names: str) -> tuple[str, ...]:
        """The columns ``names`` (a reader's), each one this file has."""
        unknown = [n for n in names if n not in self]
        if unknown:
            raise ValueError(f"{self.file} has no column(s) {', '.join(unknown)}")
        return names


TRACKS = Columns("tracks.csv", "frame", "t", "id", "x", "y", "vx", "vy")  # odom
# the ground truth adds, per person, the true distance from the robot, whether within the evaluation's range, the
# laser beams that hit them this cycle (all lasers), whether any did, seed 000's own occlusion test, and the group
GROUNDTRUTH = Columns("groundtruth.csv", *TRACKS, "range", "in_range", "beams", "visible", "visible_seed000",
                      "group")
DETECTIONS = Columns("detections.csv", "frame", "t", "id", "x", "y", "confidence")  # the fused detections, odom
RELATIONS = Columns("relations.csv", "frame", "t", "track_a", "track_b", "strength")
GROUPS = Columns("groups.csv", "frame", "t", "group", "id", "x", "y", "age")  # one row per member, the centroid
# the robot's true pose in the world and its odometry pose in odom, per tracking cycle
ROBOT = Columns("robot.csv", "frame", "t", "x", "y", "yaw", "odom_x", "odom_y", "odom_yaw")
# per sensor frame and person in view or seen: beams or visible share (amount), in view, in view but unseen
VISIBILITY = Columns("visibility.csv", "frame", "t", "id", "sensor", "amount", "in_view", "occluded")
# navigation: every person alive per cycle, world frame, with their disc radius; the follower's track of the target
PERSONS = Columns("persons.csv", "frame", "t", "id", "x", "y", "vx", "vy", "radius")
FOLLOWING = Columns("following.csv", "frame", "t", "target_track", "target_visible")
