"""Seed 003's online colour classifier: histograms and box features by hand, and two colours told apart after a few
updates."""

import numpy as np
import pytest

from pipeline.tracking.online_boost import OnlineColourClassifier, colour_histogram


def test_the_joint_histogram_and_a_box_feature_by_hand():
    h = colour_histogram(np.array([[0, 0, 0], [255, 255, 255], [200, 10, 10], [200, 10, 10]]))
    # 16 bins a channel: black in bin (0, 0, 0), white (15, 15, 15), the red (12, 0, 0) twice
    assert h[0] == 0.25 and h[-1] == 0.25 and h[(12 * 16 + 0) * 16 + 0] == 0.5 and h.sum() == 1.0
    c = OnlineColourClassifier(np.random.default_rng(0), pool=3, selectors=2)
    c.boxes = np.array([[[0, 16], [0, 16], [0, 16]],  # everything
                        [[8, 16], [0, 16], [0, 16]],  # the bright reds: white and the red
                        [[0, 1], [0, 1], [0, 8]]])  # black only
    np.testing.assert_allclose(c.features(h), [1.0, 0.75, 0.25])


def pixels(rng, rgb, n=400, spread=20):
    return np.clip(rng.normal(rgb, spread, (n, 3)), 0, 255).astype(np.uint8)


def test_two_colours_are_told_apart_after_a_few_updates():
    rng = np.random.default_rng(1)
    classifier = OnlineColourClassifier(np.random.default_rng(2))
    red, blue = (180, 40, 40), (40, 60, 170)
    for _ in range(5):
        classifier.update(colour_histogram(pixels(rng, red)), True)  # the track's detection
        classifier.update(colour_histogram(pixels(rng, blue)), False)  # another detection of the frame
        classifier.update(colour_histogram(rng.integers(0, 256, (400, 3))), False)  # a random window
    assert classifier.confidence(colour_histogram(pixels(rng, red))) > 0.5
    assert classifier.confidence(colour_histogram(pixels(rng, blue))) < -0.5
    assert (classifier.alpha > 0).sum() >= 10  # many selectors found a useful box


def test_no_opinion_before_any_update_and_all_alike_before_a_negative():
    classifier = OnlineColourClassifier(np.random.default_rng(3))
    assert classifier.confidence(colour_histogram(np.zeros((5, 3), np.uint8))) == 0.0
    classifier.update(colour_histogram(np.full((5, 3), 200, np.uint8)), True)  # positives only: no boundary yet
    assert classifier.confidence(colour_histogram(np.zeros((5, 3), np.uint8))) == pytest.approx(1.0)
