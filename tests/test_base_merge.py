"""A file built on another with ``base:``: a part given another type is replaced whole, ``!replace`` and ``!remove``
say what to do with an inherited value, agent types merge by name, and an error in an inherited key names both
files. The README's own-tracker example runs as printed."""

import json
import re
import sys
from pathlib import Path

import pytest

from crowdsim.cli import main
from scenarios import ScenarioError, load_scenario
from scenarios.format import DEFAULT_AGENT_TYPES

ROOT = Path(__file__).parent.parent
EXAMPLES = ROOT / "docs" / "examples"


def write(tmp_path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_another_planner_type_replaces_the_base_planner(tmp_path):
    # passers_by's zone planner has zone_* keys nd does not take: they do not carry over
    base = load_scenario("passers_by")["robot"]["planner"]
    assert base["type"] == "zone" and "zone_radius" in base
    sc = load_scenario(str(write(tmp_path, "nd.yaml", "base: passers_by\nrobot:\n  planner: {type: nd, sectors: 8}\n")))
    assert sc["robot"]["planner"] == {"type": "nd", "goal_tolerance": 0.1, "stop_margin": 0.05,
                                      "security_distance": 0.5, "sectors": 8, "wide_fraction": 0.25}


def test_another_tracker_type_replaces_the_base_tracker(tmp_path):
    text = "base: airport_disembarkation\npipeline:\n  tracker: {type: mht}\n"
    sc = load_scenario(str(write(tmp_path, "mht.yaml", text)))
    assert sc["pipeline"]["tracker"]["type"] == "mht" and sc["pipeline"]["tracker"]["n_scan"] == 30
    assert "initiation" not in sc["pipeline"]["tracker"]


def test_the_same_type_still_merges_key_by_key(tmp_path):
    base = load_scenario("airport_disembarkation")["pipeline"]["tracker"]
    text = "base: airport_disembarkation\npipeline:\n  tracker: {gate_chi2: 9.21}\n"
    sc = load_scenario(str(write(tmp_path, "g.yaml", text)))
    assert sc["pipeline"]["tracker"] == {**base, "association": {**base["association"], "gate_chi2": 9.21}}


def test_one_agent_type_tweaked_keeps_the_others(tmp_path):
    sc = load_scenario(str(write(tmp_path, "a.yaml", "base: airport_disembarkation\ncrowd:\n  agent_types:\n"
                                                      "    adult: {speed_mean: 1.2}\n")))
    types = sc["crowd"]["agent_types"]
    assert list(types) == ["adult", "child", "elder"]
    assert types["adult"] == {**DEFAULT_AGENT_TYPES["adult"], "speed_mean": 1.2}
    assert types["child"] == DEFAULT_AGENT_TYPES["child"]
    # a default type tweaked keeps its own other values (a child's radius, not an adult's)
    sc = load_scenario(str(write(tmp_path, "c.yaml", "base: airport_disembarkation\ncrowd:\n  agent_types:\n"
                                                      "    child: {speed_mean: 1.0}\n")))
    assert sc["crowd"]["agent_types"]["child"]["radius"] == 0.18


def test_remove_drops_an_inherited_key_and_replace_keeps_only_what_is_given(tmp_path):
    # passers_by's planner without its own yield_time: the zone default (2 s) again
    text = "base: passers_by\nrobot:\n  planner:\n    yield_time: !remove\n"
    assert load_scenario(str(write(tmp_path, "r.yaml", text)))["robot"]["planner"]["yield_time"] == 2.0
    text = ("base: airport_disembarkation\ncrowd:\n  agent_types: !replace\n    adult: {speed_mean: 1.3}\n"
            "sources: []\n")
    assert list(load_scenario(str(write(tmp_path, "p.yaml", text)))["crowd"]["agent_types"]) == ["adult"]
    text = "base: airport_disembarkation\ncrowd:\n  agent_types:\n    elder: !remove\nsources: []\n"
    assert list(load_scenario(str(write(tmp_path, "e.yaml", text)))["crowd"]["agent_types"]) == ["adult", "child"]
    # a whole section tagged !replace loses the base's keys under it
    text = "base: passers_by\nrobot: !replace\n  start: [6.0, 4.0, 0.0]\n"
    sc = load_scenario(str(write(tmp_path, "robot.yaml", text)))
    assert sc["robot"]["driver"] == "route" and sc["robot"]["route"] is None


def test_an_error_in_a_key_from_the_base_names_both_files(tmp_path):
    parent = write(tmp_path, "parent.yaml", "base: passers_by\nname: parent\nrobot:\n  max_speed: 0.3\n")
    child = write(tmp_path, "child.yaml", "base: parent.yaml\nname: child\nrobot:\n  follow: {band: [1.0, 2.0]}\n")
    load_scenario(str(child))  # fine: the parent's keys are valid
    parent.write_text("base: passers_by\nname: parent\nrobot:\n  goals: [[0.1, 4.0]]\n")  # 0.1 m from a wall
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(child))
    e = info.value
    assert e.source == str(child) and e.key == "robot.goals[0]"
    assert f"robot.goals[0] comes from the base scenario {parent}" in str(e)
    assert str(e).startswith(f"{child}: robot.goals[0]: robot goal [0.1, 4]")


def test_a_base_that_is_not_there_names_the_file_that_asks_for_it(tmp_path):
    path = write(tmp_path, "typo.yaml", "base: airport_disembarkaton\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    assert info.value.source == str(path) and info.value.key == "base"
    assert "'airport_disembarkaton': not a bundled scenario" in str(info.value)


def test_the_readme_own_tracker_example_is_the_shipped_one_and_runs(tmp_path, monkeypatch, capsys):
    readme = (ROOT / "README.md").read_text()
    for name in ("my_airport.yaml", "my_trackers.py"):
        block = re.search(rf"```(?:yaml|python)\n(# {re.escape(name)}.*?)```", readme, re.S).group(1)
        assert block == (EXAMPLES / name).read_text(), f"README's {name} differs from docs/examples/{name}"
    monkeypatch.chdir(EXAMPLES)
    monkeypatch.syspath_prepend(str(EXAMPLES))
    out = tmp_path / "run"
    assert main(["run", "my_airport.yaml", "--duration", "2", "--quiet", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["scenario"] == "my_airport" and metrics["frames"] == 50  # 2 s of 25 Hz cycles
    # the tracker's tracks are scored: it follows most of the persons in range
    assert metrics["tracking"]["mota"] > 0.5 and metrics["tracking"]["gt"] > 0
    sys.modules.pop("my_trackers", None)


def test_a_user_tracker_returning_none_is_one_error_naming_it(tmp_path, monkeypatch, capsys):
    (tmp_path / "none_trackers.py").write_text("class Nothing:\n    def update(self, stamp, detections):\n"
                                               "        return None\n    def reset(self):\n        pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    path = write(tmp_path, "none.yaml",
                 "base: passers_by\nwarmup: 0\npipeline:\n  tracker: {type: none_trackers:Nothing}\n")
    assert main(["run", str(path), "--duration", "1", "--quiet", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"crowdsim: error: {path}: pipeline.tracker.type: none_trackers:Nothing.update returned NoneType; "
                   "expected TrackedPersons (pipeline.types)"]
    assert not (tmp_path / "out").exists()


def test_a_user_part_that_raises_is_one_error_naming_it_and_its_line(tmp_path, monkeypatch, capsys):
    (tmp_path / "raising_parts.py").write_text(
        "class Broken:\n    def __init__(self):\n        raise RuntimeError('no model here')\n"
        "    def update(self, stamp, detections):\n        pass\n    def reset(self):\n        pass\n\n"
        "class Failing:\n    def update(self, stamp, detections):\n        return 1 / 0\n"
        "    def reset(self):\n        pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = tmp_path / "raising_parts.py"
    for name, said in (("Broken", f"raising_parts:Broken(...) raised RuntimeError: no model here at {module}:3"),
                       ("Failing", f"raising_parts:Failing.update raised ZeroDivisionError: division by zero at "
                                   f"{module}:11")):
        path = write(tmp_path, f"{name}.yaml", f"base: passers_by\nwarmup: 0\npipeline:\n  tracker: "
                                                f"{{type: raising_parts:{name}}}\n")
        assert main(["run", str(path), "--duration", "1", "--quiet", "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"crowdsim: error: {path}: pipeline.tracker.type: {said}; "), err
        assert not (tmp_path / "out").exists()


def test_a_user_planner_whose_command_is_no_pair_of_numbers_is_one_error(tmp_path, monkeypatch, capsys):
    (tmp_path / "lost_planners.py").write_text(
        "class Lost:\n    def command(self, stamp, pose, velocity, obstacles, tracks, goal):\n        return None\n"
        "    def reset(self):\n        pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    path = write(tmp_path, "lost.yaml", "base: passers_by\nwarmup: 0\nrobot:\n  planner: {type: lost_planners:Lost}\n")
    assert main(["run", str(path), "--duration", "1", "--quiet", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"crowdsim: error: {path}: robot.planner.type: lost_planners:Lost.command returned NoneType; "
                   "expected (v, omega), two finite numbers in m/s and rad/s"]
