"""The parts of one's own that docs/extending.md shows (docs/examples/beacons.py, my_parts.py), each named in the
scenario as ``module:Class`` and run with nothing of the loop changed: a sensor scheduled at its period whose frames
reach a detector of one's own, a group stage, a planner, a driver from one's own loop."""

from pathlib import Path

import numpy as np
import pytest
from conftest import LASERS
from test_assemble import walkers

from crowdsim.loop import Simulation
from scenarios import ScenarioError, scenario_from_dict

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"


@pytest.fixture(autouse=True)
def examples_importable(monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))


def beacon_room(**sensor):
    spec = {"type": "beacons:Beacons", "name": "beacons", "rate": 5.0, "range": 6.0, **sensor}
    data = walkers({"detectors": {"beacons": {"type": "beacons:BeaconDetector"}}})
    data["sensors"] = {"lasers": LASERS, "custom": [spec]}
    return data


def test_a_sensor_of_ones_own_is_scheduled_at_its_period_and_feeds_a_detector_of_ones_own():
    sim = Simulation(scenario_from_dict(beacon_room()))
    sim.warm_up()  # 2 s
    frames = list(sim.frames(1.0))
    (beacons,) = sim.custom_sensors
    # 5 Hz from the end of the warm-up: the first tick after it (2.04 s), then every 0.2 s
    np.testing.assert_allclose(beacons.stamps, [2.04, 2.2, 2.4, 2.6, 2.8, 3.0], atol=1e-9)
    detector = sim.pipeline.detectors["beacons"]
    assert [f.stamp for f in detector.frames] == beacons.stamps
    fed = [f for f in frames if "beacons" in f.detector_outputs]
    assert [f.stamp for f in fed] == beacons.stamps  # the lasers' cycle at the same tick fuses them
    for f in fed:
        out = f.detector_outputs["beacons"]
        assert out.frame == "odom"
        agents = f.agents
        near = np.hypot(*(agents.position - f.robot_pose[:2]).T) <= 6.0
        assert near.sum() >= 3  # the standing group at least
        np.testing.assert_array_equal(out.detection_id, agents.id[near])
        # perfect odometry from the start (2, 2, 0): odom is the world shifted by the start
        np.testing.assert_allclose(out.position[:, :2], agents.position[near] - [2.0, 2.0], atol=1e-9)
        # the ground truth lists the sensor, and what it showed of whom
        k = f.visibility.sensors.index("beacons")
        np.testing.assert_array_equal(f.visibility.amount[:, k], near.astype(float))
    sim.reset()
    assert detector.frames == [] and sim.pipeline.detectors["beacons"] is detector


def test_a_sensor_of_ones_own_without_the_sensor_methods_or_a_name_is_one_error_naming_it():
    with pytest.raises(ScenarioError, match=r"sensors\.custom\[0\]\.type: .*no method start"):
        scenario_from_dict(beacon_room(type="beacons:BeaconDetector"), source="beacons.yaml")
    data = beacon_room()
    del data["sensors"]["custom"][0]["name"]
    with pytest.raises(ScenarioError, match=r"sensors\.custom\[0\]: .*'name'"):
        scenario_from_dict(data, source="beacons.yaml")


def test_a_group_stage_of_ones_own_groups_the_standing_three():
    sim = Simulation(scenario_from_dict(walkers({"groups": {"type": "my_parts:NearbyGroups", "distance": 1.5}})))
    sim.warm_up()
    *_, last = sim.frames(1.0)
    # the standing group of three at (6, 2), 4 m ahead of the robot, is one group of its three tracks
    sizes = np.bincount(np.unique(last.groups.member_group, return_inverse=True)[1])
    assert 3 in sizes
    k = int(np.flatnonzero(sizes == 3)[0])
    np.testing.assert_allclose(last.groups.centroid[k], [4.0, 0.0], atol=0.5)  # odom: the world less (2, 2)


def test_a_planner_of_ones_own_takes_the_robot_to_its_goal_and_a_driver_of_ones_own_drives_it():
    from my_parts import drive_in_a_circle
    data = walkers(robot={"start": [2, 30, 0], "driver": "goals", "goals": [[5.0, 30.0]],
                          "planner": {"type": "my_parts:CreepPlanner", "speed": 0.3}})
    sim = Simulation(scenario_from_dict(data))
    sim.warm_up()
    frames = list(sim.frames(20.0))
    assert sim.finished and np.hypot(*(sim.robot.pose[:2] - [5.0, 30.0])) <= 0.3  # the default goal_radius
    assert max(abs(f.robot_pose[2]) for f in frames) < 0.05  # the goal straight ahead: no turning
    sim.reset()
    frames = drive_in_a_circle(sim, 2.0, v=0.4, omega=0.4)
    assert len(frames) == 50  # the lasers' 25 Hz cycles
    # 2 s at (0.4 m/s, 0.4 rad/s), less what the acceleration limits took at the start: at most 0.8 m and 0.8 rad,
    # turning left
    x, y, yaw = sim.robot.pose
    assert 0.6 < np.hypot(x - 2.0, y - 30.0) <= 0.8 and 0.6 < yaw <= 0.8 and y > 30.0


def test_a_deletion_logic_of_ones_own_decides_when_the_nnts_tracks_go():
    from my_parts import GrowingPatience
    tracker = {"type": "nnt", "deletion": {"type": "my_parts:GrowingPatience", "base": 5, "per_miss": 10, "cap": 8}}
    sim = Simulation(scenario_from_dict(walkers({"tracker": tracker})))
    deletion = sim.pipeline.tracker.deletion
    assert type(deletion) is GrowingPatience and (deletion.base, deletion.cap) == (5, 8)
    # confirmed tracks: 5 misses, one more per 10 detections, at most 8; unconfirmed: 1
    np.testing.assert_array_equal(deletion.limits(np.array([True, True, True, False]), np.array([3, 25, 90, 4])),
                                  [5, 7, 8, 1])
    sim.warm_up()
    *_, last = sim.frames(1.0)
    assert len(last.tracks) >= 3  # the standing group, tracked with it
