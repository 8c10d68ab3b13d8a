"""The robot's body: differential-drive kinematics and wheel odometry (what drives it: crowdsim/drivers.py)."""

from __future__ import annotations

import numpy as np

from pipeline.frames import compose, inverse
from scenarios.typed import Section


class Robot:
    """True pose in ``world``; odometry pose in ``odom`` (which starts at the robot's start pose)."""

    def __init__(self, params: Section, rng: np.random.Generator):
        self.p = params
        self.rng = rng
        self.pose = np.array(params.start, float)
        self.odom_pose = np.zeros(3)
        self.velocity = np.zeros(2)  # (v, omega) executed last step
        self.clock = 0.0  # s the robot has been driven (the warm-up not counted)

    @property
    def world_T_odom(self) -> np.ndarray:
        """The true transform from odom to world: where odometry believes the robot is, made to fit the truth."""
        return compose(self.pose, inverse(self.odom_pose))

    def step(self, v: float, omega: float, dt: float) -> None:
        """Move by the command, limited in speed and acceleration, with exact arc integration; integrate the
        odometry with its errors."""
        v, omega = (float(c) for c in limited(np.array([v, omega]), self.velocity, self.p, dt))
        self.pose = compose(self.pose, arc(v, omega, dt))
        distance, turn = self.measured_motion(v * dt, omega * dt)
        self.odom_pose = compose(self.odom_pose, arc(distance / dt, turn / dt, dt))
        self.velocity = np.array([v, omega])
        self.clock += dt

    def measured_motion(self, distance: float, turn: float) -> tuple[float, float]:
        """What the wheel encoders report for a true step of ``distance`` (m) and ``turn`` (rad).

        The usual odometry error model (Borenstein & Feng 1996; Thrun et al., Probabilistic Robotics Sec. 5.4):
        systematic errors (a scale error on distance, a heading drift per metre) plus random errors whose variance
        grows in proportion to the distance driven and the angle turned, so that the drift does not depend on the
        time step.
        """
        o = self.p.odometry
        d = distance * (1.0 + o.distance_scale_error)
        t = turn + o.yaw_drift * distance
        if o.distance_noise > 0:
            d += o.distance_noise * np.sqrt(abs(distance)) * self.rng.standard_normal()
        yaw_var = o.yaw_noise ** 2 * abs(turn) + o.yaw_noise_per_distance ** 2 * abs(distance)
        if yaw_var > 0:
            t += np.sqrt(yaw_var) * self.rng.standard_normal()
        return d, t


def limited(command: np.ndarray, velocity: np.ndarray, p: Section, dt: float) -> np.ndarray:
    """Commands (v, omega) [..., 2] as the drive executes them after ``velocity`` [..., 2]: within the acceleration
    limits of one step ``dt``, then within the speed limits."""
    step = np.array([p.max_acceleration, p.max_angular_acceleration]) * dt
    top = np.array([p.max_speed, p.max_angular_speed])
    # np.minimum/maximum: np.clip's wrapper costs more than the work on a handful of robots
    return np.minimum(np.maximum(np.minimum(np.maximum(command, velocity - step), velocity + step), -top), top)


def arc(v, omega, dt: float) -> np.ndarray:
    """The pose increment [..., 3] of a differential drive moving at (v, omega) (scalars or arrays) for dt."""
    v, omega = np.asarray(v, float), np.asarray(omega, float)
    th = omega * dt
    straight = np.abs(th) < 1e-9
    r = v / np.where(straight, 1.0, omega)
    out = np.empty(th.shape + (3,))
    out[..., 0] = np.where(straight, v * dt, r * np.sin(th))
    out[..., 1] = np.where(straight, 0.0, r * (1 - np.cos(th)))
    out[..., 2] = th
    return out
