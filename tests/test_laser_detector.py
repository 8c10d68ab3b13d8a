"""Jump-distance segmentation and the geometric person classifier, on scans built from exact circle and line ranges.

The scans have the default laser's layout: 381 beams from -95 deg to +95 deg every 0.5 deg (sensor frame, x ahead).
"""

import numpy as np
import pytest

from pipeline.detectors.laser_segments import SegmentDetector
from pipeline.types import UNKNOWN_VARIANCE, LaserScan

R = 0.18  # body radius (PERSON_HIP_RADIUS)
N_BEAMS = 381
ANGLE_MIN = np.radians(-95.0)
INC = np.radians(0.5)
ANGLES = ANGLE_MIN + INC * np.arange(N_BEAMS)
U = np.stack([np.cos(ANGLES), np.sin(ANGLES)], 1)


def circle_ranges(c, r=R) -> np.ndarray:
    """First hit of each beam on the circle (centre c): t = b - sqrt(b^2 - |c|^2 + r^2), b = u . c; NaN on a miss."""
    c = np.asarray(c, float)
    b = U @ c
    disc = b * b - (c @ c - r * r)
    t = b - np.sqrt(np.where(disc >= 0, disc, np.nan))
    return np.where(t > 0, t, np.nan)


def line_ranges(p, q) -> np.ndarray:
    """First hit of each beam on the segment p-q (solve t u = p + s (q - p), 0 <= s <= 1, t > 0); NaN on a miss."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    d = q - p
    den = U[:, 0] * (-d[1]) - U[:, 1] * (-d[0])  # det [u, -d]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[0] * (-d[1]) - p[1] * (-d[0])) / den
        s = (U[:, 0] * p[1] - U[:, 1] * p[0]) / den
    return np.where((t > 0) & (s >= 0) & (s <= 1), t, np.nan)


def scan_of(*ranges) -> LaserScan:
    r = np.full(N_BEAMS, np.nan)
    for x in ranges:
        r = np.fmin(r, x)
    return LaserScan(0.5, "front_laser", ANGLE_MIN, INC, 20.0, r, np.full(N_BEAMS, -1))


def test_defaults_are_seed_000s():
    d = SegmentDetector()
    assert (d.jump_distance, d.min_points, d.min_width, d.max_width, d.min_bulge, d.position_variance) == (
        0.4, 3, 0.1, 0.9, 0.03, 0.1)


def test_one_body_straight_ahead():
    # Body at (4, 0): half-width asin(0.18/4) = 2.58 deg -> beams -2.5 .. 2.5 deg, 11 points.
    # The detector takes the points' centroid (~ pi/4 r in front of the centre for beams evenly spread across the
    # body) and pushes it back along the ray by pi/8 x chord width; the estimate must land within 5 cm of (4, 0).
    scan = scan_of(circle_ranges((4.0, 0.0)))
    assert np.isfinite(scan.ranges).sum() == 11
    det = SegmentDetector().detect(scan)
    assert len(det) == 1
    np.testing.assert_allclose(det.position[0, :2], [4.0, 0.0], atol=0.05)
    assert det.position[0, 2] == 0.0
    np.testing.assert_allclose(det.covariance[0], np.diag([0.1, 0.1, UNKNOWN_VARIANCE]))
    assert det.stamp == 0.5 and det.frame == "front_laser" and det.modality == "laser2d"
    assert det.confidence[0] == 1.0


@pytest.mark.parametrize("bearing_deg", [0.1, 0.25, 0.4, 30.0, -60.0, 90.0])
def test_one_body_at_4m_any_bearing_is_located(bearing_deg):
    # Whatever the body's phase against the beam grid (10 or 11 beams hit it), the centre estimate stays within 5 cm.
    a = np.radians(bearing_deg)
    c = 4.0 * np.array([np.cos(a), np.sin(a)])
    det = SegmentDetector().detect(scan_of(circle_ranges(c)))
    assert len(det) == 1
    np.testing.assert_allclose(det.position[0, :2], c, atol=0.05)


def test_detection_ids_count_up_across_scans():
    detector = SegmentDetector()
    a = detector.detect(scan_of(circle_ranges((4.0, 1.0)), circle_ranges((4.0, -1.0))))
    b = detector.detect(scan_of(circle_ranges((3.0, 0.0))))
    np.testing.assert_array_equal(a.detection_id, [0, 1])
    np.testing.assert_array_equal(b.detection_id, [2])


@pytest.mark.parametrize("p, q, beams", [((4.0, -0.25), (4.0, 0.25), 15),  # 0.5 m, square to the view
                                         ((3.0, 0.6), (3.4, 0.9), 7),  # 0.5 m, oblique
                                         ((4.0, -1.0), (4.0, 1.0), 57)])  # 2 m
def test_flat_wall_pieces_are_not_persons(p, q, beams):
    scan = scan_of(line_ranges(p, q))
    n = np.isfinite(scan.ranges).sum()
    # the piece is seen as one run of >= 3 points: 2 atan(0.25/4) = 7.2 deg -> 15 beams square to the view,
    # atan2(0.9, 3.4) - atan2(0.6, 3) = 3.5 deg -> 7 beams for the oblique piece, 2 atan(1/4) = 28 deg -> 57 beams
    labels, pts = SegmentDetector().segments(scan)
    assert n == beams and np.all(labels == 0)
    width = np.linalg.norm(pts[-1] - pts[0])
    if np.hypot(*np.subtract(q, p)) < 1.0:
        assert 0.1 <= width <= 0.9  # so the point count and width gates pass: flatness (bulge 0) rejects it
        assert len(SegmentDetector(min_bulge=-1.0).detect(scan)) == 1  # ... as dropping it shows
    else:
        assert width > 0.9
    assert len(SegmentDetector().detect(scan)) == 0


def test_two_bodies_1m_apart_give_two_detections_without_background():
    # Bodies at (4, +-0.5): the beams between them (|a| < 7.1 - 2.5 = 4.6 deg) return nothing -> two segments.
    c = [(4.0, 0.5), (4.0, -0.5)]
    det = SegmentDetector().detect(scan_of(*(circle_ranges(x) for x in c)))
    assert len(det) == 2
    got = det.position[np.argsort(-det.position[:, 1]), :2]
    np.testing.assert_allclose(got, c, atol=0.05)


def test_two_bodies_in_front_of_a_wall_are_split_by_the_jump_distance():
    # Same bodies with a 6 m wall from (8, -3) to (8, 3) behind them: every beam within atan(3/8) = 20.6 deg returns,
    # so only the range jump (~4 m > 0.4 m) at the body edges splits that run. (Wall returns are 8 x 0.5 deg /
    # cos^2(a) <= 0.08 m apart there; a longer wall would add a new segment per beam beyond |a| = 65 deg, where the
    # spacing passes 0.4 m.) Wall pieces: the middle one spans y = 8 tan(+-4.6 deg) = +-0.64, 1.3 m wide, the outer
    # ones about 2.3 m; all are flat -> only the bodies are detected.
    c = [(4.0, 0.5), (4.0, -0.5)]
    scan = scan_of(line_ranges((8.0, -3.0), (8.0, 3.0)), *(circle_ranges(x) for x in c))
    hit = np.isfinite(scan.ranges)
    first, last = np.flatnonzero(hit)[[0, -1]]
    assert np.all(hit[first:last + 1])  # no NaN between the first and the last return
    labels, _ = SegmentDetector().segments(scan)
    assert labels.max() + 1 == 5  # wall | body | wall | body | wall
    det = SegmentDetector().detect(scan)
    assert len(det) == 2
    got = det.position[np.argsort(-det.position[:, 1]), :2]
    np.testing.assert_allclose(got, c, atol=0.05)


def test_touching_bodies_merge_into_one_segment():
    # Bodies at (4, +-0.18) touch at (4, 0). Consecutive returns across the contact are a few cm apart (< 0.4 m), so
    # jump-distance segmentation ("a run of consecutive returns whose neighbours are closer than the jump
    # distance", module docstring) makes one segment of 21 points, 0.7 m wide and round: one detection between them,
    # on the bisector y = 0, about 0.22 m from either true centre.
    c = [(4.0, 0.18), (4.0, -0.18)]
    scan = scan_of(*(circle_ranges(x) for x in c))
    labels, pts = SegmentDetector().segments(scan)
    assert pts.shape[0] == 21 and np.all(labels == 0)
    assert np.linalg.norm(np.diff(pts, axis=0), axis=1).max() < 0.4
    det = SegmentDetector().detect(scan)
    assert len(det) == 1
    assert det.position[0, 1] == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.linalg.norm(det.position[0, :2] - np.array(c), axis=1) > 0.15)


def test_jump_threshold_is_strict():
    # Three returns along one bearing (increment 0) at 4.00, 4.39, 4.80 m: steps 0.39 (< 0.4, joined) and 0.41 (split).
    scan = LaserScan(0.0, "l", 0.0, 0.0, 20.0, np.array([4.0, 4.39, 4.80]), np.full(3, -1))
    labels, _ = SegmentDetector().segments(scan)
    np.testing.assert_array_equal(labels, [0, 0, 1])


def test_nan_beams_split_segments():
    # One NaN inside the 11-point body at (4, 0) splits it into runs of 5 and 5 points.
    ranges = circle_ranges((4.0, 0.0))
    ranges[190] = np.nan  # the beam at 0 deg
    labels, pts = SegmentDetector().segments(scan_of(ranges))
    assert pts.shape[0] == 10
    np.testing.assert_array_equal(labels, [0] * 5 + [1] * 5)
    # Every other return removed: six 1-point runs, none reaches min_points 3 -> no detection
    # (the same body without holes is detected, test_one_body_straight_ahead).
    holed = circle_ranges((4.0, 0.0))
    holed[np.flatnonzero(np.isfinite(holed))[1::2]] = np.nan  # keep returns 1, 3, .., 11 of the 11
    labels, pts = SegmentDetector().segments(scan_of(holed))
    assert pts.shape[0] == 6 and labels.tolist() == list(range(6))
    assert len(SegmentDetector().detect(scan_of(holed))) == 0


def test_beams_reading_range_max_are_no_returns():
    # a driver that reports no return as range_max (no_return: range_max) gives the detector what NaN does: the
    # body's 11 points, split by the beam at 0 deg that returned nothing, and no points 20 m away
    ranges = circle_ranges((4.0, 0.0))
    ranges[190] = np.nan
    as_nan = scan_of(ranges)
    as_max = scan_of(np.where(np.isnan(ranges), 20.0, ranges))
    assert (as_max.ranges == 20.0).sum() == N_BEAMS - 10
    np.testing.assert_array_equal(as_max.returned, np.isfinite(ranges))
    assert np.isnan(as_max.points()[~as_max.returned]).all()
    for scan in (as_nan, as_max):
        labels, pts = SegmentDetector().segments(scan)
        assert pts.shape[0] == 10 and labels.tolist() == [0] * 5 + [1] * 5


def test_far_body_between_two_beams_has_too_few_points():
    # At 18 m the body's half-width is asin(0.18 / 18) = 0.573 deg. Centred at 0.25 deg (between beams), the beams
    # inside (-0.323, 0.823) deg are those at 0 and 0.5 deg: 2 points < min_points 3 -> no detection.
    a = np.radians(0.25)
    scan = scan_of(circle_ranges(18.0 * np.array([np.cos(a), np.sin(a)])))
    assert np.isfinite(scan.ranges).sum() == 2
    np.testing.assert_allclose(np.degrees(ANGLES[np.isfinite(scan.ranges)]), [0.0, 0.5], atol=1e-9)
    assert len(SegmentDetector().detect(scan)) == 0


def test_far_body_centred_on_a_beam_still_has_three_points():
    # Centred on the 0 deg beam, (-0.573, 0.573) deg holds the beams at -0.5, 0 and 0.5 deg: 3 points, so it is
    # detected. Chord: the side beams meet the circle 18 sin(0.5 deg) = 0.157 m off axis, width 0.314 m; their depth
    # in front of the centre is sqrt(0.18^2 - 0.157^2) = 0.088 m against 0.18 m for the middle one: bulge ~0.09 m.
    # (Up to 0.18 / sin(0.5 deg) = 20.6 m a centred body keeps 3 points, i.e. over the whole 20 m range.)
    scan = scan_of(circle_ranges((18.0, 0.0)))
    assert np.isfinite(scan.ranges).sum() == 3
    det = SegmentDetector().detect(scan)
    assert len(det) == 1
    np.testing.assert_allclose(det.position[0, :2], [18.0, 0.0], atol=0.05)


def test_empty_scan_gives_no_detection():
    det = SegmentDetector().detect(scan_of())
    assert len(det) == 0 and det.position.shape == (0, 3) and det.covariance.shape == (0, 3, 3)


def test_noise_does_not_turn_flat_wall_pieces_into_persons():
    # 1.2 cm range noise (the laser default) on a 0.5 m flat piece at 4 m: the mean interior depth stays near 0
    # (sigma ~ 1.2 cm / sqrt(13)), so over 1000 noisy scans at most a handful pass the 3 cm gate; a round body at the
    # same place (mean interior depth ~ pi r / 4 = 14 cm) is found in every scan.
    rng = np.random.default_rng(0)
    detector = SegmentDetector()
    flat = line_ranges((4.0, -0.25), (4.0, 0.25))
    body = circle_ranges((4.0, 0.0))
    false = sum(len(detector.detect(scan_of(flat + rng.normal(0, 0.012, flat.size)))) for _ in range(1000))
    found = sum(len(detector.detect(scan_of(body + rng.normal(0, 0.012, body.size)))) for _ in range(1000))
    assert false <= 5
    assert found == 1000


def test_person_centres_by_hand():
    from pipeline.detectors.laser_segments import _person_centres

    # a round segment (2, -0.2), (1.9, 0), (2, 0.2): chord 0.4 m wide, its middle point 0.1 m nearer the sensor
    # (bulge 0.1 m), centroid (5.9 / 3, 0), centre pi / 8 x 0.4 m beyond it; a flat wall piece at x = 5 (bulge 0)
    # and a two-point segment are not persons
    p = np.array([[2.0, -0.2], [1.9, 0.0], [2.0, 0.2], [5.0, -0.3], [5.0, 0.0], [5.0, 0.3], [8.0, 0.0], [8.0, 0.2]])
    centre = _person_centres(p, np.array([0, 3, 6]), np.array([3, 3, 2]), 3, 0.1, 0.9, 0.03)
    assert centre == pytest.approx(np.array([[5.9 / 3 + np.pi / 8 * 0.4, 0.0]]))


def test_scan_points_hand_worked():
    # beams at 0, 90, 180 and 270 degrees, range_max 5: 1 m ahead -> (1, 0); NaN and 5 m (= range_max) return
    # nothing -> NaN rows; 2 m at 270 degrees -> (2 cos 270, 2 sin 270) = (~0, -2). Made once and kept read-only.
    scan = LaserScan(0.0, "laser", 0.0, np.pi / 2, 5.0, np.array([1.0, np.nan, 5.0, 2.0]),
                     np.full(4, -1))
    p = scan.points()
    np.testing.assert_allclose(p[[0, 3]], [[1.0, 0.0], [0.0, -2.0]], atol=1e-12)
    assert np.isnan(p[[1, 2]]).all() and p is scan.points() and not p.flags.writeable
