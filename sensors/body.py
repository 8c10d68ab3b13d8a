"""The person body the sensors see: a torso, a head and two legs that swing with a gait phase driven by the distance
walked, in clothing colours that stay with the person.

Every person is this body scaled by their own factor (``body_scale``): the crowd's body radius relative to an
adult's (a child of radius 0.18 m is 0.72 of an adult), times a jitter of a few percent fixed by the id.

Proportions for an adult of 1.75 m, after the segment fractions of stature in Winter, "Biomechanics and Motor Control
of Human Movement" (4th ed., Fig. 4.1): hip joint at about half the stature (0.87 m), a step of about 0.41 stature
(0.72 m) at the free walking speed. The torso is a cylinder of the hip radius the 70 cm lasers see (seed 000); the
legs are capsules, so a laser at 38 cm (seed 001) sees two legs that part and cross as the person walks.
"""

from __future__ import annotations

import numpy as np

HIP_HEIGHT = 0.87  # m, hip joint above the floor
LEG_RADIUS = 0.06  # m, the shank at about 38 cm (12 cm across)
LEG_LENGTH = HIP_HEIGHT - LEG_RADIUS  # m, hip joint to the centre of the capsule's lower cap, which meets the floor
HIP_HALF_WIDTH = LEG_RADIUS  # m, each leg's axis from the centre line: standing legs touch
TORSO_RADIUS = 0.18  # m, hips and trunk as the 70 cm lasers see them (adult hip width ~0.36 m)
TORSO_BOTTOM, TORSO_TOP = 0.62, 1.45  # m
HEAD_RADIUS = 0.10  # m
HEAD_CENTRE = 1.62  # m (top of the head at 1.72 m)
HEIGHT = HEAD_CENTRE + HEAD_RADIUS
# the neck joins the head to the torso (a neck of 38 cm round); without it a depth camera's cloud has a 15 cm gap
# there, and a person falls apart into torso and head (seed 003's Euclidean clusters join points 2 voxels apart)
NECK_RADIUS = 0.06  # m
# the sphere that ends each leg at the hip lies wholly inside the torso, so what sees the body never needs it
HIP_INSIDE_TORSO = (HIP_HALF_WIDTH + LEG_RADIUS < TORSO_RADIUS
                    and TORSO_BOTTOM < HIP_HEIGHT - LEG_RADIUS and HIP_HEIGHT + LEG_RADIUS < TORSO_TOP)
STRIDE = 2 * 0.72  # m walked per gait cycle (two steps)
# the swing angle at which the feet are a step apart: asin(step / 2 / hip height) = 24.4 degrees
SWING_AMPLITUDE = float(np.arcsin(0.72 / 2 / HIP_HEIGHT))
FULL_SWING_SPEED = 1.0  # m/s: slower walkers take proportionally shorter swings; standing people stand still
ADULT_RADIUS = 0.25  # m, the crowd's adult body radius (scenarios/format.py), the size these proportions are for
SIZE_JITTER = 0.04  # the spread of sizes among people of one radius, +- this share
MIN_SCALE, MAX_SCALE = 0.65, 1.05  # the sizes a scene holds: a child of radius 0.18 m to a tall adult

# clothing: a top and trousers per person, picked from these by id, so a person keeps them from frame to frame
TOPS = np.array([[0.80, 0.15, 0.15], [0.15, 0.35, 0.75], [0.20, 0.60, 0.25], [0.90, 0.75, 0.20], [0.55, 0.25, 0.60],
                 [0.95, 0.95, 0.95], [0.15, 0.15, 0.15], [0.95, 0.50, 0.15], [0.35, 0.75, 0.80], [0.60, 0.45, 0.30],
                 [0.85, 0.40, 0.60], [0.45, 0.45, 0.50]])
TROUSERS = np.array([[0.10, 0.12, 0.25], [0.20, 0.20, 0.20], [0.45, 0.35, 0.25], [0.30, 0.35, 0.45],
                     [0.70, 0.65, 0.55], [0.05, 0.05, 0.05], [0.35, 0.40, 0.30]])
SKIN = np.array([0.85, 0.68, 0.55])


def body_scale(person_ids: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Each person's size relative to the adult body: their crowd radius over an adult's, jittered by the id."""
    ids = np.asarray(person_ids, np.int64).astype(np.uint64)
    # in [-1, 1]: the top 16 bits of a Fibonacci hash, so that consecutive ids get unrelated sizes
    jitter = ((ids * np.uint64(0x9E3779B97F4A7C15)) >> np.uint64(48)).astype(float) / 32767.5 - 1.0
    return np.clip(np.asarray(radius, float) / ADULT_RADIUS * (1.0 + SIZE_JITTER * jitter), MIN_SCALE, MAX_SCALE)


def _scales() -> np.ndarray:
    return np.linspace(MIN_SCALE, MAX_SCALE, 23)


def legs_show_at(height: float) -> bool:
    """Whether a horizontal ray at ``height`` can meet a leg outside the torso, for a person of any size: below the
    torso, or where a leg swung fully forward pokes out of it (a tilted capsule's section reaches r / cos(swing)
    along the swing)."""
    for k in _scales():
        h = height / k  # the height in the adult body's proportions
        if h > HIP_HEIGHT + LEG_RADIUS:
            continue
        if h < TORSO_BOTTOM or h > TORSO_TOP:
            return True
        # the section's centre lies HIP_HALF_WIDTH aside and (hip - height) tan(swing) ahead; no point of it is
        # farther from the body's axis than that centre plus the section's larger semi-axis, r / cos(swing)
        forward = max(HIP_HEIGHT - h, 0.0) * np.tan(SWING_AMPLITUDE)
        if np.hypot(HIP_HALF_WIDTH, forward) + LEG_RADIUS / np.cos(SWING_AMPLITUDE) > TORSO_RADIUS:
            return True
    return False


def torso_at(height: float) -> bool:
    """Whether a horizontal ray at ``height`` can meet the torso of a person of any size."""
    return bool(any(TORSO_BOTTOM * k <= height <= TORSO_TOP * k for k in _scales()))


def head_at(height: float) -> bool:
    """Whether a horizontal ray at ``height`` can meet the head of a person of any size."""
    return bool(any(abs(height - HEAD_CENTRE * k) <= HEAD_RADIUS * k for k in _scales()))


def clothing(person_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """RGB of each person's top and trousers [n, 3], fixed by the id (scrambled, so neighbours differ)."""
    ids = np.asarray(person_ids, np.int64)
    return TOPS[(ids * 7919) % len(TOPS)], TROUSERS[(ids * 104729) % len(TROUSERS)]


def leg_swing(walked: np.ndarray, speed: np.ndarray, scale: np.ndarray | float = 1.0) -> np.ndarray:
    """The left leg's forward swing angle (rad; the right leg's is its negative) at each person's gait phase
    (a smaller body takes shorter strides at the same angles)."""
    phase = 2 * np.pi * np.asarray(walked) / (STRIDE * scale)
    return SWING_AMPLITUDE * np.clip(np.asarray(speed) / (FULL_SWING_SPEED * scale), 0.0, 1.0) * np.sin(phase)


def leg_poses(xy: np.ndarray, heading: np.ndarray, swing: np.ndarray,
              scale: np.ndarray | float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Hip positions [n, 2, 3] (left, right) and orientations [n, 2, 4] (w, x, y, z) of both legs.

    A leg hangs from its hip along the body's -z; turning it by ``swing`` about the lateral axis moves the foot
    forward by LEG_LENGTH sin(swing).
    """
    n = len(xy)
    c, s = np.cos(heading), np.sin(heading)
    left = np.stack([-s, c], 1)  # the body's lateral axis, to its left
    hips = np.empty((n, 2, 3))
    half = HIP_HALF_WIDTH * np.broadcast_to(scale, (n,))[:, None]
    hips[:, 0, :2] = xy + half * left
    hips[:, 1, :2] = xy - half * left
    hips[:, :, 2] = HIP_HEIGHT * np.broadcast_to(scale, (n,))[:, None]
    # yaw about z, then pitch about the body's y axis; pitch -beta swings the foot forward by L sin(beta)
    beta = np.stack([swing, -swing], 1)
    a, d = np.cos(heading / 2)[:, None], np.sin(heading / 2)[:, None]
    e, g = np.cos(-beta / 2), np.sin(-beta / 2)
    quats = np.stack([a * e, -d * g, a * g, d * e], -1)
    return hips, quats


def feet(hips: np.ndarray, heading: np.ndarray, swing: np.ndarray, scale: np.ndarray | float = 1.0) -> np.ndarray:
    """The lower ends [n, 2, 3] of the leg capsules' axes that ``leg_poses`` gives."""
    beta = np.stack([swing, -swing], 1)
    forward = np.stack([np.cos(heading), np.sin(heading)], 1)[:, None, :]
    length = LEG_LENGTH * np.broadcast_to(scale, (len(hips),))[:, None]
    out = hips.copy()
    out[..., :2] += (length * np.sin(beta))[..., None] * forward
    out[..., 2] -= length * np.cos(beta)
    return out
