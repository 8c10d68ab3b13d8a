"""The simulation's public face: ``reset(seed)`` and ``step(command)``, a caller's (v, omega) in place of the route
driver, within the robot's limits; hand-worked numbers in comments."""

import numpy as np
import pytest
from conftest import room

from crowdsim.loop import Simulation
from scenarios import scenario_from_dict

DT = 0.04


def walkers(**robot) -> Simulation:
    """The conftest room (40 m x 40 m) with a flow of people past the robot, which has no route unless given."""
    return Simulation(scenario_from_dict(room(
        waypoints={"east": {"position": [30, 6]}}, routes={"across": {"waypoints": ["east"]}},
        sources=[{"position": [5, 6], "size": [1, 2], "rate": 2.0, "routes": {"across": 1.0}}],
        crowd={"random_force": 0.1}, robot={"start": [10.0, 20.0, 0.5], **robot})))


def test_a_constant_command_from_rest_follows_the_acceleration_limits_and_exact_arcs():
    # (0.3, 0.3) from rest: v gains at most 0.5 m/s^2 x 0.04 s = 0.02 a tick (0.3 at tick 15), omega 1.5 x 0.04 =
    # 0.06 (0.3 at tick 5). Each tick is an exact arc of radius v / omega: from heading a to b, the robot moves
    # (v / omega) (sin b - sin a, cos a - cos b). After 25 ticks the heading has turned
    # 0.04 (0.06 + 0.12 + 0.18 + 0.24 + 21 x 0.3) = 0.276 rad.
    sim = walkers()
    ticks = np.arange(1, 26)
    v, omega = np.minimum(0.02 * ticks, 0.3), np.minimum(0.06 * ticks, 0.3)
    heading = 0.5 + np.concatenate([[0.0], np.cumsum(omega * DT)])
    x = 10.0 + np.sum(v / omega * (np.sin(heading[1:]) - np.sin(heading[:-1])))
    y = 20.0 + np.sum(v / omega * (np.cos(heading[:-1]) - np.cos(heading[1:])))
    for _ in ticks:
        sim.step((0.3, 0.3))
    assert heading[-1] - 0.5 == pytest.approx(0.276, abs=1e-12)
    np.testing.assert_allclose(sim.robot.pose, [x, y, heading[-1]], atol=1e-12)
    np.testing.assert_allclose(sim.robot.velocity, [0.3, 0.3], atol=1e-12)


def test_a_command_beyond_the_limits_is_clipped():
    # (2, -3): one tick gives the acceleration limits (0.02, -0.06); after 40 ticks the speed limits (0.6, -1.0)
    sim = walkers()
    sim.step(np.array([2.0, -3.0]))  # a gym action: a numpy array
    np.testing.assert_allclose(sim.robot.velocity, [0.02, -0.06], atol=1e-15)
    for _ in range(39):
        sim.step((2.0, -3.0))
    np.testing.assert_array_equal(sim.robot.velocity, [0.6, -1.0])


def test_the_safety_stop_is_the_route_drivers_not_the_callers():
    # the robot faces the east wall (x = 40) 1 m away, its route leading on towards it. In the first tick, before
    # any scan, the route driver starts (0.02 m/s for 0.04 s: 0.0008 m); from the first scan on it sees the wall
    # 1 - 0.425 m from its front, inside the 0.6 m safety distance, and stands. A caller's (0.3, 0) drives on, from
    # rest: 0.04 (0.02 + 0.04 + ... + 0.1) = 0.012 m in five ticks
    sim = walkers(start=[39.0, 20.0, 0.0], route=[[39.7, 20.0], [30.0, 20.0]])
    for _ in range(5):
        sim.step()
    np.testing.assert_allclose(sim.robot.pose, [39.0008, 20.0, 0.0], atol=1e-12)
    assert sim.robot.velocity[0] == 0.0
    for _ in range(5):
        sim.step((0.3, 0.0))
    np.testing.assert_allclose(sim.robot.pose, [39.0128, 20.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("command", [(1.0,), (1.0, 2.0, 3.0), (np.nan, 0.0), (0.0, np.inf), "ab", (True, False),
                                     ((1.0, 2.0), 3.0), ("1", "2"), 0.5])
def test_a_command_that_is_not_two_finite_numbers_is_refused(command):
    sim = walkers()
    with pytest.raises(ValueError, match=r"command: expected \(v, omega\), two finite numbers"):
        sim.step(command)


def test_reset_with_a_seed_and_the_same_commands_gives_the_same_frames_bit_for_bit():
    sim = walkers()
    commands = [(0.4, 0.2 * np.sin(k / 10)) for k in range(60)]

    def episode(seed):
        sim.reset(seed)
        sim.warm_up()
        frames = [f for f in (sim.step(c) for c in commands) if f is not None]
        assert len(frames) == 60  # two lasers at 25 Hz: a tracking cycle every tick
        return [(f.stamp, f.robot_pose, [s.ranges for s in f.scans], f.agents.position, f.detections.position,
                 f.tracks.track_id, f.tracks.position, f.groundtruth.position) for f in frames]

    def same(a, b):  # bit for bit (NaN ranges included)
        return all(np.shape(x) == np.shape(y) and np.asarray(x).tobytes() == np.asarray(y).tobytes()
                   for fa, fb in zip(a, b) for x, y in zip(fa, fb))

    first, other, again = episode(3), episode(4), episode(3)
    assert same(first, again)
    assert not same(first, other)
    assert any(len(f[5]) for f in first)  # the tracker tracked someone
