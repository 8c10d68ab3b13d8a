"""The tag sensor (seed 001's RFID): coverage 0.5-4.5 m all around, bearing in base_link, its rate, and the
statistics of its errors and detections over many draws."""

import numpy as np
import pytest

from scenarios.format import TAG
from scenarios.schema import ScenarioError, validate
from sensors.tag import TagSensor

EXACT = {"range_sd": 0.0, "bearing_sd_deg": 0.0, "detection_probability": 1.0}


def test_readings_only_within_0_5_to_4_5_m_all_around():
    tag = TagSensor(rng=np.random.default_rng(0), **EXACT, rate=1000.0)
    robot = np.array([1.0, 2.0, 0.3])
    got = []
    for k, (distance, angle) in enumerate([(0.4, 0.0), (0.5, 1.0), (2.0, 3.0), (4.5, -2.0), (4.6, 0.5),
                                           (3.0, np.pi)]):
        target = robot[:2] + distance * np.array([np.cos(angle), np.sin(angle)])
        reading = tag.read(k * 0.01, robot, target)
        got.append(None if reading is None else round(reading.range, 9))
    assert got == [None, 0.5, 2.0, 4.5, None, 3.0]
    assert tag.read(1.0, robot, None) is None


def test_bearing_is_counter_clockwise_from_the_robot_heading():
    tag = TagSensor(rng=np.random.default_rng(0), **EXACT, rate=1000.0)
    robot = np.array([1.0, 1.0, np.pi / 2])  # facing +y
    ahead, left, right = (tag.read(k * 0.01, robot, xy) for k, xy in enumerate([[1, 3], [-1, 1], [3, 1]]))
    assert ahead.bearing == pytest.approx(0.0, abs=1e-12)
    assert left.bearing == pytest.approx(np.pi / 2)
    assert right.bearing == pytest.approx(-np.pi / 2)
    behind = tag.read(0.04, robot, [1.0, -1.0])
    assert abs(behind.bearing) == pytest.approx(np.pi)


def test_reads_at_its_rate():
    tag = TagSensor(rng=np.random.default_rng(0), **EXACT, rate=5.0)
    stamps = [k * 0.04 for k in range(50)]  # 2 s of 25 Hz ticks
    got = [t for t in stamps if tag.read(t, np.zeros(3), [2.0, 0.0]) is not None]
    assert got == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8])


def test_errors_and_detections_have_the_stated_statistics():
    tag = TagSensor(rng=np.random.default_rng(7), rate=1000.0)
    robot, target = np.array([0.0, 0.0, 0.0]), np.array([1.5, 2.0])  # 2.5 m, 53 deg
    readings = [tag.read(k * 0.001, robot, target) for k in range(20000)]
    seen = [r for r in readings if r is not None]
    n = len(seen)
    assert n / 20000 == pytest.approx(0.9, abs=0.01)
    range_error = np.array([r.range for r in seen]) - 2.5
    bearing_error = np.array([r.bearing for r in seen]) - np.arctan2(2.0, 1.5)
    sd_r, sd_b = TagSensor.range_sd, np.radians(TagSensor.bearing_sd_deg)
    assert abs(range_error.mean()) < 4 * sd_r / np.sqrt(n)
    assert abs(bearing_error.mean()) < 4 * sd_b / np.sqrt(n)
    assert range_error.std() == pytest.approx(sd_r, rel=0.03)
    assert bearing_error.std() == pytest.approx(sd_b, rel=0.03)
    assert (seen[0].range_sd, seen[0].bearing_sd) == (sd_r, pytest.approx(sd_b))


def test_same_seed_same_readings_and_bad_parameters_refused():
    def run(seed):
        tag = TagSensor(rng=np.random.default_rng(seed))
        return [tag.read(k * 0.04, np.zeros(3), [2.0, 1.0]) for k in range(100)]
    assert run(1) == run(1) and run(1) != run(2)
    with pytest.raises(ScenarioError, match="range_sigma: unknown key"):
        validate({"range_sigma": 0.1}, TAG, "<test>")
    with pytest.raises(ScenarioError, match="rate: expected a value greater than 0"):
        validate({"rate": 0.0}, TAG, "<test>")
    with pytest.raises(ScenarioError, match="range_min: 4.5; expected below range_max"):
        validate({"range_min": 4.5}, TAG, "<test>")
