"""The leg detector (seed 001 Sec. 4.1) on synthetic scans: circles cast exactly, a wall, a corner."""

import numpy as np
import pytest

from pipeline.detectors.legs import LegDetector, inscribed_angles, pair_legs
from pipeline.detectors.segment_features import jump_segments
from pipeline.types import LaserScan
from scenarios.format import DETECTOR
from scenarios.schema import ScenarioError, validate

STEP = np.radians(0.5)  # seed 001's SICK: 180 degrees at 0.5 degree steps


def cast(circles=(), segments=(), fov=np.pi, step=STEP, range_max=8.0) -> LaserScan:
    """A scan from the origin of circles (cx, cy, r) and line segments ((x0, y0), (x1, y1)): each beam's nearest hit."""
    angles = -fov / 2 + step * np.arange(int(round(fov / step)) + 1)
    d = np.stack([np.cos(angles), np.sin(angles)], 1)
    best = np.full(len(angles), np.inf)
    for cx, cy, r in circles:
        c = np.array([cx, cy])
        along = d @ c
        miss = along ** 2 - (c @ c - r * r)
        t = np.where(miss >= 0, along - np.sqrt(np.maximum(miss, 0)), np.inf)
        best = np.minimum(best, np.where(t > 0, t, np.inf))
    for p0, p1 in segments:
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        e = p1 - p0
        den = d[:, 0] * -e[1] - d[:, 1] * -e[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (p0[0] * -e[1] - p0[1] * -e[0]) / den
            s = (d[:, 0] * p0[1] - d[:, 1] * p0[0]) / den
        hit = (t > 0) & (s >= 0) & (s <= 1)
        best = np.minimum(best, np.where(hit, t, np.inf))
    ranges = np.where(np.isfinite(best), best, np.nan)
    return LaserScan(0.0, "laser", float(angles[0]), step, range_max, ranges, -np.ones(len(angles), np.int64))


def test_inscribed_angles_of_a_circular_arc_are_all_the_same():
    # a leg (r 6 cm) 2 m ahead: at every interior return the inscribed angle is 180 - (arc between the first and last
    # returns) / 2 degrees, and that arc is 2 asin(chord / 2r)
    scan = cast([(2.0, 0.0, 0.06)], step=np.radians(0.25))
    seg = jump_segments(scan, 0.1)
    mean, sd, least = inscribed_angles(seg)
    assert len(mean) == 1 and seg.count[0] == 13
    chord = np.linalg.norm(seg.points[-1] - seg.points[0])
    assert np.degrees(mean[0]) == pytest.approx(180 - np.degrees(np.arcsin(chord / 0.12)), abs=1e-6)
    assert np.degrees(sd[0]) < 1e-4 and least[0] == pytest.approx(mean[0])
    # two returns have no interior point
    mean, sd, least = inscribed_angles(jump_segments(cast([(5.0, 0.0, 0.03)]), 0.1))
    assert np.isnan(mean[0]) and least[0] == np.pi


def test_two_legs_make_one_person_at_their_centre_and_a_wall_none():
    # legs 0.3 m apart across the beam at 3 m; the person's centre is between the legs' centres
    scan = cast([(3.0, -0.15, 0.06), (3.0, 0.15, 0.06)], segments=[((6.0, -3.0), (6.0, 3.0))])
    det = LegDetector().detect(scan)
    assert len(det.position) == 1
    np.testing.assert_allclose(det.position[0, :2], [3.0, 0.0], atol=0.02)
    # the wall alone: flat (inscribed angles near 180 degrees) and far wider than a leg
    assert len(LegDetector().detect(cast(segments=[((6.0, -3.0), (6.0, 3.0))])).position) == 0


def test_a_corner_pointing_at_the_sensor_is_no_leg():
    # a 10 cm box's corner pointing at the sensor at 2 m is as wide as a leg, but its inscribed angles spread from
    # its faces' to the corner's own 90 degrees (a circle's are all equal)
    corner = [((2.0, 0.0), (2.07, 0.07)), ((2.0, 0.0), (2.07, -0.07))]
    scan = cast(segments=corner, step=np.radians(0.25))
    mean, sd, least = inscribed_angles(jump_segments(scan, 0.1))
    assert np.degrees(sd[0]) > 10 and np.degrees(least[0]) == pytest.approx(90, abs=0.5)
    assert len(LegDetector(max_angle_sd_deg=10).legs(scan)) == 0
    assert len(LegDetector(max_angle_sd_deg=15, sharp_angle_deg=95).legs(scan)) == 0
    assert len(LegDetector(max_angle_sd_deg=15, sharp_angle_deg=85).legs(scan)) == 1


def test_pairing_takes_the_closest_legs_first_and_keeps_single_legs_on_request():
    legs = np.array([[0.0, 0.0], [0.3, 0.0], [0.5, 0.0], [3.0, 0.0]])
    # 1-2 (0.2 m) pair first; 0 has no partner left within 0.5 m but 1; 3 is alone
    people = pair_legs(legs, 0.5, single_legs=False)
    np.testing.assert_allclose(people, [[0.4, 0.0]])
    people = pair_legs(legs, 0.5, single_legs=True)
    np.testing.assert_allclose(people, [[0.4, 0.0], [0.0, 0.0], [3.0, 0.0]])


def test_raw_blobs_keep_the_radius_band():
    # a leg (r 6 cm), a thin table leg (r 1 cm) and a wall piece 1.2 m long: only the leg's blob is in [0.03, 0.3]
    scan = cast([(2.0, 0.5, 0.06), (2.0, 1.5, 0.01)], segments=[((4.0, -2.0), (4.0, -0.8))],
                step=np.radians(0.25))
    blobs = LegDetector().raw_blobs(scan)
    assert blobs.modality == "laser_blobs" and len(blobs.position) == 1
    np.testing.assert_allclose(blobs.position[0, :2], [1.95, 0.5], atol=0.03)


def test_blobs_of_too_few_returns_are_left_out_and_come_as_a_named_batch():
    # a leg 2 m away (about 6 returns at 0.5 degrees) and one 12 m away (2 returns, as a grazing wall's pieces)
    scan = cast([(2.0, 0.0, 0.06), (12.0, 0.0, 0.06)], range_max=20.0, step=np.radians(0.5))
    assert len(LegDetector().raw_blobs(scan).position) == 1
    named = LegDetector(blobs=True).detect(scan)
    assert set(named) == {"legs", "blobs"} and named["legs"].modality == "laser2d"
    np.testing.assert_allclose(named["blobs"].position[:, 0], [1.95], atol=0.03)


def test_limits_out_of_order_are_one_error_naming_the_key():
    for params, key in (({"min_width": 0.3, "max_width": 0.2}, "min_width"),
                        ({"min_angle_deg": 170.0}, "min_angle_deg")):
        with pytest.raises(ScenarioError, match=rf"<test>: d\.{key}: .*; expected at most max"):
            validate({"type": "laser_legs", **params}, DETECTOR, "<test>", "d")
