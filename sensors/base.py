"""What every sensor is to the loop: a ``Sensor`` captures the world into its frame when it is due, says where it
was (for the robot's software, which places the frame's detections with it) and what each person showed it (for the
ground truth). Lasers, depth cameras, wall cameras, the tag reader and a user's own class (``sensors.custom`` in a
scenario) implement it; the loop schedules them all the same way.

``world`` is ``crowdsim.world.World`` (duck-typed: this package does not import crowdsim): ``world.t``,
``world.robot`` (``pose`` in the world, ``odom_pose``, ``world_T_odom``), ``world.agents()`` (every person, sorted by
id) and ``world.tagged_position()``.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

DUE_TOLERANCE = 1e-9  # s: a frame due at t is taken at the tick stamped t, whatever the rounding of the sums


class Sensor(Protocol):
    name: str
    period: float  # s between frames

    def start(self, t: float) -> None:
        """The first frame is due at ``t``."""

    def due(self, stamp: float) -> bool:
        """Whether a frame is due at the tick ``stamp``."""

    def captured(self, stamp: float) -> None:
        """A frame was taken at ``stamp``: the next is due a period after the last was due."""

    def capture(self, world: Any, stamp: float) -> Any:
        """The frame (its ``frame`` attribute names the sensor), or None: nothing came (a missed read)."""

    def pose_in_odom(self, world: Any) -> np.ndarray | None:
        """Where the robot believes the sensor is, in odom: (x, y, yaw), or a 4x4 for a 3D sensor; None for a
        sensor without a detector (the tag reader)."""

    def shown(self, world: Any, frame: Any) -> tuple[np.ndarray, np.ndarray] | None:
        """Per person of ``world.agents()``: what ``frame`` shows of them (laser beams, a camera's visible share)
        and whether they were in the sensor's view; None for a sensor the visibility leaves out."""


class Periodic:
    """A sensor's clock: due at ``start`` and every ``period`` after it, on the simulation's ticks."""

    period: float
    next_due: float = 0.0

    def start(self, t: float) -> None:
        self.next_due = t

    def due(self, stamp: float) -> bool:
        return self.next_due <= stamp + DUE_TOLERANCE

    def captured(self, stamp: float) -> None:
        self.next_due += self.period


def capture_due(sensors: list, world: Any, stamp: float) -> list[tuple[Any, Any]]:
    """(sensor, frame) of every sensor due at ``stamp``, in the list's order, each sensor's clock moved on. Sensors
    that share a ``batch`` (the lasers of one scene, cast after one sync of it) are captured together, where the first
    of them stands in the list."""
    due = [s for s in sensors if s.due(stamp)]
    out, done = [], set()
    for sensor in due:
        if id(sensor) in done:
            continue
        batch = getattr(sensor, "batch", None)
        together = [s for s in due if getattr(s, "batch", None) is batch] if batch is not None else [sensor]
        frames = batch.capture(together, world, stamp) if batch is not None else [sensor.capture(world, stamp)]
        for s, frame in zip(together, frames):
            done.add(id(s))
            s.captured(stamp)
            out.append((s, frame))
    return out
