"""Seed 001's security zones, worked by hand: the disc and the sector ahead of a walker, the disc alone for a
standing person, and ray distances to the zones against the analytic ray-disc intersection."""

import numpy as np
import pytest

from pipeline.navigation.zones import SecurityZones
from pipeline.types import TrackedPersons

ZONES = SecurityZones(r=0.5, R=1.5, omega=np.radians(30.0), standing_speed=0.25)


def persons(position, velocity) -> TrackedPersons:
    position, velocity = np.atleast_2d(np.asarray(position, float)), np.atleast_2d(np.asarray(velocity, float))
    n = len(position)
    cov = np.tile(0.01 * np.eye(2), (n, 1, 1))
    return TrackedPersons(0.0, "odom", np.arange(1, n + 1), np.ones(n, bool), np.zeros(n, bool),
                          np.full(n, -1), position, velocity, cov, cov.copy(), np.zeros(n))


def test_a_walker_heading_along_x_has_the_sector_ahead_and_the_disc_around():
    walker = persons([0.0, 0.0], [1.2, 0.0])
    # sector: within R = 1.5 m and within +-15 deg of the heading (omega = 30 deg is the full opening)
    inside = [[1.4, 0.0], [1.4, 0.3], [1.0, -0.2], [0.45, 0.0], [0.0, 0.45], [-0.45, 0.0], [0.0, -0.45]]
    # 1.4 m ahead but 17.8 deg off; beyond R; beside and behind beyond r
    outside = [[1.4, 0.45], [1.4, -0.45], [1.6, 0.0], [0.0, 0.6], [0.0, -0.6], [-0.6, 0.0], [-1.4, 0.0]]
    assert ZONES.contains(np.array(inside), walker).all()
    assert not ZONES.contains(np.array(outside), walker).any()


def test_the_sector_turns_with_the_heading():
    ahead = np.array([[0.0, 1.4]])
    assert ZONES.contains(ahead, persons([0.0, 0.0], [0.0, 1.2])).all()
    assert not ZONES.contains(ahead, persons([0.0, 0.0], [1.2, 0.0])).any()
    heading = np.radians(135.0)
    walker = persons([2.0, -1.0], [np.cos(heading), np.sin(heading)])
    along = np.array([2.0, -1.0]) + 1.4 * np.array([[np.cos(heading), np.sin(heading)]])
    beside = np.array([2.0, -1.0]) + 1.4 * np.array([[np.cos(heading + 0.4), np.sin(heading + 0.4)]])
    assert ZONES.contains(along, walker).all()
    assert not ZONES.contains(beside, walker).any()


def test_a_standing_person_gets_the_disc_alone():
    standing = persons([0.0, 0.0], [0.2, 0.0])  # below 0.25 m/s
    assert ZONES.contains(np.array([[0.45, 0.0], [-0.45, 0.0], [0.0, 0.45]]), standing).all()
    assert not ZONES.contains(np.array([[1.0, 0.0], [1.4, 0.0]]), standing).any()
    assert ZONES.contains(np.array([[1.0, 0.0]]), persons([0.0, 0.0], [0.25, 0.0])).all()  # at the threshold: walks


def test_points_are_tested_against_every_zone():
    two = persons([[0.0, 0.0], [5.0, 0.0]], [[0.0, 0.0], [0.0, -1.0]])
    got = ZONES.contains(np.array([[0.3, 0.0], [5.0, -1.0], [5.0, 1.0], [2.5, 0.0]]), two)
    assert got.tolist() == [True, True, False, False]
    assert not ZONES.contains(np.array([[0.0, 0.0]]), persons(np.zeros((0, 2)), np.zeros((0, 2)))).any()


def ray_disc(origin, angle, centre, radius) -> float:
    """The entry distance of one ray into one disc, by the textbook formula."""
    u = np.array([np.cos(angle), np.sin(angle)])
    c = np.asarray(centre) - origin
    if c @ c <= radius ** 2:
        return 0.0
    b = c @ u
    h2 = c @ c - b * b
    if b < 0 or h2 > radius ** 2:
        return np.inf
    return b - np.sqrt(radius ** 2 - h2)


def test_zone_ranges_of_standing_persons_are_the_analytic_ray_disc_distances():
    origin = np.array([0.5, -0.2])
    centres = np.array([[3.0, 0.0], [-1.0, 2.0], [0.6, -3.0], [4.0, 0.3]])
    angles = np.linspace(-np.pi, np.pi, 721)[:-1]
    got = ZONES.zone_ranges(origin, angles, centres, np.zeros(4), np.zeros(4, bool))
    want = [min(ray_disc(origin, a, c, 0.5) for c in centres) for a in angles]
    np.testing.assert_allclose(got, want, atol=1e-9)
    assert np.isfinite(got).sum() > 20 and np.isinf(got).sum() > 300


def test_zone_ranges_reach_the_sector_of_a_walker_coming_head_on():
    # a walker 3 m ahead walking towards the origin: the ray along x meets the sector's arc at R = 1.5 m from them
    got = ZONES.zone_ranges(np.zeros(2), np.array([0.0, 0.1, np.pi / 2]), np.array([[3.0, 0.0]]), np.array([np.pi]),
                            np.array([True]))
    assert got[0] == pytest.approx(1.5)
    # 0.1 rad off the axis: the ray meets the arc (the sector's edges are at +-15 deg about the walker)
    t = 3.0 * np.cos(0.1) - np.sqrt(1.5 ** 2 - (3.0 * np.sin(0.1)) ** 2)
    assert got[1] == pytest.approx(t)
    assert np.isinf(got[2])
    inside = ZONES.zone_ranges(np.array([2.0, 0.0]), np.array([0.0]), np.array([[3.0, 0.0]]), np.array([np.pi]),
                               np.array([True]))
    assert inside[0] == 0.0


def test_zone_ranges_agree_with_contains_along_each_ray():
    rng = np.random.default_rng(3)
    centres = rng.uniform(-4, 4, (6, 2))
    headings = rng.uniform(-np.pi, np.pi, 6)
    walking = np.array([True, True, True, True, False, True])
    origin = np.array([0.1, 0.2])
    angles = np.linspace(-np.pi, np.pi, 181)[:-1]
    ranges = ZONES.zone_ranges(origin, angles, centres, headings, walking)
    steps = np.arange(0.0, 12.0, 0.002)
    for a, got in zip(angles, ranges):
        march = origin + steps[:, None] * np.array([np.cos(a), np.sin(a)])
        hit = np.flatnonzero(ZONES.inside_each(march, centres, headings, walking).any(axis=1))
        want = steps[hit[0]] if hit.size else np.inf
        if np.isinf(want):
            assert np.isinf(got) or got > 11.99
        else:
            assert got == pytest.approx(want, abs=0.0021)


def test_bad_zone_parameters_are_refused():
    with pytest.raises(ValueError, match="omega"):
        SecurityZones(omega=4.0)
    with pytest.raises(ValueError, match="r and R"):
        SecurityZones(r=0.0)
