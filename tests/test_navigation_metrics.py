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
