"""The robot's body: differential-drive kinematics and wheel odometry (what drives it: crowdsim/drivers.py)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pipeline.frames import compose, inverse
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
        v, omega = (float(c) for c in limited(np.array([v, omega]), self.velocity, self, dt))
        self.pose = compose(self.pose, arc(v, omega, dt))
        distance, turn = self.odometry.measured(v * dt, omega * dt, self.rng)
        self.odom_pose = compose(self.odom_pose, arc(distance / dt, turn / dt, dt))
        self.velocity = np.array([v, omega])
        self.clock += dt


def limited(command: np.ndarray, velocity: np.ndarray, limits, dt: float) -> np.ndarray:
    """Commands (v, omega) [..., 2] as the drive executes them after ``velocity`` [..., 2]: within the acceleration
    limits of one step ``dt``, then within the speed limits (``limits``: a Robot, or its scenario section)."""
    step = np.array([limits.max_acceleration, limits.max_angular_acceleration]) * dt
    top = np.array([limits.max_speed, limits.max_angular_speed])
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
