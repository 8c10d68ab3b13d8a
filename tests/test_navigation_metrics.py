"""evaluation/navigation.py on hand-worked trajectories: outcomes, path, smoothness, social distances, time to
collision, social work, passers-by crossings, following; the run-directory loader, its errors, and
``crowdsim evaluate-nav``."""

import json
import math

import numpy as np
import pytest

from crowdsim.cli import main
from evaluation.io import EvaluationInputError
from evaluation.navigation import NavEpisode, PersonRows, navigation_metrics, read_nav_run, social_force
from test_cli import one_error_line


def episode(stamp, xy, yaw=None, persons=(), walls=(), task="goal", goal=(100.0, 0.0), goal_radius=0.1,
            time_limit=100.0, robot_radius=0.3, **following):
    """An episode from the robot's positions and person rows (frame, id, x, y, vx, vy, radius)."""
    xy = np.asarray(xy, float)
    yaw = np.zeros(len(xy)) if yaw is None else np.asarray(yaw, float)
    rows = np.asarray(persons, float).reshape(-1, 7)
    people = PersonRows(rows[:, 0], rows[:, 1], rows[:, 2:4], rows[:, 4:6], rows[:, 6])
    return NavEpisode(stamp=np.asarray(stamp, float), robot_pose=np.column_stack([xy, yaw]),
                      robot_radius=robot_radius, persons=people, walls=np.asarray(walls, float).reshape(-1, 2, 2),
                      task=task, time_limit=time_limit, goal=None if task == "follow" else goal,
                      goal_radius=goal_radius, **following)


def line(x, y=0.0):
    return np.column_stack([x, np.full(len(x), y)])


def test_head_on_collision_with_a_person_ends_the_episode_at_its_frame():
    # dt 0.5 s; robot (r 0.3) from x = 0 at +1 m/s, person 7 (r 0.3) from x = 4 at -1 m/s; the log goes on after
    # centre distances 4, 3, 2, 1, 0 -> gaps 3.4, 2.4, 1.4, 0.4, -0.6: the collision is frame 4 (x = 2)
    t = np.arange(7) * 0.5
    x = np.arange(7) * 0.5
    people = [(k, 7, 4 - x[k], 0, -1, 0, 0.3) for k in range(7)]
    m = navigation_metrics(episode(t, line(x), persons=people, goal=(10.0, 0.0)))
    assert m["collision_person"] and not m["collision_wall"]
    assert not (m["success"] or m["timeout"] or m["ended_early"])
    assert math.isnan(m["time_to_goal"])
    assert m["path_length"] == pytest.approx(2.0)  # frames 0-4 only: the episode ended at the collision
    assert m["min_distance"] == pytest.approx(-0.6)
    # smallest gaps per frame 3.4, 2.4, 1.4, 0.4, -0.6: < 0.2 in 1 of 5 frames, < 0.45 in 2, [0.45, 1.2) in none
    assert m["discomfort_frequency"] == pytest.approx(0.2)
    assert m["intimate_share"] == pytest.approx(0.4)
    assert m["personal_share"] == 0.0
    assert m["min_time_to_collision"] == 0.0  # overlapping in frame 4


def test_wall_collision_and_segment_ends():
    # robot (r 0.3) along y = 0 at 1 m/s, dt 0.5 s; wall x = 2.5 for y in [-1, 1]: centre distances 2.5, 2, 1.5,
    # 1, 0.5, 0 -> gap -0.3 first at frame 5 (x = 2.5); a wall on the line x = 1 but only for y in [5, 10] is 5 m
    # from (1, 0), never touched
    t = np.arange(8) * 0.5
    x = np.arange(8) * 0.5
    m = navigation_metrics(episode(t, line(x), walls=[[[2.5, -1], [2.5, 1]], [[1, 5], [1, 10]]]))
    assert m["collision_wall"] and not m["collision_person"] and not m["success"]
    assert m["path_length"] == pytest.approx(2.5)
    assert m["min_distance"] == math.inf and m["min_time_to_collision"] == math.inf  # nobody around


@pytest.mark.parametrize("offset, gap, discomfort", [(0.8, 0.3, 0 / 11), (0.65, 0.15, 1 / 11)])
def test_passing_a_standing_person(offset, gap, discomfort):
    # robot (r 0.3) along y = 0 at 0.8 m/s, dt 0.5 s: x = 0, 0.4, ..., 4 (11 frames); standing person (r 0.2) at
    # (2, offset). dx = x - 2 in {0, +-0.4, +-0.8, +-1.2, +-1.6, +-2}; gap = sqrt(dx^2 + offset^2) - 0.5:
    # offset 0.8:  dx 0: 0.300, 0.4: 0.394, 0.8: 0.631, 1.2: 0.942, 1.6: 1.289, 2: 1.654
    # offset 0.65: dx 0: 0.150, 0.4: 0.263, 0.8: 0.531, 1.2: 0.865, 1.6: 1.227, 2: 1.662
    # intimate (< 0.45): dx 0, +-0.4 = 3 frames; personal: +-0.8, +-1.2 = 4; discomfort (< 0.2): only offset 0.65's
    # dx 0. The goal (4, 0) is reached at frame 10: t = 5 s over 4 m, no turning.
    t = np.arange(11) * 0.5
    x = np.arange(11) * 0.4
    people = [(k, 1, 2.0, offset, 0, 0, 0.2) for k in range(11)]
    m = navigation_metrics(episode(t, line(x), persons=people, goal=(4.0, 0.0)))
    assert m["success"] and not (m["collision_person"] or m["timeout"] or m["ended_early"])
    assert m["time_to_goal"] == pytest.approx(5.0)
    assert m["path_length"] == pytest.approx(4.0)
    assert m["path_irregularity"] == 0.0
    assert m["min_distance"] == pytest.approx(gap)
    assert m["discomfort_frequency"] == pytest.approx(discomfort)
    assert m["intimate_share"] == pytest.approx(3 / 11)
    assert m["personal_share"] == pytest.approx(4 / 11)
    # the person stands; the robot passes them with a centre offset above the 0.5 m of both radii: never touches
    assert m["min_time_to_collision"] == math.inf
    assert m["crossings_front"] == m["crossings_behind"] == 0  # a standing person has no path to cross


def test_acceleration_step_gives_the_jerk():
    # dt 0.1 s; x = 0, 0, 0, 0.1, 0.2, 0.3: speeds per interval 0, 0, 1, 1, 1 m/s; accelerations 0, 10, 0, 0 m/s^2
    # (mean |a| 2.5, peak 10); jerks 100, -100, 0 m/s^3 (mean 66.67, peak 100). The yaw does the same across the
    # wrap at pi: 3.1, 3.1, 3.1, 3.2 - 2 pi, 3.3 - 2 pi, 3.4 - 2 pi: rates 0, 0, 1, 1, 1 rad/s.
    t = np.arange(6) * 0.1
    x = np.array([0, 0, 0, 0.1, 0.2, 0.3])
    yaw = np.array([3.1, 3.1, 3.1, 3.2 - 2 * np.pi, 3.3 - 2 * np.pi, 3.4 - 2 * np.pi])
    m = navigation_metrics(episode(t, line(x), yaw))
    for kind in ("linear", "angular"):
        assert m[f"mean_{kind}_acceleration"] == pytest.approx(2.5)
        assert m[f"peak_{kind}_acceleration"] == pytest.approx(10.0)
        assert m[f"mean_{kind}_jerk"] == pytest.approx(200 / 3)
        assert m[f"peak_{kind}_jerk"] == pytest.approx(100.0)


def test_path_irregularity_is_the_unnecessary_turning_per_metre():
    # x = 0, 1, 2, 3 along y = 0 to the goal (10, 0), yaw 0.3, 0.5, -0.5, 0: turned 0.2 + 1.0 + 0.5 = 1.7 rad; the
    # straight path needs 0.3 (turn to face the goal), so (1.7 - 0.3) / 3 m
    m = navigation_metrics(episode(np.arange(4.0), line(np.arange(4.0)), [0.3, 0.5, -0.5, 0.0], goal=(10.0, 0.0)))
    assert m["path_irregularity"] == pytest.approx(1.4 / 3)


@pytest.mark.parametrize("person, ttc", [
    # on the robot's line: centre distances 5, 4, 3 closing at 2 m/s, radii 0.3 + 0.2: (d - 0.5) / 2
    ((5.0, 0.0), 1.25),
    # 0.3 m off the line, 6 m ahead: (dx - 2 tau)^2 + 0.3^2 = 0.5^2 -> tau = (dx - 0.4) / 2 with dx = 6, 5, 4
    ((6.0, 0.3), 1.8),
])
def test_constant_velocity_time_to_collision(person, ttc):
    # dt 0.5 s; robot at +1 m/s from x = 0, the person at -1 m/s; a third person walking away never collides
    t = np.arange(3) * 0.5
    x = t.copy()
    people = [(k, 1, person[0] - t[k], person[1], -1, 0, 0.2) for k in range(3)]
    people += [(k, 2, -3 - t[k], 0, -1, 0, 0.2) for k in range(3)]
    m = navigation_metrics(episode(t, line(x), persons=people))
    assert m["min_time_to_collision"] == pytest.approx(ttc)
    assert m["ended_early"]  # one second of a 100 s time limit, no goal, no collision


def test_social_force_and_social_work():
    # both still, 1 m apart: I = e, |I| = 1, B = 0.35, theta = 0: the force on b points away from a with
    # 2.1 exp(-1 / 0.35) = 0.1206 m/s^2
    f = social_force(np.array([[1.0, 0.0]]), np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2)))
    assert f[0] == pytest.approx([-2.1 * math.exp(-1 / 0.35), 0.0])
    # a still robot and a still person 1 m apart for 2 s (3 frames), no walls: per frame the force each way,
    # 2 * 0.1206; integrated over 2 s: 4 * 2.1 exp(-1 / 0.35) = 0.4825 m/s
    people = [(k, 1, 1.0, 0.0, 0, 0, 0.2) for k in range(3)]
    m = navigation_metrics(episode(np.arange(3.0), line(np.zeros(3)), persons=people))
    assert m["social_work"] == pytest.approx(4 * 2.1 * math.exp(-1 / 0.35))


def test_crossings_in_front_behind_and_alongside():
    # dt 0.25 s, 15 frames (t = 0 ... 3.5); robot (r 0.3) along x = 0 at +1 m/s from y = -1.5, persons r 0.25:
    # it is on a side of a person's path when |lateral| >= 0.55 m.
    # Person 1 walks +x along y = 0 from x = -3: robot - person = (3 - t, t - 1.5); last on the right at
    # t = 0.75 (x 2.25, y -0.75), first on the left at t = 2.25 (x 0.75, y 0.75): crossed at x = 1.5 > 0, in front.
    # Person 2 walks +x along y = 1 from x = 0.5: (-0.5 - t, t - 2.5); t = 1.75 (x -2.25, y -0.75) to
    # t = 3.25 (x -3.75, y 0.75): crossed at x = -3.0, behind (within 3.6 m).
    # Person 3 walks 1 m ahead of the robot, jittering 0.2 m left and right: the lateral offset changes sign every
    # frame (14 naive crossings) but never leaves the 0.55 m strip: none. Person 4 walks beside the robot at
    # x = 0.7 +- 0.1: always on one side: none.
    t = np.arange(15) * 0.25
    ry = -1.5 + t
    jitter = np.where(np.arange(15) % 2, 0.2, -0.2)
    people = [(k, 1, -3 + t[k], 0.0, 1, 0, 0.25) for k in range(15)]
    people += [(k, 2, 0.5 + t[k], 1.0, 1, 0, 0.25) for k in range(15)]
    people += [(k, 3, jitter[k], ry[k] + 1.0, 0, 1, 0.25) for k in range(15)]
    people += [(k, 4, 0.7 + jitter[k] / 2, ry[k], 0, 1, 0.25) for k in range(15)]
    m = navigation_metrics(episode(t, np.column_stack([np.zeros(15), ry]), np.full(15, np.pi / 2), people,
                                   goal=(0.0, 100.0)))
    assert not (m["collision_person"] or m["collision_wall"])
    assert (m["crossings_front"], m["crossings_behind"]) == (1, 1)


def follow_episode(track, target_radius=0.1):
    # dt 1 s, 6 frames, time limit 6 s (the log covers it within one frame); still robot at the origin; target 5
    # at centre distances 1.5, 2.5, 0.5, 1.0, 2.0, 3.0 (radii 0.3 + 0.1: the 0.5 m is a gap of 0.1, no collision)
    d = [1.5, 2.5, 0.5, 1.0, 2.0, 3.0]
    people = [(k, 5, d[k], 0.0, 0, 0, target_radius) for k in range(6)]
    return episode(np.arange(6.0), np.zeros((6, 2)), persons=people, task="follow", time_limit=6.0, target_id=5,
                   band=(1.0, 2.0), target_track=np.array(track), target_visible=np.array([1, 1, 0, 0, 1, 1], bool))


def test_following_band_losses_and_reacquisition():
    m = navigation_metrics(follow_episode([-1, 3, -1, -1, 3, 8]))
    assert m["success"] and not (m["timeout"] or m["ended_early"])
    # within [1, 2] m (inclusive): 1.5, 1.0, 2.0 = 3 of 6; outside by 0, 0.5, 0.5, 0, 0, 1.0: mean 2 / 6
    assert m["in_band_share"] == pytest.approx(0.5)
    assert m["distance_error"] == pytest.approx(1 / 3)
    # the first -1 is no loss (never had it); lost at frame 2 (3 -> -1, back at frame 4: 2 s) and at frame 5
    # (3 -> 8, another track at once: 0 s)
    assert m["target_losses"] == 2
    assert m["mean_reacquire_time"] == pytest.approx(1.0)
    assert m["max_reacquire_time"] == pytest.approx(2.0)
    assert m["target_hidden_share"] == pytest.approx(2 / 6)
    # the target is no passer-by: the social figures see nobody (it came within a 0.1 m gap in frame 2)
    assert m["min_distance"] == math.inf and m["discomfort_frequency"] == 0.0
    assert math.isnan(m["path_irregularity"])
    # lost at frame 2 for good: counted until the last frame, 5 - 2 = 3 s, a lower bound
    m = navigation_metrics(follow_episode([3, 3, -1, -1, -1, -1]))
    assert (m["target_losses"], m["mean_reacquire_time"], m["max_reacquire_time"]) == (1, 3.0, 3.0)
    # a target of radius 0.25 is hit at frame 2 (gap 0.5 - 0.55): the episode is frames 0-2, 1 of 3 in the band
    # (1.5), outside by 0, 0.5, 0.5; lost at frame 2 and not back by then: 0 s
    m = navigation_metrics(follow_episode([3, 3, -1, -1, -1, -1], target_radius=0.25))
    assert m["collision_person"] and not m["success"]
    assert m["in_band_share"] == pytest.approx(1 / 3) and m["distance_error"] == pytest.approx(1 / 3)
    assert (m["target_losses"], m["max_reacquire_time"], m["target_hidden_share"]) == (1, 0.0, 1 / 3)


def write_run(run_dir, ep: NavEpisode):
    """The run-directory files of a follow episode (frames numbered from 10, to check the mapping to indices;
    numbers written exactly)."""
    run_dir.mkdir()
    frames = np.arange(len(ep.stamp)) + 10

    def csv(name, header, columns):
        rows = [",".join(repr(v.item()) for v in values) for values in zip(*columns)]
        (run_dir / name).write_text("\n".join([header, *rows]) + "\n")

    zero = np.zeros(len(frames))
    csv("robot.csv", "frame,t,x,y,yaw,odom_x,odom_y,odom_yaw", [frames, ep.stamp, *ep.robot_pose.T, zero, zero, zero])
    p = ep.persons
    csv("persons.csv", "frame,t,id,x,y,vx,vy,radius",
        [frames[p.frame], ep.stamp[p.frame], p.id, *p.position.T, *p.velocity.T, p.radius])
    csv("following.csv", "frame,t,target_track,target_visible",
        [frames, ep.stamp, ep.target_track, ep.target_visible.astype(int)])
    spec = {"task": ep.task, "goal": None, "goal_radius": None, "robot_radius": ep.robot_radius,
            "time_limit": ep.time_limit, "walls": ep.walls.reshape(-1, 4).tolist(), "target_id": ep.target_id,
            "band": list(ep.band)}
    (run_dir / "navigation.json").write_text(json.dumps(spec))


def test_run_directory_round_trip_and_evaluate_nav(tmp_path, capsys):
    ep = follow_episode([-1, 3, -1, -1, 3, 8])
    ep.walls = np.array([[[0.0, -5.0], [9.0, -5.0]]])
    write_run(tmp_path / "run", ep)
    back = read_nav_run(tmp_path / "run")
    for name in ("stamp", "robot_pose", "walls", "target_track", "target_visible"):
        np.testing.assert_array_equal(getattr(back, name), getattr(ep, name))
    for name in ("frame", "id", "position", "velocity", "radius"):
        np.testing.assert_array_equal(getattr(back.persons, name), getattr(ep.persons, name))
    assert (back.task, back.target_id, back.band, back.robot_radius, back.time_limit) == ("follow", 5, (1.0, 2.0),
                                                                                          0.3, 6.0)
    expected = navigation_metrics(ep)
    assert navigation_metrics(back) == pytest.approx(expected, nan_ok=True)

    # the same run twice: mean = the run's figure, sd 0; the JSON's NaN are null
    js = tmp_path / "nav.json"
    assert main(["evaluate-nav", str(tmp_path / "run"), str(tmp_path / "run"), "--json", str(js)]) == 0
    out = capsys.readouterr().out
    assert "| mean of 2 |" in out and "| sd |" in out and "in band [%]" in out
    data = json.loads(js.read_text())
    assert data["mean"]["in_band_share"] == pytest.approx(0.5) and data["sd"]["in_band_share"] == 0.0
    assert data["mean"]["success"] == 1.0
    assert data["runs"][0]["time_to_goal"] is None and data["runs"][0]["run_dir"] == str(tmp_path / "run")
    # an existing --json file is refused before anything is read
    assert main(["evaluate-nav", str(tmp_path / "run"), "--json", str(js)]) == 2
    assert "already exists" in one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("break_it, expect", [
    (lambda d: (d / "persons.csv").write_text("frame,t,id,x,y,vx,vy\n10,0,5,1,0,0,0\n"),
     "persons.csv: header 'frame,t,id,x,y,vx,vy' lacks column(s) radius"),
    (lambda d: (d / "following.csv").unlink(), "following.csv: cannot be read (No such file or directory)"),
    (lambda d: (d / "navigation.json").write_text('{"task": "follow", "robot_radius": 0.3, "time_limit": 6, '
                                                  '"target": 5}'),
     "navigation.json: unknown key(s) 'target'; expected only task, goal, goal_radius, robot_radius, time_limit, "
     "walls, target_id, band"),
    (lambda d: (d / "navigation.json").write_text('{"task": "goal", "robot_radius": 0.3, "time_limit": 6, '
                                                  '"goal": [1, 2], "goal_radius": -1}'),
     "navigation.json: key 'goal_radius' is -1; expected a number above 0"),
    (lambda d: (d / "persons.csv").write_text("frame,t,id,x,y,vx,vy,radius\n99,0,5,1,0,0,0,0.2\n"),
     "persons.csv: frame 99 is not in robot.csv; expected the frames of robot.csv"),
])
def test_bad_run_directory_gets_one_clear_error(tmp_path, capsys, break_it, expect):
    write_run(tmp_path / "run", follow_episode([-1, 3, -1, -1, 3, 8]))
    break_it(tmp_path / "run")
    with pytest.raises(EvaluationInputError) as e:
        read_nav_run(tmp_path / "run")
    assert expect in str(e.value)
    assert main(["evaluate-nav", str(tmp_path / "run")]) == 2
    assert expect in one_error_line(capsys.readouterr().err)


# ---- the kernels, on hand-worked values ----

def test_wall_distance_to_segments_and_a_zero_length_one():
    from evaluation.navigation import _wall_distance

    # the segment (0, 0)-(2, 0) and the point wall (5, 5): (1, 1) is 1 m above the segment's middle, (3, 1) sqrt 2
    # from its end (2, 0), (-1, 0) 1 m before its start, (5, 4) 1 m below the point (and 5 m from (2, 0))
    xy = np.array([[1.0, 1.0], [3.0, 1.0], [-1.0, 0.0], [5.0, 4.0]])
    d = _wall_distance(xy, np.array([[[0.0, 0.0], [2.0, 0.0]], [[5.0, 5.0], [5.0, 5.0]]]))
    assert d.tolist() == pytest.approx([1.0, math.sqrt(2), 1.0, 1.0])
    assert _wall_distance(xy, np.zeros((0, 2, 2))).tolist() == [math.inf] * 4


def test_person_gaps_and_the_least_per_frame():
    from evaluation.navigation import _person_gaps

    # robot (r 0.3) at (0, 0) in frame 0 and (1, 0) in frame 2; rows: frame 0 person at (2, 0) r 0.2 (gap 1.5),
    # frame 0 at (0, 1) r 0.2 (gap 0.5), frame 2 at (1, 3) r 0.5 (gap 2.2); frame 1 has nobody
    frame = np.array([0, 0, 2])
    gap, least = _person_gaps(frame, np.array([[2.0, 0.0], [0.0, 1.0], [1.0, 3.0]]), np.array([0.2, 0.2, 0.5]),
                              np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]]), 0.3, 3)
    assert gap.tolist() == pytest.approx([1.5, 0.5, 2.2])
    assert least.tolist() == pytest.approx([0.5, math.inf, 2.2])


def test_end_frames_median_interval_collision_and_goal():
    from evaluation.navigation import _end_frames

    # stamps 0, 1, 2, 4, 7 (intervals 1, 1, 2, 3: median (1 + 2) / 2 = 1.5); time limit 4 s: frames 0-3 within;
    # a person gap below 0 at frame 2, a wall gap below 0 at frame 1 (the first collision), the goal (3, 0)
    # within 0.5 m of frame 3's (3.2, 0) and of frame 4's, which is past the limit
    stamp = np.array([0.0, 1.0, 2.0, 4.0, 7.0])
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.2, 0.0], [3.0, 0.0]])
    person, wall = np.array([1.0, 1.0, -0.1, 1.0, 1.0]), np.array([1.0, -0.2, 1.0, 1.0, 1.0])
    assert _end_frames(stamp, xy, np.array([3.0, 0.0]), 0.5, 4.0, person, wall) == (3, 1.5, 1, 3)
    # no goal, no collision; an odd count of intervals (1, 1, 2: median 1)
    ok = np.ones(4)
    assert _end_frames(stamp[:4], xy[:4], np.zeros(0), 0.5, 10.0, ok, ok) == (3, 1.0, -1, -1)
    assert _end_frames(stamp[:1], xy[:1], np.zeros(0), 0.5, 10.0, ok[:1], ok[:1]) == (0, 0.0, -1, -1)


def test_path_length_turning_and_smoothness_kernel():
    from evaluation.navigation import SMOOTHNESS_KEYS, _path

    # dt 1 s; (0, 0) -> (3, 4) -> (3, 4) -> (3, 5): steps 5, 0, 1 m; yaw 3.0, -3.0 (a turn of 2 pi - 6 through pi),
    # -3.0, -2.5: turned 0.2832 + 0 + 0.5. Speeds 5, 0, 1 at t 0.5, 1.5, 2.5: accelerations -5, 1 (mean 3, peak 5)
    # at t 1, 2: jerk 6. Yaw rates 0.2832, 0, 0.5: accelerations -0.2832, 0.5, jerk 0.7832.
    pose = np.array([[0.0, 0.0, 3.0], [3.0, 4.0, -3.0], [3.0, 4.0, -3.0], [3.0, 5.0, -2.5]])
    out = _path(np.arange(4.0), pose, 4)
    w = 2 * math.pi - 6
    assert out[:2].tolist() == pytest.approx([6.0, w + 0.5])
    figures = dict(zip(SMOOTHNESS_KEYS, out[2:]))
    assert figures == pytest.approx({"mean_linear_acceleration": 3.0, "peak_linear_acceleration": 5.0,
                                     "mean_linear_jerk": 6.0, "peak_linear_jerk": 6.0,
                                     "mean_angular_acceleration": (w + 0.5) / 2, "peak_angular_acceleration": 0.5,
                                     "mean_angular_jerk": 0.5 + w, "peak_angular_jerk": 0.5 + w})
    one = _path(np.zeros(1), pose[:1], 1)  # one frame: no path, no rates
    assert one[:2].tolist() == [0.0, 0.0] and np.isnan(one[2:]).all()


def test_gradient_kernel_uniform_and_uneven_stamps():
    from evaluation.navigation import _gradient

    # x = t^2 at t = 0, 1, 2: central difference (4 - 0) / 2 = 2 inside, one-sided 1 and 3 at the ends
    xy = np.column_stack([np.array([0.0, 1.0, 4.0]), np.zeros(3)])
    assert _gradient(xy, np.array([0.0, 1.0, 2.0]), 3)[:, 0].tolist() == [1.0, 2.0, 3.0]
    # t = 0, 1, 3, x = t^2 (0, 1, 9): numpy's second-order formula at t = 1 with h1 = 1, h2 = 2 gives the exact
    # derivative 2 of a parabola; ends (1 - 0) / 1 = 1 and (9 - 1) / 2 = 4
    xy = np.column_stack([np.zeros(3), np.array([0.0, 1.0, 9.0])])
    assert _gradient(xy, np.array([0.0, 1.0, 3.0]), 3)[:, 1].tolist() == pytest.approx([1.0, 2.0, 4.0])


def test_time_to_collision_kernel():
    from evaluation.navigation import _time_to_collision

    # 3 m apart closing at 2 m/s, radii 1: (3 - 1) / 2 = 1 s; moving apart: never; overlapping: 0; standing: never
    assert _time_to_collision(3.0, 0.0, -2.0, 0.0, 1.0) == pytest.approx(1.0)
    assert _time_to_collision(3.0, 0.0, 2.0, 0.0, 1.0) == math.inf
    assert _time_to_collision(0.5, 0.0, 2.0, 0.0, 1.0) == 0.0
    assert _time_to_collision(3.0, 4.0, 0.0, 0.0, 1.0) == math.inf
    # 4 m ahead, 0.6 m off the line, closing at 1 m/s, radii 1: touch when the along-line offset is 0.8: 3.2 s
    assert _time_to_collision(4.0, 0.6, -1.0, 0.0, 1.0) == pytest.approx(3.2)


def test_social_kernel_counts_frames_by_their_least_gap():
    from evaluation.navigation import _social

    # four frames, the robot still at the origin; rows (frame, gap): (0, 0.1), (0, 0.3), (1, 0.3), (2, 1.0),
    # (3, 2.0) and a row of frame 1 left out of ``rows``. Least per frame 0.1, 0.3, 1.0, 2.0: below 0.2 once,
    # below 0.45 twice, in [0.45, 1.2) once
    frame = np.array([0, 0, 1, 1, 2, 3])
    gap = np.array([0.1, 0.3, -5.0, 0.3, 1.0, 2.0])
    pos, zero = np.column_stack([np.arange(2.0, 8.0), np.zeros(6)]), np.zeros((6, 2))
    out = _social(np.array([0, 1, 3, 4, 5]), frame, pos, zero, np.full(6, 0.2), gap, np.zeros((4, 2)),
                  np.zeros((4, 2)), 0.3, 4)
    assert out == (0.1, math.inf, 1, 2, 1)


def test_person_order_is_by_id_then_frame_whatever_the_rows_order():
    from evaluation.navigation import _by_person

    frame, ids = np.array([2, 0, 1, 0, 1, 2]), np.array([5, 5, 7, 7, 5, 7])
    # person 5 at frames 0, 1, 2 are rows 1, 4, 0; person 7 rows 3, 2, 5
    assert _by_person(np.arange(6), frame, ids).tolist() == [1, 4, 0, 3, 2, 5]
    assert _by_person(np.arange(6), frame, ids * 1000).tolist() == [1, 4, 0, 3, 2, 5]  # ids too far apart to count
    assert _by_person(np.array([5, 0]), frame, ids).tolist() == [0, 5]
    assert _by_person(np.zeros(0, np.int64), frame, ids).tolist() == []


def test_integrated_work_is_the_trapezoid_of_the_frames_work():
    from evaluation.navigation import _integrated_work

    # stamps 0, 1, 3; one person row in frames 0 and 2 (forces on the robot (3, 4) and (0, 1), the robot's on them
    # of size 1 and 2), obstacle forces 1, 2, 0: work 5 + 1 + 1 = 7, 2, 1 + 0 + 2 = 3; area 1 (7 + 2) / 2 +
    # 2 (2 + 3) / 2 = 9.5
    force = np.array([[3.0, 4.0], [0.0, 1.0], [1.0, 0.0], [0.0, 2.0]])
    assert _integrated_work(np.array([0.0, 1.0, 3.0]), force, np.array([0, 1]), np.array([0, 2]),
                            np.array([1.0, 2.0, 0.0])) == pytest.approx(9.5)


def test_social_force_rows_must_pair():
    with pytest.raises(ValueError, match="as many rows"):
        social_force(np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((1, 2)), np.zeros((2, 2)))
