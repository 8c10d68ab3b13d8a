"""The loaded scenario is a read-only typed object (scenarios/typed.py): its sections' keys are attributes, it
cannot be changed in place, and it turns back into the data a file holds; the packages read it by attribute only."""

import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from scenarios import bundled_scenarios, load_scenario, scenario_from_dict
from scenarios.geometry import wall_segments
from scenarios.typed import Names, Scenario, Section, as_written, plain

ROOT = Path(__file__).resolve().parents[1]


def test_sections_are_attributes_lists_tuples_and_named_items_names():
    s = load_scenario("airport_disembarkation")
    assert isinstance(s, Scenario) and isinstance(s.robot, Section)
    assert s.robot.radius == 0.425 and s.sensors.lasers[0].rate == 25.0  # seed 000's platform, SICK at 25 Hz
    assert isinstance(s.sensors.lasers, tuple) and isinstance(s.robot.start, tuple)
    assert isinstance(s.routes, Names) and isinstance(next(iter(s.routes.values())), Section)
    assert s.pipeline.tracker.deletion.type == "young_mature"
    np.testing.assert_array_equal(s.map.segments, wall_segments(plain(s)))
    with pytest.raises(AttributeError, match="no key 'radious'.*radius"):
        s.robot.radious


def test_it_cannot_be_changed_in_place_and_replace_gives_a_changed_copy():
    s = load_scenario("passers_by")
    with pytest.raises(AttributeError, match="read-only"):
        s.seed = 3
    with pytest.raises(TypeError):
        s.routes["x"] = 1
    t = s.replace(seed=3, robot=s.robot.replace(radius=0.3))
    assert (t.seed, t.robot.radius, s.seed, s.robot.radius) == (3, 0.3, s.seed, s.robot.radius)
    assert isinstance(t, Scenario) and isinstance(t.routes, Names)


@pytest.mark.parametrize("name", bundled_scenarios())
def test_every_bundled_scenario_goes_back_to_its_data_and_through_a_pickle_whole(name):
    s = load_scenario(name)
    data = plain(s)
    # as crowdsim run writes it to scenario.yaml (the keys left unset left out, a sensor without a detector kept
    # as such): it loads to the same scenario
    written = as_written(s)
    assert scenario_from_dict({k: v for k, v in written.items() if k != "source"}, s.source) == s
    again = pickle.loads(pickle.dumps(s))
    assert type(again) is Scenario and plain(again) == data and isinstance(again.routes, Names)
    assert again.map.segments.shape == s.map.segments.shape


# a read of the scenario by string key: scenario["robot"], sc["map"], self.scenario.get("seed"), ...
STRING_READ = re.compile(r"\b(?:scenario|sc)(?:\[\s*[\"']|\.get\(\s*[\"'])")


def test_no_module_outside_scenarios_reads_the_scenario_by_string_key():
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for package in ("crowdsim", "sensors", "pipeline", "evaluation")
             for path in sorted((ROOT / package).rglob("*.py"))
             for n, line in enumerate(path.read_text().splitlines(), 1) if STRING_READ.search(line)]
    assert found == []
