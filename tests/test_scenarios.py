"""Scenario files: every fault gives one ScenarioError naming the file, the key path and what was expected.

Each test writes a small YAML file into ``tmp_path`` the way a user would and loads it with ``load_scenario``.
"""

import copy
import math

import pytest
import yaml

from scenarios import ScenarioError, bundled_scenarios, load_scenario
from scenarios.format import CROWD, SCENARIO

# A valid 20 m x 20 m room: two goals, one route, one source, a parked robot, two lasers.
BASE = {
    "name": "tiny_room",
    "duration": 5.0,
    "map": {"walls": [[[0, 0], [20, 0], [20, 20], [0, 20], [0, 0]]]},
    "waypoints": {"a": {"position": [3, 10]}, "b": {"position": [17, 10], "radius": 0.5}},
    "routes": {"r": {"waypoints": ["a", "b"]}},
    "sources": [{"position": [3, 10], "rate": 1.0, "routes": {"r": 1.0}}],
    "robot": {"start": [10, 3, 0]},
    "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]},
                           {"name": "rear_laser", "mount": [-0.25, 0, math.pi]}]},
}


def base() -> dict:
    return copy.deepcopy(BASE)


def write(tmp_path, data, name="scenario.yaml"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def expect_error(path, key, *words, **overrides) -> str:
    """Load ``path``; check the one ScenarioError names the file and ``key`` and says ``words``; return its text."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path), **overrides)
    e = info.value
    message = str(e)
    assert isinstance(e, ValueError)
    assert e.source == str(path)
    assert e.key == key
    assert message.startswith(f"{path}: {key}: "), message
    for w in words:
        assert w in message, (w, message)
    return message


def test_valid_base_loads(tmp_path):
    path = write(tmp_path, base())
    sc = load_scenario(str(path))
    assert sc["name"] == "tiny_room"
    assert sc["source"] == str(path)


# --- unknown keys ------------------------------------------------------------------------------------------------

def test_unknown_top_level_key(tmp_path):
    data = base()
    data["durration"] = 3
    path = write(tmp_path, data)
    message = expect_error(path, "durration", "unknown key", "expected one of:")
    assert "\n" not in message
    listed = message.split("expected one of:")[1]
    for name in SCENARIO.fields:
        assert name in listed


def test_unknown_nested_key(tmp_path):
    data = base()
    data["crowd"] = {"radiuss": 0.3}
    path = write(tmp_path, data)
    message = expect_error(path, "crowd.radiuss", "unknown key", "expected one of:")
    listed = [k.strip() for k in message.split("expected one of:")[1].split(",")]
    assert listed == list(CROWD.fields)
    assert "agent_types" in listed


def test_unknown_key_inside_a_list_item(tmp_path):
    data = base()
    data["sensors"]["lasers"][1]["heigth"] = 0.7
    path = write(tmp_path, data)
    expect_error(path, "sensors.lasers[1].heigth", "unknown key", "expected one of:", "height", "fov_deg")


# --- wrong types -------------------------------------------------------------------------------------------------

def _set_duration(d, v):
    d["duration"] = v


def _set_rate(d, v):
    d["sources"][0]["rate"] = v


def _set_position(d, v):
    d["waypoints"]["a"]["position"] = v


def _set_start(d, v):
    d["robot"]["start"] = v


@pytest.mark.parametrize("setter, value, key, words", [
    (_set_duration, "long", "duration", ("expected a number", "'long'")),
    (_set_duration, True, "duration", ("expected a number", "True")),
    (_set_rate, [1], "sources[0].rate", ("expected a number", "list")),
    (_set_position, [1, 2, 3], "waypoints.a.position", ("expected a point [x, y]", "a list of 2 numbers")),
    (_set_position, [1, "x"], "waypoints.a.position", ("expected a point [x, y]", "a list of 2 numbers")),
    (_set_start, [1, 2], "robot.start", ("expected a pose [x, y, yaw]", "a list of 3 numbers")),
], ids=["duration-str", "duration-bool", "rate-list", "point-3-numbers", "point-str", "pose-2-numbers"])
def test_wrong_type(tmp_path, setter, value, key, words):
    data = base()
    setter(data, value)
    path = write(tmp_path, data)
    message = expect_error(path, key, *words)
    assert "\n" not in message


def test_wrong_type_for_a_section(tmp_path):
    data = base()
    data["crowd"] = [1, 2]
    path = write(tmp_path, data)
    expect_error(path, "crowd", "expected a mapping of keys", "list")


def test_wrong_int(tmp_path):
    data = base()
    data["seed"] = 1.5
    path = write(tmp_path, data)
    expect_error(path, "seed", "expected an integer", "1.5")


# --- ranges ------------------------------------------------------------------------------------------------------

def test_negative_rate(tmp_path):
    data = base()
    data["sources"][0]["rate"] = -1
    path = write(tmp_path, data)
    expect_error(path, "sources[0].rate", "at least 0", "-1")


def test_exclusive_minimum(tmp_path):
    data = base()
    data["duration"] = 0
    path = write(tmp_path, data)
    expect_error(path, "duration", "greater than 0")


def test_maximum(tmp_path):
    data = base()
    data["sensors"]["lasers"][0]["fov_deg"] = 400
    path = write(tmp_path, data)
    expect_error(path, "sensors.lasers[0].fov_deg", "at most 360")


def test_empty_laser_list(tmp_path):
    data = base()
    data["sensors"]["lasers"] = []
    path = write(tmp_path, data)
    expect_error(path, "sensors.lasers", "at least 1 item")


# --- geometry ----------------------------------------------------------------------------------------------------

def test_goal_near_a_wall(tmp_path):
    data = base()
    data["waypoints"]["by_the_wall"] = {"position": [10, 0.1]}  # 0.1 m from the wall y = 0; adults are 0.25 m
    path = write(tmp_path, data)
    message = expect_error(path, "waypoints.by_the_wall.position", "goal", "inside a wall", "0.10 m from a wall",
                           "largest body radius")
    assert "\n" not in message


def test_goal_inside_an_obstacle(tmp_path):
    data = base()
    data["map"]["obstacles"] = [[[8, 8], [12, 8], [12, 12], [8, 12]]]
    data["waypoints"]["in_the_column"] = {"position": [10, 10]}  # 2 m from every edge, but inside
    path = write(tmp_path, data)
    expect_error(path, "waypoints.in_the_column.position", "goal", "inside a wall", "inside an obstacle")


def test_goal_with_clearance_is_fine(tmp_path):
    data = base()
    data["waypoints"]["clear"] = {"position": [10, 0.3]}  # more than crowd.radius 0.25 from the wall
    path = write(tmp_path, data)
    assert load_scenario(str(path)).waypoints["clear"].position == (10.0, 0.3)


def test_robot_start_inside_a_wall(tmp_path):
    data = base()
    data["robot"]["start"] = [0.05, 5, 0]
    path = write(tmp_path, data)
    expect_error(path, "robot.start", "robot start", "inside a wall")


def test_route_with_unknown_waypoint(tmp_path):
    data = base()
    data["routes"]["r"]["waypoints"] = ["a", "nowhere"]
    path = write(tmp_path, data)
    expect_error(path, "routes.r.waypoints[1]", "unknown stage 'nowhere'", "expected a waypoint or queue: a, b")


def test_source_with_unknown_route(tmp_path):
    data = base()
    data["sources"][0]["routes"] = {"r": 1.0, "nope": 1.0}
    path = write(tmp_path, data)
    expect_error(path, "sources[0].routes.nope", "unknown route", "expected one of: r")


def test_source_routes_all_zero(tmp_path):
    data = base()
    data["sources"][0]["routes"] = {"r": 0.0}
    path = write(tmp_path, data)
    expect_error(path, "sources[0].routes", "positive weight")


@pytest.mark.parametrize("key", ["sources", "clusters"])
def test_group_sizes_all_zero(tmp_path, key):
    data = base()
    if key == "clusters":
        data["clusters"] = [{"position": data["sources"][0]["position"], "route": "r"}]
    data[key][0]["group_size_weights"] = [0.0, 0.0]
    path = write(tmp_path, data)
    expect_error(path, f"{key}[0].group_size_weights", "positive weight")


def test_agent_type_speed_limits_ordered(tmp_path):
    data = base()
    data["crowd"] = {"agent_types": {"adult": {"speed_min": 2.5, "speed_max": 2.0}}}
    path = write(tmp_path, data)
    expect_error(path, "crowd.agent_types.adult.speed_min", "at most crowd.agent_types.adult.speed_max")


def test_unknown_agent_type_is_named(tmp_path):
    data = base()
    data["sources"][0]["agent_types"] = {"adult": 1.0, "giant": 0.5}
    expect_error(write(tmp_path, data), "sources[0].agent_types.giant", "unknown agent type", "adult, child, elder")


# --- missing keys, bad files -------------------------------------------------------------------------------------

def test_missing_robot(tmp_path):
    data = base()
    del data["robot"]
    path = write(tmp_path, data)
    expect_error(path, "robot", "missing required key")


def test_missing_nested_required_key(tmp_path):
    data = base()
    del data["sources"][0]["rate"]
    path = write(tmp_path, data)
    expect_error(path, "sources[0].rate", "missing required key")


def test_invalid_yaml_syntax(tmp_path):
    path = write(tmp_path, "name: broken\nduration: [1, 2\nrobot: {start: [1, 1, 0]}\n")
    message = expect_error(path, "<file>", "not valid YAML")
    assert "line" in message


def test_yaml_that_is_not_a_mapping(tmp_path):
    path = write(tmp_path, "- just\n- a list\n")
    expect_error(path, "<top level>", "expected a mapping of keys")


def test_empty_file(tmp_path):
    path = write(tmp_path, "")
    expect_error(path, "<top level>", "expected a mapping of keys")


def test_missing_file(tmp_path):
    path = tmp_path / "nope.yaml"
    expect_error(path, "<file>", "no such scenario file")


def test_a_folder_named_as_a_bundled_scenario_does_not_hide_it(tmp_path, monkeypatch):
    # `crowdsim run ktp_group --out ktp_group` leaves a folder of that name: the name, and a file based on it, still
    # mean the bundled scenario
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ktp_room").mkdir()
    assert load_scenario("ktp_room")["name"] == "ktp_room"
    assert load_scenario("ktp_group")["robot"]["driver"] == "script"  # ktp_group starts from base: ktp_room


def test_not_a_bundled_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScenarioError) as info:
        load_scenario("not_a_scenario")
    assert info.value.source == "not_a_scenario"
    assert "airport_disembarkation" in str(info.value)


# --- overrides ---------------------------------------------------------------------------------------------------

def test_negative_seed_override(tmp_path):
    path = write(tmp_path, base())
    message = expect_error(path, "seed", "at least 0", "-1", seed=-1)
    assert "\n" not in message


def test_overrides_replace_and_none_keeps(tmp_path):
    data = base()
    data["seed"] = 4
    path = write(tmp_path, data)
    assert load_scenario(str(path), seed=9, duration=1.5)["seed"] == 9
    sc = load_scenario(str(path), seed=None, duration=None)
    assert sc["seed"] == 4 and sc["duration"] == 5.0


def test_duration_override_checked(tmp_path):
    path = write(tmp_path, base())
    expect_error(path, "duration", "greater than 0", duration=-2.0)


def test_error_is_one_value_error_with_source_and_key():
    e = ScenarioError("some/file.yaml", "crowd.radius", "expected a number")
    assert isinstance(e, ValueError)
    assert (e.source, e.key) == ("some/file.yaml", "crowd.radius")
    assert str(e) == "some/file.yaml: crowd.radius: expected a number"


# --- bundled scenarios and defaults ------------------------------------------------------------------------------

def test_every_bundled_scenario_loads():
    names = bundled_scenarios()
    assert "airport_disembarkation" in names
    for name, description in names.items():
        sc = load_scenario(name)
        assert sc["name"] == name
        assert description and "\n" not in description
        assert sc["source"].endswith(f"{name}.yaml")


def test_the_camera_variant_adds_the_robot_and_wall_cameras():
    sc = load_scenario("airport_disembarkation_cameras")
    cams = sc["sensors"]
    assert [c["name"] for c in cams["depth_cameras"]] == ["front_depth", "rear_depth"]
    front = cams["depth_cameras"][0]
    # the kinect_160 preset fills what the file leaves out; the file's own values win
    assert (front["width"], front["height"], front["fovy_deg"], front["noise"]) == (160, 120, 43.0, "kinect")
    assert front["rate"] == 15.0 and front["rgb"] is True
    assert [c["name"] for c in cams["wall_cameras"]] == ["north_west_cam", "south_east_cam"]
    assert sc["crowd"] == load_scenario("airport_disembarkation")["crowd"]  # the same crowd as its base


def test_sensor_names_must_be_unique(tmp_path):
    data = yaml.safe_load(open(load_scenario("airport_disembarkation")["source"]).read())
    data["sensors"]["depth_cameras"] = [{"name": "front_laser"}]
    path = tmp_path / "dup.yaml"
    path.write_text(yaml.safe_dump(data))
    expect_error(path, "sensors.depth_cameras[0].name", "'front_laser' is taken (sensors.lasers[0].name)")


@pytest.mark.parametrize("kind, change, key, words", [
    # a Hokuyo UTM-30LX scans at 40 Hz: more than the 25 steps a second of the default dt 0.04 s
    ("lasers", {"preset": "hokuyo_utm30lx"}, "sensors.lasers[0].rate",
     ["40 Hz is more than the simulation's 25 steps per second (dt 0.04 s)",
      "at most 25 Hz, or a dt of at most 0.025"]),
    ("depth_cameras", {"rate": 30.0}, "sensors.depth_cameras[0].rate", ["30 Hz", "a dt of at most 0.0333333 s"]),
    ("wall_cameras", {"rate": 26.0, "position": [5, 5, 3]}, "sensors.wall_cameras[0].rate", ["26 Hz"]),
    ("lasers", {"range_min": 6.0, "range_max": 5.0}, "sensors.lasers[0].range_min",
     ["6 m; expected less than range_max (5 m)"]),
    ("depth_cameras", {"range_min": 8.0}, "sensors.depth_cameras[0].range_min",
     ["8 m; expected less than range_max (8 m)"]),
    ("lasers", {"noise": [{"up_to": 10.0}, {"up_to": 4.0}]}, "sensors.lasers[0].noise[1].up_to",
     ["4 m; expected the bands nearest first, beyond the previous one's 10 m"]),
])
def test_sensors_that_cannot_run_as_given_are_refused(tmp_path, kind, change, key, words):
    data = yaml.safe_load(open(load_scenario("airport_disembarkation")["source"]).read())
    if kind == "lasers":
        data["sensors"]["lasers"][0].update(change)
    else:
        data["sensors"][kind] = [{"name": "s", **change}]
    path = tmp_path / "sensor.yaml"
    path.write_text(yaml.safe_dump(data))
    expect_error(path, key, *words)
    # a smaller simulation step runs the fast sensors
    if key.endswith(".rate"):
        data["dt"] = 0.025 if change.get("preset") else 1 / change["rate"]
        path.write_text(yaml.safe_dump(data))
        assert load_scenario(str(path))["sensors"][kind][0]["rate"] == change.get("rate", 40.0)


def test_airport_has_the_documented_values():
    sc = load_scenario("airport_disembarkation")
    lasers = sc["sensors"]["lasers"]
    assert len(lasers) == 2
    for laser in lasers:
        assert laser["height"] == pytest.approx(0.70)
        assert laser["fov_deg"] == 190.0
        assert laser["resolution_deg"] == 0.5
        assert laser["range_max"] == 20.0
    crowd = sc["crowd"]
    assert crowd["agent_types"]["adult"]["speed_mean"] == 1.34
    assert crowd["agent_types"]["adult"]["speed_std"] == 0.26
    assert crowd["relaxation_time"] == 0.5
    assert crowd["max_speed_factor"] == 1.3
    grouped = [s for s in sc["sources"] if sum(s["group_size_weights"][1:]) > 0]
    assert grouped, "no source emits groups of two or more"
    assert len(grouped[0]["group_size_weights"]) >= 2
    assert any(s["count"] >= 2 for s in sc["standing"]), "no standing group"


def test_defaults_are_filled(tmp_path):
    path = write(tmp_path, base())
    sc = load_scenario(str(path))
    assert sc["evaluation"] == {"threshold": 1.0, "max_range": 20.0}
    assert sc["seed"] == 0 and sc["warmup"] == 0.0 and sc["dt"] == 0.04 and sc["description"] == ""
    assert sc.map.obstacles == () and sc.standing == ()
    adult = sc["crowd"]["agent_types"]["adult"]
    assert adult["radius"] == 0.25 and adult["speed_mean"] == 1.34
    src = sc["sources"][0]
    assert src.size == (1.0, 1.0) and src.group_size_weights == (1.0,)
    assert src["start"] == 0.0 and src["stop"] == math.inf
    assert sc["routes"]["r"]["sink"] is True
    assert sc["waypoints"]["a"]["radius"] == 1.0 and sc["waypoints"]["b"]["radius"] == 0.5
    assert sc["robot"]["radius"] == 0.425 and sc["robot"]["route"] is None and sc["robot"]["loop"] is True
    laser = sc["sensors"]["lasers"][0]
    assert (laser["height"], laser["fov_deg"], laser["resolution_deg"], laser["range_max"], laser["rate"]) == (
        0.70, 190.0, 0.5, 20.0, 25.0)
    assert sc["pipeline"]["detector"]["jump_distance"] == 0.4
    assert sc["pipeline"]["tracker"]["deletion"]["n_delete"] == 5  # seed 000 Sec. V-C, the base NNT


def test_partial_section_keeps_other_defaults(tmp_path):
    data = base()
    data["evaluation"] = {"max_range": 8}
    data["crowd"] = None  # an empty `crowd:` section in YAML
    path = write(tmp_path, data)
    sc = load_scenario(str(path))
    assert sc["evaluation"] == {"threshold": 1.0, "max_range": 8.0}
    assert sc["crowd"]["relaxation_time"] == 0.5


def test_not_a_number_and_infinity_are_refused(tmp_path):
    data = base()
    data["duration"] = float("nan")
    expect_error(write(tmp_path, data), "duration", "expected a finite number")
    data = base()
    data["sources"][0]["rate"] = float("inf")
    expect_error(write(tmp_path, data), "sources[0].rate", "expected a finite number")
    data = base()
    data["waypoints"]["a"]["position"] = [float("nan"), 1.0]
    expect_error(write(tmp_path, data), "waypoints.a.position", "expected a point [x, y]")
    data = base()
    data["sources"][0]["stop"] = float("inf")  # 'never stop' is a meaningful infinity
    assert load_scenario(str(write(tmp_path, data)))["sources"][0]["stop"] == float("inf")


def test_stop_before_start_names_the_source(tmp_path):
    data = base()
    data["sources"][0].update(start=5.0, stop=1.0)
    expect_error(write(tmp_path, data), "sources[0].stop", "after sources[0].start")


def test_unreadable_file_is_one_error(tmp_path):
    path = tmp_path / "binary.yaml"
    path.write_bytes(b"name: x\n\xff\xfe: 1\n")
    expect_error(path, "<file>", "UTF-8")


def test_base_scenario_is_laid_under(tmp_path):
    quiet = load_scenario("airport_disembarkation_quiet")
    full = load_scenario("airport_disembarkation")
    assert quiet["sources"][0]["rate"] == 1.0 and full["sources"][0]["rate"] == 1.6
    assert quiet["map"] == full["map"] and quiet["routes"] == full["routes"]  # inherited
    assert len(quiet["standing"]) < len(full["standing"])  # a list is replaced, not merged
    child = write(tmp_path, {"base": "airport_disembarkation", "name": "mine", "crowd": {"max_agents": 50}},
                  "mine.yaml")
    sc = load_scenario(str(child))
    assert sc["crowd"]["max_agents"] == 50 and sc["crowd"]["agent_types"] == full["crowd"]["agent_types"]
    loop = write(tmp_path, {"base": "loop.yaml", "name": "loop"}, "loop.yaml")
    expect_error(loop, "base", "leads back to this file")


def test_the_committed_format_reference_is_current():
    # docs/scenario-format.md is generated from the schema: regenerate it with `crowdsim scenario-keys`
    from pathlib import Path

    from scenarios.format import reference

    committed = (Path(__file__).parent.parent / "docs" / "scenario-format.md").read_text()
    assert committed == reference() + "\n"
    assert "| `rate` | float | required | >= 0 | persons/s, mean emission rate (Poisson) |" in committed
