"""pipeline/frames.py: the one place for rotations and transforms; each function and its inverse."""

import numpy as np
import pytest

from pipeline.frames import (compose, inverse, optical_rotation, rotate, rotate_covariances, rotation, to_frame,
                             transform_points, unrotate, wrap_angle)

POSE = np.array([1.5, -2.0, 2.4])


def test_points_there_and_back():
    pts = np.random.default_rng(0).normal(0, 5, (20, 2))
    there = transform_points(POSE, pts)
    assert np.allclose(to_frame(POSE, there), pts, atol=1e-12)
    assert np.allclose(transform_points(inverse(POSE), there), pts, atol=1e-12)
    # the point's pose composed with POSE has the same position
    assert np.allclose(compose(POSE, np.column_stack([pts, np.zeros(20)]))[:, :2], there, atol=1e-12)


def test_vectors_turn_without_the_translation():
    v = np.array([[1.0, 0.0], [0.0, 2.0]])
    c, s = np.cos(POSE[2]), np.sin(POSE[2])
    assert np.allclose(rotate(POSE, v), [[c, s], [-2 * s, 2 * c]], atol=1e-15)
    assert np.allclose(unrotate(POSE, rotate(POSE, v)), v, atol=1e-15)
    assert np.array_equal(rotate(POSE, v) + POSE[:2], transform_points(POSE, v))


def test_rotation_matrices():
    r2, r3 = rotation(POSE), rotation(POSE, 3)
    assert np.allclose(r2 @ r2.T, np.eye(2)) and np.isclose(np.linalg.det(r2), 1.0)
    assert np.array_equal(r3[:2, :2], r2) and np.array_equal(r3[2], [0.0, 0.0, 1.0])
    assert np.array_equal(rotation([3.0, 4.0, 0.0]), np.eye(2))


def test_covariances_turn_with_the_frame():
    cov = np.array([[[4.0, 0.0], [0.0, 1.0]]])  # long along the frame's x
    turned = rotate_covariances(rotation([0.0, 0.0, np.pi / 2]), cov)
    assert np.allclose(turned, [[[1.0, 0.0], [0.0, 4.0]]], atol=1e-12)
    rot = rotation(POSE)
    assert np.allclose(rotate_covariances(rot.T, rotate_covariances(rot, cov)), cov, atol=1e-12)


def test_4x4_transforms():
    t = np.eye(4)
    t[:3, :3] = rotation(POSE, 3)
    t[:3, 3] = [1.0, 2.0, 3.0]
    pts = np.random.default_rng(1).normal(0, 3, (7, 3))
    assert np.array_equal(rotation(t), t[:3, :3])
    there = transform_points(t, pts)
    assert np.allclose(there[:, 2], pts[:, 2] + 3.0)
    assert np.allclose(to_frame(t, there), pts, atol=1e-12)


@pytest.mark.parametrize("a", [np.pi, -np.pi, 3 * np.pi, 0.5])
def test_wrap_angle_half_open(a):
    w = wrap_angle(a)
    assert -np.pi < w <= np.pi and np.isclose(np.cos(w), np.cos(a)) and np.isclose(np.sin(w), np.sin(a))


def test_optical_axes_of_a_camera():
    level = optical_rotation(0.0, 0.0)  # looking along x: right is -y, down is -z
    assert np.allclose(level, [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]], atol=1e-15)
    rot = optical_rotation(0.7, 0.3)
    assert np.allclose(rot.T @ rot, np.eye(3)) and np.isclose(np.linalg.det(rot), 1.0)
    assert np.isclose(rot[2, 2], -np.sin(0.3))  # forward dips by the pitch


def test_compose_by_hand_and_its_shapes():
    # a robot at (1, 2) facing +y drives 0.5 m ahead and 0.2 m to its left, turning 3 rad: it ends at
    # (1 - 0.2, 2 + 0.5), facing pi/2 + 3 wrapped into (-pi, pi]
    a, b = [1.0, 2.0, np.pi / 2], [0.5, 0.2, 3.0]
    assert compose(a, b) == pytest.approx([0.8, 2.5, np.pi / 2 + 3.0 - 2 * np.pi], abs=1e-12)
    many = np.array([b, [0.0, 0.0, 0.0], [1.0, 0.0, -np.pi / 2]])
    one_many = compose(a, many)  # one pose and many
    assert one_many.shape == (3, 3) and one_many[1] == pytest.approx(a) and one_many[2] == pytest.approx([1, 3, 0])
    assert compose(many, [0.0, 0.0, 0.0]) == pytest.approx(many)  # many and one: the identity changes nothing
    assert np.array_equal(compose(many, many)[2], compose(many[2], many[2]))  # as many of each, row by row
    grid = compose(many[:, None], many[None])  # shapes that broadcast: every pose in every pose
    assert grid.shape == (3, 3, 3) and np.array_equal(grid[2, 0], compose(many[2], many[0]))
    assert compose(a, np.zeros((0, 3))).shape == (0, 3) and compose(np.zeros((0, 3)), a).shape == (0, 3)
    assert np.allclose(wrap_angle(np.array([[4.0, -4.0]])), [[4.0 - 2 * np.pi, 2 * np.pi - 4.0]], atol=1e-15)
