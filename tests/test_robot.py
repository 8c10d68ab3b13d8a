"""Differential-drive kinematics, odometry and the route driver against hand-worked values."""

import numpy as np
import pytest

from crowdsim.robot import Robot, arc


def params(**kw):
    p = {"start": [0.0, 0.0, 0.0], "route": None, "loop": True, "radius": 0.425, "max_speed": 1.0,
         "max_angular_speed": 2.0, "safety_distance": 0.6, "odometry_noise": 0.0}
    p.update(kw)
    return p


def test_quarter_circle():
    # v = 1 m/s, omega = pi/2 rad/s for 1 s: a quarter circle of radius 2/pi, ending at (r, r) facing +y
    robot = Robot(params(), np.random.default_rng(0))
    for _ in range(25):
        robot.step(1.0, np.pi / 2, 0.04)
    r = 2 / np.pi
    assert robot.pose == pytest.approx([r, r, np.pi / 2], abs=1e-9)
    assert robot.odom_pose == pytest.approx(robot.pose, abs=1e-9)  # perfect odometry from the origin


def test_limits_are_applied():
    robot = Robot(params(max_speed=0.5, max_angular_speed=1.0), np.random.default_rng(0))
    robot.step(3.0, 5.0, 1.0)
    assert robot.velocity == pytest.approx([0.5, 1.0])
    assert arc(0.5, 1.0, 1.0) == pytest.approx([0.5 * np.sin(1.0), 0.5 * (1 - np.cos(1.0)), 1.0])


def test_odometry_noise_drifts_and_world_T_odom_tracks_it():
    start = [3.0, -1.0, 0.3]
    robot = Robot(params(start=start, odometry_noise=0.05), np.random.default_rng(0))
    for _ in range(500):
        robot.step(0.8, 0.2, 0.04)
    # odom and world disagree after 20 s of noisy odometry, and world_T_odom maps one onto the other exactly
    w = robot.world_T_odom
    assert np.linalg.norm(w[:2] - start[:2]) > 0.01
    c, s = np.cos(w[2]), np.sin(w[2])
    mapped = w[:2] + np.array([[c, -s], [s, c]]) @ robot.odom_pose[:2]
    assert mapped == pytest.approx(robot.pose[:2], abs=1e-9)


def test_route_driver_reaches_waypoints_and_stops_for_obstacles():
    robot = Robot(params(route=[[5.0, 0.0], [5.0, 5.0]], loop=False), np.random.default_rng(0))
    assert robot.drive_command(front_clearance=0.3) == (0.0, 0.0)  # something 0.3 m ahead: stand still
    for _ in range(2000):
        v, w = robot.drive_command(front_clearance=np.inf)
        robot.step(v, w, 0.04)
    assert np.linalg.norm(robot.pose[:2] - [5.0, 5.0]) < 0.5
    assert robot.drive_command(front_clearance=np.inf) == (0.0, 0.0)  # route done, no loop
