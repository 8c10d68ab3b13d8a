"""HSV histograms and the Bhattacharyya distance (seed 001 Sec. 4.3, 5.2.5) by hand."""

import colorsys

import numpy as np
import pytest

from pipeline.appearance import BINS, bhattacharyya, bin_image, blend, histogram, hsv


def test_hsv_matches_the_standard_library():
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (500, 3)).astype(np.uint8)
    h, s, v = hsv(rgb)
    expected = np.array([colorsys.rgb_to_hsv(*(np.array(c) / 255.0)) for c in rgb.tolist()])
    np.testing.assert_allclose(h, expected[:, 0], atol=1e-6)
    np.testing.assert_allclose(s, expected[:, 1], atol=1e-6)
    np.testing.assert_allclose(v, expected[:, 2], atol=1e-6)


def test_bins_of_colours_and_greys():
    # pure red: hue 0, saturation 1 -> bin 0 x 8 + 7; pure blue: hue 2/3 -> 5 x 8 + 7; mid grey (value 128/255 =
    # 0.502) has no colour -> 64 + 4; black -> 64
    rgb = np.array([[[255, 0, 0], [0, 0, 255], [128, 128, 128], [0, 0, 0]]], np.uint8)
    assert bin_image(rgb).tolist() == [[7, 47, 68, 64]]
    # dark red (value 0.16 <= 0.2) counts as grey
    assert bin_image(np.array([[[40, 0, 0]]], np.uint8)).tolist() == [[64 + 1]]


def binned_by_hand(image):
    """The 72 bins from the HSV arithmetic: hue x 8 + saturation where coloured, 64 + value elsewhere."""
    hue, saturation, value = hsv(image)
    h, s, v = (np.minimum((x * 8).astype(int), 7) for x in (hue, saturation, value))
    return np.where((saturation > 0.1) & (value > 0.2), h * 8 + s, 64 + v)


def test_looked_up_bins_are_the_arithmetics_for_new_and_seen_colours():
    rng = np.random.default_rng(1)
    image = rng.integers(0, 256, (40, 50, 3)).astype(np.uint8)
    assert (bin_image(image) == binned_by_hand(image)).all()  # colours met for the first time
    mixed = image.copy()
    mixed[::2] = rng.integers(0, 256, mixed[::2].shape)  # half the rows new colours, half seen ones
    assert (bin_image(mixed) == binned_by_hand(mixed)).all()
    assert (bin_image(image) == binned_by_hand(image)).all()  # all seen


def test_histogram_of_a_box_and_the_bhattacharyya_distance():
    bins = np.zeros((4, 6), np.uint8)
    bins[:, 3:] = 47
    h = histogram(bins, (2, 0, 6, 4))  # columns 2..5: one red column of 4, three blue
    assert h.shape == (BINS,) and h[0] == pytest.approx(0.25) and h[47] == pytest.approx(0.75)
    assert histogram(bins, (7, 0, 9, 4)).sum() == 0  # outside the image
    red, blue = histogram(bins[:, :3]), histogram(bins[:, 3:])
    assert bhattacharyya(red, red) == pytest.approx(0.0, abs=1e-9)
    assert bhattacharyya(red, blue) == pytest.approx(1.0)
    # sqrt(1 - sqrt(0.25 x 1)) = sqrt(0.5)
    assert bhattacharyya(h, blue) == pytest.approx(np.sqrt(1 - np.sqrt(0.75)))
    assert bhattacharyya(h, red) == pytest.approx(np.sqrt(0.5))


def test_colour_model_update_keeps_ninety_percent():
    old, new = np.eye(BINS)[0], np.eye(BINS)[1]
    updated = blend(old, new)
    assert updated[0] == pytest.approx(0.9) and updated[1] == pytest.approx(0.1) and updated.sum() == pytest.approx(1)
