"""The drivers of crowdsim/drivers.py on their own: the route driver's steering and safety stop, the script's rows,
the front clearance they stop by."""

import numpy as np
import pytest

from crowdsim.drivers import RouteDriver, ScriptDriver, front_clearance
from crowdsim.robot import Robot
from pipeline.types import LaserScan
from test_robot import params


def test_route_driver_reaches_waypoints_and_stops_for_obstacles():
    p = params(route=[[5.0, 0.0], [5.0, 5.0]], loop=False)
    robot, driver = Robot.of(p, np.random.default_rng(0)), RouteDriver.of(p)
    driver.reset()
    assert driver.steer(robot.pose, front_clearance=0.3) == (0.0, 0.0)  # something 0.3 m ahead: stand still
    for _ in range(2000):
        robot.step(*driver.steer(robot.pose, front_clearance=np.inf), 0.04)
    assert np.linalg.norm(robot.pose[:2] - [5.0, 5.0]) < 0.5
    assert driver.steer(robot.pose, front_clearance=np.inf) == (0.0, 0.0)  # route done, no loop


def test_the_script_driver_holds_each_command_in_turn():
    # seed 003's KTP motions: 2 s translating at 0.15 m/s, 2 s rotating at 0.11 rad/s, then standing (no loop);
    # acceleration limits high enough to change speed within a step
    p = params(driver="script", script=[[2.0, 0.15, 0.0], [2.0, 0.0, 0.11]], loop=False,
               max_acceleration=100.0, max_angular_acceleration=100.0)
    robot, driver = Robot.of(p, np.random.default_rng(0)), ScriptDriver.of(p)
    dt = 0.04
    for _ in range(150):  # 6 s
        robot.step(*driver.at(robot.clock), dt)
    np.testing.assert_allclose(robot.pose, [0.30, 0.0, 0.22], atol=1e-9)
    assert driver.at(robot.clock) == (0.0, 0.0) and robot.clock == pytest.approx(6.0)
    looping = ScriptDriver.of(params(driver="script", script=[[1.0, 0.1, 0.0], [1.0, -0.1, 0.0]], loop=True))
    assert looping.at(2.5) == (0.1, 0.0)  # back in the first row
    assert looping.at(3.5) == (-0.1, 0.0)


def test_front_clearance_is_the_nearest_return_in_the_robots_corridor():
    # a laser 0.2 m ahead of the centre, beams at -90, 0 and +90 degrees: 3 m ahead, 0.5 m to each side
    scan = LaserScan(0.0, "front", -np.pi / 2, np.pi / 2, 10.0, np.array([0.5, 3.0, 0.5]), np.full(3, -1))
    mount = np.array([0.2, 0.0, 0.0])
    # the side returns lie 0.5 m off the axis, outside a 0.3 m robot's 0.4 m corridor; the one ahead is at 3.2 m
    assert front_clearance([(scan, mount)], radius=0.3) == pytest.approx(3.2 - 0.3)
    # a 0.45 m robot's corridor (0.55 m) takes the side returns in, 0.2 m ahead of the centre: already touching
    assert front_clearance([(scan, mount)], radius=0.45) == pytest.approx(0.2 - 0.45)
    assert front_clearance([], radius=0.3) == np.inf


def test_drivers_made_in_python_take_keyword_parameters_with_the_formats_defaults():
    # the route driver stops for a return nearer than the default 0.6 m safety distance and drives on beyond it;
    # a script loops by default
    body = Robot(start=(0.0, 0.0, 0.0), rng=np.random.default_rng(0))  # 0.425 m, 0.6 m/s
    route = RouteDriver(body=body, route=[[5.0, 0.0]])
    route.reset()
    assert route.steer(np.zeros(3), front_clearance=0.59) == (0.0, 0.0)
    assert route.steer(np.zeros(3), front_clearance=0.61) == pytest.approx((0.6, 0.0))
    script = ScriptDriver(body=body, script=[[1.0, 0.1, 0.0], [1.0, 0.0, 0.2]])
    assert script.at(2.5) == (0.1, 0.0)
    with pytest.raises(TypeError, match="safety_distanse"):
        RouteDriver(body=body, safety_distanse=0.3)
