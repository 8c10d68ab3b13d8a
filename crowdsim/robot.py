"""The robot's body: differential-drive kinematics and wheel odometry (what drives it: crowdsim/drivers.py)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pipeline.compiled import kernel
from pipeline.frames import compose, compose_pose, inverse
from pipeline.params import REQUIRED, given, param


@dataclass(frozen=True, kw_only=True)
class Odometry:
    """What the wheel encoders report of a true motion: the usual odometry error model (Borenstein & Feng 1996;
    Thrun et al., Probabilistic Robotics Sec. 5.4), systematic errors (a scale error on distance, a heading drift per
    metre) plus random errors whose variance grows in proportion to the distance driven and the angle turned, so that
    the drift does not depend on the time step. All 0: perfect odometry."""

    distance_scale_error: float = param(0.0, "relative error of the distance measured (a wheel radius off by this "
                                             "share)", min=-0.5, max=0.5)
    yaw_drift: float = param(0.0, "rad/m, heading error per metre driven (wheels of unequal diameter)")
    distance_noise: float = param(0.0, "m/sqrt(m): the distance error's variance grows by this^2 per m", min=0.0)
    yaw_noise: float = param(0.0, "rad/sqrt(rad): heading error variance per radian turned", min=0.0)
    yaw_noise_per_distance: float = param(0.0, "rad/sqrt(m): heading error variance per metre driven", min=0.0)

    def measured(self, distance: float, turn: float, rng: np.random.Generator) -> tuple[float, float]:
        """The distance (m) and turn (rad) reported for a true step of ``distance`` and ``turn``."""
        d = distance * (1.0 + self.distance_scale_error)
        t = turn + self.yaw_drift * distance
        if self.distance_noise > 0:
            d += self.distance_noise * np.sqrt(abs(distance)) * rng.standard_normal()
        yaw_var = self.yaw_noise ** 2 * abs(turn) + self.yaw_noise_per_distance ** 2 * abs(distance)
        if yaw_var > 0:
            t += np.sqrt(yaw_var) * rng.standard_normal()
        return d, t


@dataclass(kw_only=True, eq=False)
class Robot:
    """True pose in ``world``; odometry pose in ``odom`` (which starts at the robot's start pose):
    ``Robot(start=..., rng=..., **params)``."""

    start: tuple = param(REQUIRED, "m, m, rad: initial pose in the world frame", kind="pose")
    radius: float = param(0.425, "m, footprint radius (SPENCER platform ~0.85 m wide)", min=0.0, exclusive_min=True)
    max_speed: float = param(0.6, "m/s", min=0.0)
    max_angular_speed: float = param(1.0, "rad/s", min=0.0)
    max_acceleration: float = param(0.5, "m/s^2 (an assumption for a ~1.5 m platform)", min=0.0, exclusive_min=True)
    max_angular_acceleration: float = param(1.5, "rad/s^2 (an assumption)", min=0.0, exclusive_min=True)
    odometry: Odometry = param(Odometry(), "wheel odometry's systematic and random errors (all 0: perfect odometry)")
    rng: np.random.Generator

    def __post_init__(self):
        if isinstance(self.odometry, Mapping):  # a scenario's section, or a dict of its keys
            self.odometry = Odometry(**self.odometry)
        self.pose = np.array(self.start, float)
        self.odom_pose = np.zeros(3)
        self.velocity = np.zeros(2)  # (v, omega) executed last step
        self.clock = 0.0  # s the robot has been driven (the warm-up not counted)

    @classmethod
    def of(cls, robot: Mapping, rng: np.random.Generator) -> Robot:
        """The body a scenario's ``robot`` section gives (its other keys are the driver's)."""
        return cls(rng=rng, **given(cls, robot))

    @property
    def world_T_odom(self) -> np.ndarray:
        """The true transform from odom to world: where odometry believes the robot is, made to fit the truth."""
        return compose(self.pose, inverse(self.odom_pose))

    def step(self, v: float, omega: float, dt: float) -> None:
        """Move by the command, limited in speed and acceleration, with exact arc integration; integrate the
        odometry with its errors."""
        velocity, pose = drive(np.array([[v, omega]], float), self.velocity[None], self.pose[None],
                               np.array([self.max_acceleration, self.max_angular_acceleration]),
                               np.array([self.max_speed, self.max_angular_speed]), dt, 1)
        self.velocity, self.pose = velocity[0, 0], pose[0, 0]
        v, omega = float(self.velocity[0]), float(self.velocity[1])
        distance, turn = self.odometry.measured(v * dt, omega * dt, self.rng)
        self.odom_pose = compose(self.odom_pose, arc(distance / dt, turn / dt, dt))
        self.clock += dt


@kernel
def drive(command, velocity, pose, acceleration, top, dt, ticks):
    """``ticks`` steps ``dt`` of E differential-drive robots at ``pose`` [E, 3] moving at ``velocity`` [E, 2]
    (v, omega), each holding its ``command`` [E, 2] as the drive executes it: within ``acceleration`` [2] (m/s^2,
    rad/s^2) of the last velocity, then within the speeds ``top`` [2]. Returns the velocities [ticks, E, 2] and the
    poses [ticks, E, 3] after each step."""
    velocities, poses = np.empty((ticks, len(pose), 2)), np.empty((ticks, len(pose), 3))
    for k in range(len(pose)):
        v, omega, x, y, yaw = velocity[k, 0], velocity[k, 1], pose[k, 0], pose[k, 1], pose[k, 2]
        for t in range(ticks):
            v = _limited(command[k, 0], v, acceleration[0] * dt, top[0])
            omega = _limited(command[k, 1], omega, acceleration[1] * dt, top[1])
            x, y, yaw = compose_pose(x, y, yaw, *arc(v, omega, dt))
            velocities[t, k, 0], velocities[t, k, 1] = v, omega
            poses[t, k, 0], poses[t, k, 1], poses[t, k, 2] = x, y, yaw
    return velocities, poses


@kernel
def _limited(command, last, step, top):
    """The command within ``step`` of the ``last`` velocity, then within +-``top``."""
    return min(max(min(max(command, last - step), last + step), -top), top)


@kernel
def arc(v, omega, dt):
    """The pose increment (dx, dy, dyaw) of a differential drive moving at (v, omega) for dt."""
    th = omega * dt
    if abs(th) < 1e-9:
        return v * dt, 0.0, th
    r = v / omega
    return r * np.sin(th), r * (1 - np.cos(th)), th
