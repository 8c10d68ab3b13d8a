"""HOG features (Dalal & Triggs 2005) by hand: orientation votes, L2-Hys blocks, the score map against single windows,
box overlap and non-maximum suppression."""

import numpy as np
import pytest

from pipeline.detectors.hog import (CELL, HogModel, blocks, box_iou, cells, integral, non_maximum_suppression,
                                    orientation_votes, window_features)


def test_a_vertical_edge_votes_half_each_to_the_bins_beside_zero_degrees():
    # a step from 0 to 100 between columns 3 and 4: the centred gradient is 100 in columns 3 and 4, horizontal
    # (0 degrees, half way between bin 8 centred at 170 and bin 0 at 10)
    rgb = np.zeros((6, 8, 3), np.uint8)
    rgb[:, 4:] = 100
    votes = orientation_votes(rgb)
    assert votes[2, 3].tolist() == pytest.approx([50, 0, 0, 0, 0, 0, 0, 0, 50])
    assert votes[2, 4].sum() == pytest.approx(100) and votes[2, 1].sum() == 0
    # a horizontal edge: 90 degrees, the middle of bin 4 (80-100)
    votes = orientation_votes(np.ascontiguousarray(rgb.transpose(1, 0, 2)))
    assert votes[3, 2].tolist() == pytest.approx([0, 0, 0, 0, 100, 0, 0, 0, 0])


def test_the_looked_up_votes_are_the_per_pixel_formula():
    # the table of orientation_votes against arctan2 per pixel, on random colours
    rng = np.random.default_rng(1)
    rgb = rng.integers(0, 256, (40, 50, 3)).astype(np.uint8)
    # and a tie: pixel (11, 11)'s channels have gradients (4, 3), (3, 4) and (0, 5), the first one's counts
    rgb[11, 10] = rgb[10, 11] = 0
    rgb[11, 12], rgb[12, 11] = (4, 3, 0), (3, 4, 5)
    image = rgb.astype(np.float32)
    gx, gy = np.zeros_like(image), np.zeros_like(image)
    gx[:, 1:-1], gy[1:-1] = image[:, 2:] - image[:, :-2], image[2:] - image[:-2]
    channel = (gx * gx + gy * gy).argmax(axis=-1)[..., None]
    gx, gy = np.take_along_axis(gx, channel, -1)[..., 0], np.take_along_axis(gy, channel, -1)[..., 0]
    position = (np.arctan2(gy, gx) % np.pi) * 9 / np.pi - 0.5
    lower = np.floor(position)
    expected = np.zeros((40, 50, 9), np.float32)
    r, c = np.indices((40, 50))
    expected[r, c, lower.astype(int) % 9] = np.hypot(gx, gy) * (1 - (position - lower))
    expected[r, c, (lower.astype(int) + 1) % 9] = np.hypot(gx, gy) * (position - lower)
    np.testing.assert_allclose(orientation_votes(rgb), expected, rtol=1e-5, atol=1e-3)  # float32 rounding
    np.testing.assert_array_equal(orientation_votes(rgb[:, ::-1]), orientation_votes(rgb[:, ::-1].copy()))
    with pytest.raises(ValueError, match="expected an 8-bit image"):
        orientation_votes(image)

def test_cells_sum_the_votes_and_blocks_are_l2hys_normalised():
    votes = np.ones((16, 16, 9), np.float32)
    c = cells(integral(votes), (0.0, 0.0), 8.0, (2, 2))
    assert c.shape == (2, 2, 9) and np.all(c == 64)
    # a block of four equal cells: 36 equal entries, 1/6 each after L2, not clipped (< 0.2)
    b = blocks(c)
    assert b.shape == (1, 1, 36) and b[0, 0, 0] == pytest.approx(1 / 6, rel=1e-5)
    # one non-zero entry: 1 after L2, clipped to 0.2, 1 again (0.2 / sqrt(0.04 + 1e-6): the norm's epsilon)
    one = np.zeros((2, 2, 9))
    one[0, 0, 0] = 5.0
    assert blocks(one)[0, 0, 0] == pytest.approx(0.2 / np.sqrt(0.04 + 1e-6), rel=1e-6)
    # four entries: 0.5 each, clipped to 0.2, renormalised to 0.5
    four = np.zeros((2, 2, 9))
    four[:, :, 0] = 3.0
    assert blocks(four)[0, 0, [0, 9, 18, 27]] == pytest.approx([0.5] * 4, rel=1e-5)


def test_the_score_map_scores_each_window_as_its_own_features():
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 255, (200, 150, 3)).astype(np.uint8)
    table = integral(orientation_votes(rgb))
    model = HogModel(rng.normal(0, 1, 3780), 0.5, 0.0)
    size = CELL * 1.25  # 10 pixels a cell
    scores = model.score_map(table, size)
    assert scores.shape == (20 - 16 + 1, 15 - 8 + 1)
    for r, c in ((0, 0), (3, 5), (4, 7)):
        u0, v0 = c * size, r * size
        person = np.array([[u0 + 2 * size, v0 + 2 * size, u0 + 6 * size, v0 + 14 * size]])
        features = window_features(table, person)
        assert features.shape == (1, 3780)
        assert scores[r, c] == pytest.approx(features[0] @ model.weight + 0.5, rel=1e-9)


def test_box_overlap_and_non_maximum_suppression():
    boxes = np.array([[0, 0, 10, 20], [1, 0, 11, 20], [30, 0, 40, 20]], float)
    iou = box_iou(boxes, boxes)
    assert iou[0, 1] == pytest.approx(180 / 220) and iou[0, 2] == 0 and iou[0, 0] == pytest.approx(1)
    keep = non_maximum_suppression(boxes, np.array([0.5, 0.9, 0.1]), 0.5)
    assert keep.tolist() == [1, 2]
