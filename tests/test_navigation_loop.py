"""Navigation in the loop: the driver keys (validated, with one error naming the file and key), the goals and follow
drivers stepping the planner and the follower on what the robot has, the run directory's navigation files read back
by ``read_nav_run``, and ``crowdsim navigate``. Small rooms, few people, short runs."""

import json
import math

import numpy as np
import pytest
import yaml

from crowdsim.cli import main
from crowdsim.loop import Simulation
from crowdsim.navigate import episode_metrics, with_planner
from crowdsim.run import run
from evaluation.navigation import navigation_metrics, read_nav_run
from pipeline.navigation.planners import NDPlanner, build_planner
from scenarios import ScenarioError, load_scenario
from scenarios.format import TAG

LASERS = [{"name": "front_laser", "mount": [0.25, 0, 0]}, {"name": "rear_laser", "mount": [-0.25, 0, math.pi]}]


def room(size=(12.0, 8.0), **robot) -> dict:
    """An empty walled room, two lasers, no random force, the robot with ``robot``'s keys."""
    w, h = size
    return {"name": "nav_room", "seed": 1, "duration": 20.0, "crowd": {"random_force": 0.0},
            "map": {"walls": [[[0, 0], [w, 0], [w, h], [0, h], [0, 0]]]},
            "robot": {"start": [1.5, 4.0, 0.0], **robot}, "sensors": {"lasers": LASERS}}


def goals_room(**robot) -> dict:
    return room(**{"driver": "goals", "goals": [[10.5, 4.0]], **robot})


def follow_room(duration=20.0, **follow) -> dict:
    """A long hall; the target appears 1.5 m ahead of the robot and walks straight on at 0.45 m/s."""
    data = room((30.0, 8.0), start=[2.0, 4.0, 0.0], driver="follow",
                follow={"target": {"start": [3.5, 4.0], "route": "line", "speed": 0.45}, **follow})
    data.update(duration=duration, waypoints={"end": {"position": [28.0, 4.0]}}, routes={"line": {"waypoints":
                                                                                                    ["end"]}})
    data["sensors"]["tag"] = {}
    return data


def load(tmp_path, data: dict, name="nav.yaml") -> dict:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return load_scenario(str(path))


def refused(tmp_path, data: dict, key: str, *words: str) -> str:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    message = str(info.value)
    assert info.value.key == key and message.startswith(f"{path}: {key}: "), message
    for word in words:
        assert word in message, (word, message)
    return message


# ---- the keys ----

def _drop(data, *path):
    d = data
    for key in path[:-1]:
        d = d[key]
    del d[path[-1]]
    return data


@pytest.mark.parametrize("make, key, words", [
    (lambda: room(driver="goals"), "robot.goals", ("missing", "robot.driver is goals")),
    (lambda: room(driver="goals", goals=[[10.5, 4.0], [11.9, 4.0]]), "robot.goals[1]",
     ("inside a wall", "robot.radius")),
    (lambda: room(driver="drive"), "robot.driver", ("route, goals, follow, script",)),
    (lambda: room(driver="script"), "robot.script", ("[duration, v, omega]", "robot.driver is script")),
    (lambda: room(driver="script", script=[[0.0, 0.1, 0.0]]), "robot.script", ("s > 0",)),
    (lambda: goals_room(goal_radius=0.0), "robot.goal_radius", ("greater than 0",)),
    (lambda: goals_room(planner={"type": "zigzag"}), "robot.planner.type", ("zone, nd, straight, social_force",)),
    (lambda: goals_room(planner={"type": "nd", "zone_reach": 2.0}), "robot.planner.zone_reach", ("unknown key",)),
    (lambda: goals_room(planner={"type": "zone", "zone_reach": -1.0}), "robot.planner.zone_reach",
     ("greater than 0",)),
    (lambda: _drop(follow_room(), "robot", "follow"), "robot.follow.target", ("missing", "robot.driver is follow")),
    (lambda: _drop(follow_room(), "robot", "follow", "target"), "robot.follow.target", ("missing",)),
    (lambda: follow_room(band=[2.0, 1.0]), "robot.follow.band", ("0 < near < far",)),
    (lambda: _drop(follow_room(), "sensors", "tag"), "sensors.tag", ("missing", "tag")),
    (lambda: _drop(follow_room(), "robot", "follow", "target", "speed"), "robot.follow.target.speed",
     ("missing required key",)),
])
def test_bad_driver_keys_are_one_error_naming_the_file_and_key(tmp_path, make, key, words):
    refused(tmp_path, make(), key, *words)


def test_a_follow_target_on_an_unknown_route_or_too_fast_or_in_a_wall_is_refused(tmp_path):
    data = follow_room()
    data["robot"]["follow"]["target"]["route"] = "lap"
    refused(tmp_path, data, "robot.follow.target.route", "unknown route 'lap'", "line")
    data = follow_room()
    data["robot"]["follow"]["target"]["speed"] = 0.6  # the robot's max_speed
    refused(tmp_path, data, "robot.follow.target.speed", "below robot.max_speed", "keep up")
    data = follow_room()
    data["robot"]["follow"]["target"]["start"] = [3.5, 7.9]
    refused(tmp_path, data, "robot.follow.target.start", "inside a wall")


def test_driver_defaults_and_the_tag_defaults(tmp_path):
    sc = load(tmp_path, room())
    robot = sc["robot"]
    assert robot["driver"] == "route" and robot["goals"] is None and robot["follow"] is None
    assert robot["goal_radius"] == 0.3 and robot["planner"]["type"] == "zone"
    assert sc["sensors"]["tag"] is None
    follow = load(tmp_path, follow_room())
    assert follow.robot.follow.band == (1.0, 2.0)
    assert follow.sensors.tag == {k: f.default for k, f in TAG.fields.items()}


# ---- the loop ----

def test_goals_driver_reaches_its_goals_in_an_empty_room_within_the_robot_limits(tmp_path):
    data = goals_room(goals=[[6.0, 5.5], [10.5, 4.0]])
    sc = load(tmp_path, data)
    sim = Simulation(sc)
    p = sc["robot"]
    previous = np.zeros(2)
    stamps = []
    for _ in range(int(30 / sc["dt"])):
        frame = sim.step()
        v, omega = sim.robot.velocity
        assert abs(v) <= p["max_speed"] + 1e-12 and abs(omega) <= p["max_angular_speed"] + 1e-12
        assert abs(v - previous[0]) <= p["max_acceleration"] * sc["dt"] + 1e-12
        assert abs(omega - previous[1]) <= p["max_angular_acceleration"] * sc["dt"] + 1e-12
        previous = sim.robot.velocity.copy()
        if frame is not None:
            stamps.append(frame.stamp)
            if frame.goal is not None:
                assert frame.goal.tolist() in data["robot"]["goals"]
        if sim.finished:
            break
    assert sim.finished and sim.driver.goal_index == 2
    assert np.hypot(*(sim.robot.pose[:2] - [10.5, 4.0])) <= p["goal_radius"]
    assert sim.collision_ticks == 0 and sim.first_collision is None
    assert 15 < stamps[-1] < 30  # 10 m at 0.6 m/s at best
    # the frames stop at the last goal
    sim.reset()
    frames = list(sim.frames(60.0))
    assert sim.finished and frames[-1].stamp == pytest.approx(stamps[-1])


def test_a_collision_is_recorded_the_tick_it_happens(tmp_path):
    sc = load(tmp_path, goals_room())
    sim = Simulation(sc)
    for _ in range(int(25 / sc["dt"])):
        sim.step((0.6, 0.0))  # a caller's command, straight into the east wall at x = 12
    assert sim.collision_ticks > 0
    # the disc first overlaps the wall when the centre is within the radius of it: 12 - 0.425 - 1.5 = 10.075 m on
    assert sim.first_collision is not None and 10.075 / 0.6 < sim.first_collision < 10.075 / 0.6 + 2.0


def test_the_follower_keeps_a_target_walking_a_straight_line_in_its_band(tmp_path):
    sc = load(tmp_path, follow_room(duration=24.0))
    sim = Simulation(sc)
    distances, tracked, seen = [], [], []
    for frame in sim.frames(sc["duration"]):
        assert frame.target_id == sim.target_id == 1
        target = frame.agents.position[frame.agents.id == 1][0]
        distances.append((frame.stamp, np.hypot(*(target - frame.robot_pose[:2]))))
        tracked.append(frame.target_track)
        seen.append(frame.target_visible)
    t, d = np.array(distances).T
    settled = t > 6.0  # it sets off once she is beyond 2 m, reaches 0.45 m/s and falls in behind her
    assert (d[settled] >= 1.0).all() and (d[settled] <= 2.0).all(), d[settled].round(2)
    assert all(seen)
    assert tracked[-1] != -1 and len(set(tracked[len(tracked) // 2:])) == 1  # one track, kept


# ---- outputs ----

def _same(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        x, y = float(a[key]), float(b[key])
        assert (math.isnan(x) and math.isnan(y)) or x == y, (key, x, y)


def test_goal_run_writes_navigation_files_that_read_back_as_its_metrics(tmp_path):
    sc = load(tmp_path, goals_room())
    metrics = run(sc, tmp_path / "out", progress=False)
    out = tmp_path / "out"
    assert {"persons.csv", "navigation.json"} <= {p.name for p in out.iterdir()}
    assert not (out / "following.csv").exists()
    spec = json.loads((out / "navigation.json").read_text())
    assert spec["task"] == "goal" and spec["goal"] == [10.5, 4.0] and spec["goal_radius"] == 0.3
    assert spec["time_limit"] == 20.0 and len(spec["walls"]) == 4
    episode = read_nav_run(out)
    _same(navigation_metrics(episode), metrics["navigation"])
    assert metrics["navigation"]["success"] and metrics["duration_s"] < 20.0  # ended at the goal
    saved = json.loads((out / "metrics.json").read_text())["navigation"]
    assert saved["success"] is True and saved["min_distance"] is None  # nobody around: inf, JSON's null


def test_follow_run_writes_persons_and_following_that_read_back(tmp_path):
    sc = load(tmp_path, follow_room(duration=6.0))
    metrics = run(sc, tmp_path / "out", progress=False)
    out = tmp_path / "out"
    spec = json.loads((out / "navigation.json").read_text())
    assert spec["task"] == "follow" and spec["target_id"] == 1 and spec["band"] == [1.0, 2.0]
    following = np.loadtxt(out / "following.csv", delimiter=",", skiprows=1)
    robot = np.loadtxt(out / "robot.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(following[:, 0], robot[:, 0])
    persons = np.loadtxt(out / "persons.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(persons) == len(robot) and (persons[:, 2] == 1).all() and (persons[:, 7] == 0.25).all()
    episode = read_nav_run(out)
    assert episode.task == "follow" and (episode.target_visible).all()
    _same(navigation_metrics(episode), metrics["navigation"])


def test_a_route_run_writes_no_navigation_files(tmp_path):
    sc = load(tmp_path, {**room(route=[[3.0, 4.0], [9.0, 4.0]]), "duration": 2.0})
    metrics = run(sc, tmp_path / "out", progress=False)
    assert "navigation" not in metrics
    assert not {"persons.csv", "navigation.json", "following.csv"} & {p.name for p in (tmp_path / "out").iterdir()}


# ---- crowdsim navigate ----

def test_navigate_prints_the_table_and_writes_json(tmp_path, capsys):
    path = tmp_path / "nav.yaml"
    path.write_text(yaml.safe_dump(goals_room()))
    out = tmp_path / "nav.json"
    assert main(["navigate", str(path), "--planner", "straight", "--seeds", "2", "--duration", "20", "--json",
                 str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "planner straight, seeds 1..2" in printed and "2/2 successes, 0 collisions" in printed
    assert "| mean of 2 |" in printed and "| sd |" in printed
    saved = json.loads(out.read_text())
    assert saved["seeds"] == [1, 2] and saved["counts"]["successes"] == 2 and len(saved["runs"]) == 2
    assert saved["planner"]["type"] == "straight"
    # an existing --json file is refused before anything runs
    assert main(["navigate", str(path), "--planner", "straight", "--seeds", "1", "--json", str(out),
                 "--quiet"]) == 2
    assert "already exists" in capsys.readouterr().err


def test_navigate_prints_the_same_table_on_two_workers_and_on_ray(tmp_path, capsys):
    path = tmp_path / "nav.yaml"
    path.write_text(yaml.safe_dump(goals_room()))
    tables = []
    for engine in ([], ["--workers", "2"], ["--workers", "2", "--ray"]):
        assert main(["navigate", str(path), "--planner", "straight", "--seeds", "2", "--duration", "5", "--quiet",
                     *engine]) == 0
        tables.append(capsys.readouterr().out)
    assert tables[0] == tables[1] == tables[2] and "seeds 1..2" in tables[0]


def test_navigate_without_planner_keeps_the_scenarios_own_and_with_another_takes_its_defaults(tmp_path):
    path = tmp_path / "nav.yaml"
    path.write_text(yaml.safe_dump(goals_room(planner={"type": "zone", "zone_reach": 2.5})))
    sc = load_scenario(path)
    assert with_planner(sc, None)["robot"]["planner"] == sc["robot"]["planner"]
    assert with_planner(sc, None)["robot"]["planner"]["zone_reach"] == 2.5
    assert with_planner(sc, "zone")["robot"]["planner"]["zone_reach"] == 2.5
    nd = with_planner(sc, "nd")["robot"]["planner"]
    assert nd["type"] == "nd" and "zone_reach" not in nd


def test_navigate_refuses_a_route_scenario_and_an_unknown_planner(tmp_path, capsys):
    path = tmp_path / "route.yaml"
    path.write_text(yaml.safe_dump(room(route=[[3.0, 4.0], [9.0, 4.0]])))
    assert main(["navigate", str(path), "--planner", "zone", "--seeds", "1", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"crowdsim: error: {path}: robot.driver: route") and "expected goals or follow" in err
    path.write_text(yaml.safe_dump(goals_room()))
    assert main(["navigate", str(path), "--planner", "zigzag", "--seeds", "1", "--quiet"]) == 2
    assert "robot.planner.type" in capsys.readouterr().err


def test_same_seed_same_navigation_metrics(tmp_path):
    data = follow_room(duration=8.0)
    data.update(sources=[{"position": [10.0, 1.0], "size": [4.0, 1.0], "rate": 1.0, "routes": {"up": 1.0}}],
                routes={"line": {"waypoints": ["end"]}, "up": {"waypoints": ["top"]}})
    data["waypoints"]["top"] = {"position": [10.0, 7.2]}
    sim = Simulation(load(tmp_path, data))
    a = episode_metrics(sim, 3, 8.0)
    b = episode_metrics(sim, 3, 8.0)
    c = episode_metrics(Simulation(load(tmp_path, data, "again.yaml")), 3, 8.0)
    _same(a, b)
    _same(a, c)


def test_the_script_driver_turns_the_robot_in_place_in_the_loop(tmp_path):
    # seed 003's KTP rotation: 0.11 rad/s in place; 2 s at the default angular acceleration (1.5 rad/s^2: full speed
    # after 0.073 s, 0.004 rad short of 0.22), then the script ends and the robot stops (0.004 rad more)
    sim = Simulation(load(tmp_path, room(driver="script", script=[[2.0, 0.0, 0.11]], loop=False)))
    list(sim.frames(3.0))
    np.testing.assert_allclose(sim.robot.pose[:2], [1.5, 4.0], atol=1e-12)
    assert sim.robot.pose[2] == pytest.approx(0.22, abs=0.01)
    assert sim.robot.velocity.tolist() == [0.0, 0.0]


def test_a_built_in_planner_gets_the_robots_radius_and_limits_besides_its_own_keys(tmp_path):
    sc = load(tmp_path, goals_room(radius=0.3, max_speed=0.4, planner={"type": "nd", "sectors": 120}))
    assert list(sc["robot"]["planner"]) == ["type", "goal_tolerance", "stop_margin", "security_distance", "sectors",
                                            "wide_fraction"]  # the robot's keys are the robot's
    planner = build_planner(sc["robot"]["planner"], sc["robot"])
    assert type(planner) is NDPlanner and planner.nd.n == 120
    assert (planner.radius, planner.max_speed, planner.max_angular_speed, planner.max_acceleration) == (0.3, 0.4,
                                                                                                        1.0, 0.5)
