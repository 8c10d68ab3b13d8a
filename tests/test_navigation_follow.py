"""The person follower: which track the tag picks, keeping it, re-acquiring it, and where it drives."""

import numpy as np
import pytest

from pipeline.navigation.follow import PersonFollower
from pipeline.navigation.planners import StraightPlanner
from pipeline.types import TagReading, TrackedPersons

ROBOT = {"radius": 0.425, "max_speed": 0.6, "max_angular_speed": 1.0, "max_acceleration": 0.5}
HERE = np.zeros(3)


def persons(ids, position, velocity=None) -> TrackedPersons:
    position = np.atleast_2d(np.asarray(position, float)).reshape(-1, 2)
    n = len(position)
    velocity = np.zeros((n, 2)) if velocity is None else np.atleast_2d(np.asarray(velocity, float))
    cov = np.tile(0.01 * np.eye(2), (n, 1, 1))
    return TrackedPersons(0.0, "odom", np.asarray(ids, np.int64), np.ones(n, bool), np.zeros(n, bool),
                          np.full(n, -1), position, velocity, cov, cov.copy(), np.zeros(n))


def tag_at(xy, pose=HERE) -> TagReading:
    """An exact reading of a tag at ``xy`` (odom) from ``pose``, with the default sensor's stated errors."""
    rel = np.asarray(xy, float) - pose[:2]
    return TagReading(0.0, float(np.hypot(*rel)), float(np.arctan2(rel[1], rel[0]) - pose[2]), 0.5,
                      np.radians(20.0))


class Recorder(StraightPlanner):
    """The straight planner, remembering the tracks and goal it was given."""

    def command(self, stamp, pose, velocity, obstacles, tracks, goal):
        self.tracks, self.goal = tracks, goal
        return super().command(stamp, pose, velocity, obstacles, tracks, goal)


def follower() -> PersonFollower:
    return PersonFollower(Recorder(**ROBOT))


def step(f, tracks, tag=None, pose=HERE):
    return f.command(0.0, pose, np.zeros(2), np.zeros((0, 2)), tracks, tag)


def test_picks_the_track_the_tag_agrees_with_and_drives_behind_it():
    f = follower()
    two = persons([4, 9], [[3.0, 1.5], [3.0, -1.5]])
    v, _ = step(f, two, tag_at([3.2, -1.3]))
    assert f.target_track == 9 and v > 0
    # the goal lies on the line from the robot to the person, short of them by the band's centre (1.5 m) less the
    # planner's goal tolerance (0.1 m: it stops that far short of its goal): the robot stops at the centre
    person = np.array([3.0, -1.5])
    np.testing.assert_allclose(f.planner.goal, person - 1.4 * person / np.hypot(*person))
    assert f.planner.tracks.track_id.tolist() == [4]  # the user is the goal, not a passer-by


def test_keeps_the_track_between_readings_and_reacquires_after_it_is_lost():
    f = follower()
    step(f, persons([4, 9], [[3.0, 1.5], [3.0, -1.5]]), tag_at([3.0, -1.5]))
    step(f, persons([4, 9], [[3.0, 1.2], [3.2, -1.0]]))  # no reading: the same track, wherever it goes
    assert f.target_track == 9
    step(f, persons([4], [[3.0, 1.2]]))  # the track is gone and nothing says where the user is
    assert f.target_track == -1
    v, _ = step(f, persons([4], [[3.0, 1.2]]))  # heads for where the user was last tracked (standing still)
    np.testing.assert_allclose(f.planner.goal, np.array([3.2, -1.0]) * (1 - 1.4 / np.hypot(3.2, -1.0)))
    assert v > 0
    step(f, persons([4, 12], [[3.0, 1.2], [3.4, -0.8]]))  # a new track, but no reading yet: not taken blindly
    assert f.target_track == -1
    step(f, persons([4, 12], [[3.0, 1.2], [3.4, -0.8]]), tag_at([3.3, -0.9]))
    assert f.target_track == 12


def test_a_reading_that_contradicts_the_track_while_agreeing_with_another_switches_to_it():
    # 80 deg apart as the robot sees them: 4 bearing sd, outside each other's gate
    f = follower()
    step(f, persons([4, 9], [[3.0, 2.5], [3.0, -2.5]]), tag_at([3.0, -2.5]))
    swapped = persons([4, 9], [[3.0, -2.5], [3.0, 2.5]])  # the tracker swapped the two ids
    step(f, swapped, tag_at([3.0, -2.5]))
    assert f.target_track == 9  # one reading may be off by chance
    step(f, swapped)  # no reading in between: the count of disagreeing readings stands
    step(f, swapped, tag_at([3.0, -2.5]))
    assert f.target_track == 4  # the second in a row: switched
    step(f, swapped, tag_at([3.0, 0.3]))  # nearer the other track, yet within the followed one's gate: it stays
    assert f.target_track == 4


def test_no_reading_of_anyone_far_from_every_track_is_followed():
    f = follower()
    step(f, persons([4], [[3.0, 1.5]]), tag_at([-3.0, -1.5]))
    assert f.target_track == -1
    assert step(PersonFollower(Recorder(**ROBOT)), persons([], np.zeros((0, 2)))) == (0.0, 0.0)


def test_sets_off_beyond_the_band_stops_at_its_centre_and_faces_the_user_within_it():
    f = follower()
    near = persons([9], [[1.2, 1.2]])  # 1.7 m away, within the band, to the left
    v, w = step(f, near, tag_at([1.2, 1.2]))
    assert v == 0.0 and w == pytest.approx(1.0 * (np.pi / 4) / (np.pi / 2))
    assert step(f, persons([9], [[2.5, 0.0]]))[0] > 0  # beyond 2 m: off it goes
    assert step(f, persons([9], [[1.8, 0.0]]))[0] > 0  # and on, until the band's centre
    assert step(f, persons([9], [[1.5, 0.0]])) == (0.0, 0.0)
    assert step(f, persons([9], [[1.9, 0.0]]))[0] == 0.0  # within the band again: it waits
    f.reset()
    assert f.target_track == -1 and step(f, persons([9], [[3.0, 0.0]])) == (0.0, 0.0)


def test_bad_band_refused():
    with pytest.raises(ValueError, match="band"):
        PersonFollower(Recorder(**ROBOT), band=(2.0, 1.0))


def test_a_lost_user_is_looked_for_where_they_were_going():
    f = follower()
    walking = TrackedPersons(0.0, "odom", np.array([9]), np.ones(1, bool), np.zeros(1, bool), np.full(1, -1),
                             np.array([[3.0, 0.0]]), np.array([[0.0, 0.5]]), np.tile(0.01 * np.eye(2), (1, 1, 1)),
                             np.tile(0.01 * np.eye(2), (1, 1, 1)), np.zeros(1))
    f.command(10.0, HERE, np.zeros(2), np.zeros((0, 2)), walking, tag_at([3.0, 0.0]))
    gone = persons([], np.zeros((0, 2)))
    # short of her by the band's centre less what braking at 0.5 m/s leaves behind a moving goal: 0.5^2 / (2 x 0.5)
    # plus the goal tolerance, 0.1 m
    aim = 1.5 - 0.25 - 0.1
    f.command(12.0, HERE, np.zeros(2), np.zeros((0, 2)), gone, None)  # 2 s on at 0.5 m/s: (3, 1)
    expected = np.array([3.0, 1.0])
    np.testing.assert_allclose(f.planner.goal, expected * (1 - aim / np.hypot(*expected)))
    f.command(20.0, HERE, np.zeros(2), np.zeros((0, 2)), gone, None)  # at most predict_time (3 s) on: (3, 1.5)
    expected = np.array([3.0, 1.5])
    np.testing.assert_allclose(f.planner.goal, expected * (1 - aim / np.hypot(*expected)))


def test_of_the_tracks_a_coarse_reading_agrees_with_it_takes_the_one_where_the_user_is_expected():
    f = follower()
    step(f, persons([9], [[3.0, 0.0]]), tag_at([3.0, 0.0]))
    assert f.target_track == 9
    # her track is lost; two new ones, both within the reading's gate (20 deg bearing sd at 3 m: +-1 m each sd)
    two = persons([21, 22], [[3.0, 0.6], [3.1, 0.05]])
    step(f, two, tag_at([3.0, 0.6]))  # the reading is nearer the passer-by, 21
    assert f.target_track == 22  # but 22 is where she was last seen
