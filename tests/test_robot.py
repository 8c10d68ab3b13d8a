"""Differential-drive kinematics, odometry and the route driver against hand-worked values."""

import numpy as np
import pytest

from crowdsim.robot import Robot, arc
from scenarios.format import ROBOT
from scenarios.schema import validate
from scenarios.typed import typed


def params(**kw):
    """The robot as a scenario gives it; accelerations effectively unlimited unless a test sets them."""
    raw = {"start": [0.0, 0.0, 0.0], "max_speed": 1.0, "max_angular_speed": 2.0, "max_acceleration": 1e9,
           "max_angular_acceleration": 1e9}
    raw.update(kw)
    return typed(validate(raw, ROBOT, "<test>"), ROBOT)


def test_quarter_circle():
    # v = 1 m/s, omega = pi/2 rad/s for 1 s: a quarter circle of radius 2/pi, ending at (r, r) facing +y
    robot = Robot.of(params(), np.random.default_rng(0))
    for _ in range(25):
        robot.step(1.0, np.pi / 2, 0.04)
    r = 2 / np.pi
    assert robot.pose == pytest.approx([r, r, np.pi / 2], abs=1e-9)
    assert robot.odom_pose == pytest.approx(robot.pose, abs=1e-9)  # perfect odometry from the origin


def test_limits_are_applied():
    robot = Robot.of(params(max_speed=0.5, max_angular_speed=1.0), np.random.default_rng(0))
    robot.step(3.0, 5.0, 1.0)
    assert robot.velocity == pytest.approx([0.5, 1.0])
    assert arc(0.5, 1.0, 1.0) == pytest.approx([0.5 * np.sin(1.0), 0.5 * (1 - np.cos(1.0)), 1.0])


def test_acceleration_limits_ramp_the_speed():
    # from rest, v = 1 m/s commanded at 0.5 m/s^2 and omega = 2 rad/s at 1.5 rad/s^2: after 1 s (25 steps)
    # v = 0.5 m/s and omega = 1.5 rad/s; both then reach their commands (1 and 2) after 2 s and 1.33 s
    robot = Robot.of(params(max_acceleration=0.5, max_angular_acceleration=1.5), np.random.default_rng(0))
    for _ in range(25):
        robot.step(1.0, 2.0, 0.04)
    assert robot.velocity == pytest.approx([0.5, 1.5])
    for _ in range(25):
        robot.step(1.0, 2.0, 0.04)
    assert robot.velocity == pytest.approx([1.0, 2.0])
    robot.step(-1.0, 0.0, 0.04)  # braking is limited too
    assert robot.velocity == pytest.approx([1.0 - 0.02, 2.0 - 0.06])


def drive_straight(odometry: dict, metres: float = 10.0, seed: int = 0) -> Robot:
    robot = Robot.of(params(odometry=odometry), np.random.default_rng(seed))
    for _ in range(round(metres / 0.04)):
        robot.step(1.0, 0.0, 0.04)
    return robot


def test_systematic_odometry_errors_bend_and_stretch_the_odometry_path():
    # 10 m straight: a +2% scale error reads 10.2 m
    robot = drive_straight({"distance_scale_error": 0.02})
    assert robot.pose == pytest.approx([10.0, 0.0, 0.0], abs=1e-9)
    assert robot.odom_pose == pytest.approx([10.2, 0.0, 0.0], abs=1e-9)
    # a heading drift of 0.01 rad/m: odometry believes in an arc of 10 m turning by 0.1 rad, radius 100 m:
    # (100 sin 0.1, 100 (1 - cos 0.1)) = (9.98334, 0.49958)
    robot = drive_straight({"yaw_drift": 0.01})
    assert robot.odom_pose == pytest.approx([100 * np.sin(0.1), 100 * (1 - np.cos(0.1)), 0.1], abs=1e-9)


def test_random_odometry_errors_grow_with_the_square_root_of_the_distance():
    # distance noise 0.05 m/sqrt(m) and heading noise 0.01 rad/sqrt(m) over 10 m: the odometry's distance error
    # has sd 0.05 sqrt(10) = 0.158 m, its heading error sd 0.01 sqrt(10) = 0.0316 rad, whatever the step length;
    # over 300 independent runs the sample sd is within about 3 x 4% of that
    runs = [drive_straight({"distance_noise": 0.05, "yaw_noise_per_distance": 0.01}, seed=k).odom_pose
            for k in range(300)]
    runs = np.array(runs)
    heading_err = runs[:, 2]
    distance_err = np.hypot(runs[:, 0], runs[:, 1]) - 10.0
    assert abs(distance_err.mean()) < 3 * 0.158 / np.sqrt(300)
    assert distance_err.std(ddof=1) == pytest.approx(0.05 * np.sqrt(10), rel=0.13)
    assert heading_err.std(ddof=1) == pytest.approx(0.01 * np.sqrt(10), rel=0.13)


def test_noisy_odometry_drifts_and_world_T_odom_tracks_it():
    start = [3.0, -1.0, 0.3]
    robot = Robot.of(params(start=start, odometry={"distance_noise": 0.05, "yaw_noise": 0.05}),
                     np.random.default_rng(0))
    for _ in range(500):
        robot.step(0.8, 0.2, 0.04)
    # odom and world disagree after 20 s of noisy odometry, and world_T_odom maps one onto the other exactly
    w = robot.world_T_odom
    assert np.linalg.norm(w[:2] - start[:2]) > 0.01
    c, s = np.cos(w[2]), np.sin(w[2])
    mapped = w[:2] + np.array([[c, -s], [s, c]]) @ robot.odom_pose[:2]
    assert mapped == pytest.approx(robot.pose[:2], abs=1e-9)


def test_a_robot_made_in_python_has_the_scenario_formats_defaults():
    # the body declares its parameters once, on the class: Robot(start=...) and a scenario's robot section that gives
    # only its start are the same robot (0.425 m, 0.6 m/s at 0.5 m/s^2, perfect odometry)
    made = Robot(start=(1.0, 2.0, 0.5), rng=np.random.default_rng(0), odometry={"yaw_drift": 0.01})
    loaded = Robot.of(typed(validate({"start": [1.0, 2.0, 0.5], "odometry": {"yaw_drift": 0.01}}, ROBOT, "<test>"),
                            ROBOT), np.random.default_rng(0))
    assert (made.radius, made.max_speed, made.max_acceleration) == (loaded.radius, loaded.max_speed, 0.5) == (
        0.425, 0.6, 0.5)
    for robot in (made, loaded):
        for _ in range(50):  # 2 s: 0.02 m/s more each step up to 0.6 m/s at step 30, then 20 steps at 0.6 m/s
            robot.step(1.0, 0.0, 0.04)
    driven = 0.04 * (0.02 * sum(range(1, 31)) + 0.6 * 20)  # 0.852 m
    assert made.pose == pytest.approx(loaded.pose) and made.pose[:2] == pytest.approx(
        [1.0 + np.cos(0.5) * driven, 2.0 + np.sin(0.5) * driven], abs=1e-9)
    assert made.odom_pose[2] == pytest.approx(loaded.odom_pose[2]) == pytest.approx(0.01 * made.odom_pose[0], rel=0.05)


def test_drive_steps_many_robots_through_many_ticks():
    from crowdsim.robot import drive

    # robot 0 from rest, v = 1 m/s and omega = 0 commanded at 0.5 m/s^2 (dt 0.1 s: +0.05 m/s a tick), capped at
    # 0.12 m/s: 0.05, 0.10, 0.12 m/s, so x = 0.1 * (0.05 + 0.10 + 0.12) = 0.027 m after three ticks; robot 1 turns on
    # the spot at its cap of 1 rad/s from 1 rad/s already, facing pi - 0.1 + 0.3, wrapped
    velocities, poses = drive(np.array([[1.0, 0.0], [0.0, 5.0]]), np.array([[0.0, 0.0], [0.0, 1.0]]),
                              np.array([[0.0, 0.0, 0.0], [2.0, 3.0, np.pi - 0.1]]), np.array([0.5, 1.5]),
                              np.array([0.12, 1.0]), 0.1, 3)
    assert velocities[:, 0, 0] == pytest.approx([0.05, 0.10, 0.12])
    assert poses[-1, 0] == pytest.approx([0.027, 0.0, 0.0], abs=1e-15)
    assert np.array_equal(velocities[:, 1], [[0.0, 1.0]] * 3)
    assert poses[-1, 1] == pytest.approx([2.0, 3.0, np.pi + 0.2 - 2 * np.pi], abs=1e-12)
