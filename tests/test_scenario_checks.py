"""Load-time checks of a scenario file: a strict YAML reader (a key twice, deep nesting, alias bombs, huge numbers),
each part's own rules across its keys, and places in the map's free space; each one ScenarioError naming the file,
the key and what was expected."""

import pytest

from scenarios import ScenarioError, load_scenario
from scenarios.loader import first_sentence


def expect(tmp_path, text: str, key: str, *words) -> str:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    e = info.value
    assert (e.source, e.key) == (str(path), key), str(e)
    for w in words:
        assert w in e.message, (w, e.message)
    return e.message


# the strict reader

def test_a_key_given_twice_names_both_lines(tmp_path):
    expect(tmp_path, "base: passers_by\nduration: 5\nseed: 2\nduration: 9\n", "<file>",
           "'duration' is given twice, at lines 2 and 4")
    expect(tmp_path, "base: passers_by\nrobot:\n  max_speed: 0.5\n  max_speed: 0.4\n", "<file>", "lines 3 and 4")


def test_deep_nesting_and_alias_bombs_are_refused_before_anything_walks_them(tmp_path):
    expect(tmp_path, "name: deep\ndescription: " + "[" * 5000 + "]" * 5000 + "\n", "<file>", "nested more than 64")
    bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join(['*' + chr(97 + k)] * 10)}]\n" for k in range(7))
    expect(tmp_path, bomb, "<file>", "more than 1,000,000 values through its aliases")


def test_numbers_beyond_a_float_or_an_int64_are_one_error(tmp_path):
    expect(tmp_path, "base: passers_by\nwarmup: " + "9" * 400 + "\n", "warmup",
           "expected a finite number, got an integer of 400 digits")
    expect(tmp_path, "base: passers_by\nseed: " + "9" * 30 + "\n", "seed", "at most 18 digits")


def test_a_utf8_bom_is_read(tmp_path):
    path = tmp_path / "bom.yaml"
    path.write_bytes("\ufeffbase: passers_by\nseed: 4\n".encode("utf-8"))
    assert load_scenario(str(path))["seed"] == 4


# each part's rules, at load time

@pytest.mark.parametrize("text, key, words", [
    ("base: passers_by\nrobot:\n  planner: {type: nd, sectors: 9}\n", "robot.planner.sectors", ["multiple of 4"]),
    ("base: person_following\nsensors:\n  tag: {range_min: 5.0, range_max: 1.0}\n", "sensors.tag.range_min",
     ["expected below range_max (1)"]),
    ("base: seed001_room_1\npipeline:\n  detectors:\n    camera_1: {hog_scales: []}\n",
     "pipeline.detectors.camera_1.hog_scales", ["at least 1 item"]),
    ("base: seed001_room_1\npipeline:\n  detectors:\n    camera_1: {foreground: false, hog: false}\n",
     "pipeline.detectors.camera_1.hog", ["at least one of foreground and hog"]),
    ("base: ktp_group\npipeline:\n  detectors:\n    kinect: {up: [0.0, 0.0, 0.0]}\n", "pipeline.detectors.kinect.up",
     ["non-zero vector"]),
    # 1 deg at 10 deg a beam: round(0.1) + 1 = 1 beam
    ("base: seed001_room_1\nsensors:\n  lasers:\n    - {name: laser, mount: [0.15, 0, 0], fov_deg: 1.0, "
     "resolution_deg: 10.0, rate: 5.0}\n", "sensors.lasers[0].resolution_deg", ["gives 1 beam", "at least 2"]),
    ("base: airport_disembarkation\npipeline:\n  tracker: {type: mht, p_det: 0.8}\n", "pipeline.tracker.p_del",
     ["p_det + p_occ + p_del = 1.1", "expected 1"]),
    ("base: airport_disembarkation\npipeline:\n  tracker: {v_min: 2.0, v_max: 2.0}\n", "pipeline.tracker.v_min",
     ["expected below v_max"]),
    ("base: seed001_room_1\npipeline:\n  tracker: {move_probabilities: [0.5, 0.5, 0.5, 0.5]}\n",
     "pipeline.tracker.move_probabilities", ["summing to 1"]),
    ("base: ktp_group\nsensors:\n  depth_cameras:\n    - {name: kinect, preset: kinect_160, "
     "position: [0.0, 0.33, 1.1], yaw: 1.5707963, rate: 30.0}\n", "sensors.depth_cameras[0].rgb",
     ["pipeline.detectors.kinect (rgbd_people) needs this camera's colour images", "hog: false"]),
    ("base: seed001_room_1\nsensors:\n  wall_cameras:\n    - {name: 'cam \"east\"', position: [5.0, 4.0, 2.6], "
     "rate: 5.0}\n", "sensors.wall_cameras[0].name", ["letters, digits"]),
    ("base: passers_by\nsources:\n  - {position: [3.0, 0.6], size: [-1.0, 1.0], rate: 1.0, routes: {to_north3: 1}}\n",
     "sources[0].size", ["at least 0 m"]),
])
def test_a_part_rule_is_one_error_at_load_time(tmp_path, text, key, words):
    expect(tmp_path, text, key, *words)


# places in the map's free space

def test_the_robot_start_needs_its_own_radius_of_clearance(tmp_path):
    # passers_by's wall runs along x = 0: a start at x = 0.3 is 0.30 m from it, the robot's radius 0.425 m
    expect(tmp_path, "base: passers_by\nrobot:\n  start: [0.3, 4.0, 0.0]\n", "robot.start",
           "robot start [0.3, 4] lies inside a wall (0.30 m from a wall)", "0.425 m (robot.radius)")
    assert load_scenario(str(_write(tmp_path, "base: passers_by\nrobot:\n  start: [0.5, 4.0, 0.0]\n")))


def _write(tmp_path, text):
    path = tmp_path / "ok.yaml"
    path.write_text(text)
    return path


def test_places_outside_the_map_are_refused(tmp_path):
    # the airport's walls span x 0..37 m, y -8..27 m
    expect(tmp_path, "base: airport_disembarkation\nrobot:\n  start: [100.0, 100.0, 0.0]\n", "robot.start",
           "lies outside the map", "x 0..37 m, y -8..27 m")
    expect(tmp_path, "base: airport_disembarkation\nstanding:\n  - {position: [-1.0, 9.5], count: 3}\n",
           "standing[0].position", "standing place [-1, 9.5] lies outside the map")
    # seed 001's room closes: a cluster's 200 m start area reaches beyond its outer wall
    expect(tmp_path, "base: seed001_room_1\nclusters:\n  - {position: [2.5, 1.4], route: diagonal_up, count: 10, "
                     "spread: [200.0, 200.0]}\n", "clusters[0].spread",
           "a corner of the cluster's start area [-97.5, -98.6] lies outside the map", "inside the outer wall")
    expect(tmp_path, "base: seed001_room_1\nsensors:\n  wall_cameras:\n"
                     "    - {name: camera_1, position: [9.8, 0.2, 2.6]}\n"
                     "    - {name: camera_2, position: [50.0, 4.0, 2.6]}\n",
           "sensors.wall_cameras[1].position", "wall camera [50, 4] lies outside the map")


def test_exits_beyond_a_door_and_clusters_waiting_outside_are_fine():
    # ktp_room's doorway waypoints lie beyond its walls, ktp_group's persons wait outside its north door
    sc = load_scenario("ktp_group")
    assert sc["waypoints"]["north_doorway"]["position"][1] > 3.0 and sc["clusters"][2]["position"][1] > 3.0


# the listing's first sentence

def test_the_first_sentence_keeps_abbreviations_whole():
    assert first_sentence("KTP's group (seed 003 Sec. 2): five persons gather. Three start beside it.") == \
        "KTP's group (seed 003 Sec. 2): five persons gather."
    assert first_sentence("Seed 001's room (Mekonnen et al. 2013, Fig. 11) is\nsmall. The robot stands.") == \
        "Seed 001's room (Mekonnen et al. 2013, Fig. 11) is small."
    assert first_sentence("No full stop") == "No full stop."


def test_a_duration_shorter_than_a_step_and_deep_pedsim_xml_are_refused(tmp_path):
    expect(tmp_path, "base: passers_by\nduration: 1.0e-9\n", "duration", "expected at least one step, dt (0.04 s)")
    path = tmp_path / "deep.xml"
    path.write_text("<scenario>" + "<welcome>" * 20000 + "</welcome>" * 20000 + "</scenario>\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    assert info.value.source == str(path) and "nested more than 16 elements deep" in info.value.message


def test_yaml_merge_keys_a_nul_byte_a_standing_circle_and_walkers_too_fast(tmp_path):
    path = tmp_path / "merge.yaml"
    path.write_text("base: passers_by\nwaypoints:\n  north3: {<<: {radius: 0.5}, position: [3.0, 10.0]}\n")
    assert load_scenario(str(path))["waypoints"]["north3"]["radius"] == 0.5
    expect(tmp_path, "base: passers_by\nname: a\0b\n", "<file>", "unacceptable character #x0000")
    # 6 persons 1 m apart stand on a circle of 1 / (2 sin(pi / 6)) = 1 m round [3.5, 20], 1.5 m from the airport's
    # west wall; at spacing 2.5 the circle's 2.5 m plus a body's 0.25 m reach past the wall 3.5 m away
    load_scenario(str(_write(tmp_path, "base: airport_disembarkation\nstanding:\n  - {position: [3.5, 20], count: 6, "
                                       "spacing: 1.0}\n")))
    expect(tmp_path, "base: airport_disembarkation\nstanding:\n  - {position: [3.5, 20], count: 6, spacing: 3.25}\n",
           "standing[0].position", "is too near a wall (3.50 m from a wall)", "circle of 3.25 m")
    # an adult at most 2.0 m/s x 1.3 = 2.6 m/s, 0.104 m a step: fine; x 1000, 2,000 m/s: 80 m a step, past 0.25 m
    expect(tmp_path, "base: passers_by\ncrowd: {max_speed_factor: 1000.0}\n", "crowd.agent_types.adult.speed_max",
           "moves a walker 80 m in one step", "--allow-large does not pass it")
