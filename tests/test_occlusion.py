"""Seed 000's occlusion test on hand-worked geometry."""

import numpy as np

from evaluation.occlusion import seed000_visible


def arc(centre, radius, from_deg, to_deg):
    a = np.radians(np.linspace(from_deg, to_deg, 37))
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def test_seed000_rule_on_a_person_seen_and_one_behind_them():
    # a laser at the origin sees the front arc of person A (torso radius 0.18 m) at (5, 0): A's position moved 0.2 m
    # towards the laser, (4.8, 0), lies 0.02 m from A's nearest point (4.82, 0): visible
    points = arc((5.0, 0.0), 0.18, 100, 260)
    # person B 0.38 m behind A gets no beam, but A's outermost point (5 + 0.18 cos 100deg, 0.18 sin 100deg) =
    # (4.969, 0.177) is sqrt(0.211^2 + 0.177^2) = 0.275 m from B's shifted position (5.18, 0): seed 000's rule calls
    # B visible; person C 0.5 m behind A: that point is sqrt(0.331^2 + 0.177^2) = 0.375 m away: occluded
    # person D off to the side at (3, 4) with no points near: occluded
    got = seed000_visible(np.array([[5.0, 0.0], [5.38, 0.0], [5.5, 0.0], [3.0, 4.0]]), np.zeros(2), points)
    assert got.tolist() == [True, True, False, False]
    assert seed000_visible(np.array([[5.0, 0.0]]), np.zeros(2), np.full((3, 2), np.nan)).tolist() == [False]


def test_seed000_rule_across_the_bearing_seam_and_round_the_laser():
    # a person straight behind the laser (bearing 180 deg, where the bins wrap) with a point 0.1 m below their
    # shifted position (-4.8, 0): visible; a person 0.1 m from the laser, shifted 0.2 m past it to (-0.1, 0), whose
    # 0.3 m disc holds the laser, and a point 0.269 m from there: visible; a person with no point near: occluded
    points = np.array([[-4.8, -0.1], [0.0, 0.25]])
    got = seed000_visible(np.array([[-5.0, 0.0], [0.1, 0.0], [-5.0, 3.0]]), np.zeros(2), points)
    assert got.tolist() == [True, True, False]


def test_seed000_rule_is_a_radius_search_about_the_shifted_positions():
    # random scenes against a brute-force search: every point within 0.3 m of each shifted position
    rng = np.random.default_rng(1)
    for _ in range(50):
        origin = rng.uniform(-5, 5, 2)
        positions = origin + rng.uniform(-8, 8, (40, 2))
        points = origin + rng.uniform(-8, 8, (300, 2))
        towards = origin - positions
        shifted = positions + 0.2 * towards / np.linalg.norm(towards, axis=1)[:, None]
        near = (np.linalg.norm(shifted[:, None] - points[None], axis=2) < 0.3).any(axis=1)
        assert seed000_visible(positions, origin, points).tolist() == near.tolist()
