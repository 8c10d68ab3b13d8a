"""Sigma-Delta background subtraction and person-shaped blobs (seed 001 Sec. 4.2) on tiny image sequences."""

import numpy as np

from pipeline.detectors.background import SigmaDelta, person_blobs


def frame(square=None, level=100, size=(8, 8)):
    image = np.full(size + (3,), level, np.uint8)
    if square is not None:
        v0, u0, value = square
        image[v0:v0 + 2, u0:u0 + 2] = value
    return image


def test_sigma_delta_finds_a_square_and_absorbs_it_when_it_stays():
    sd = SigmaDelta(bootstrap=3)
    for _ in range(3):
        assert not sd.update(frame()).any()  # the model starts from the median of three frames
    # a bright square (200 on 100): O = |101 - 200| = 99 > V = 3 there, nothing elsewhere
    mask = sd.update(frame((2, 3, 200)))
    assert mask.sum() == 4 and mask[2:4, 3:5].all()
    assert sd.background[2, 3, 0] == 101 and sd.spread[2, 3, 0] == 3
    # it stays: after t frames O = 100 - t and V = 2 + t, so it is foreground while 100 - t > 2 + t, t <= 48
    for t in range(2, 60):
        mask = sd.update(frame((2, 3, 200)))
        assert mask[2, 3] == (t <= 48), t
    # the square leaves after 59 frames: the background (159) comes back a level a frame, and the spread, grown by a
    # level a frame while 2 O > V (to 61), stays above the ghost's difference (|158 - 100| = 58 against V = 62)
    assert sd.background[2, 3, 0] == 159 and sd.spread[2, 3, 0] == 61
    assert not sd.update(frame())[2, 3]
    sd.reset()
    assert sd.background is None


def test_person_blobs_keep_upright_shapes_of_some_size():
    mask = np.zeros((60, 80), bool)
    mask[10:40, 5:15] = True  # 10 wide, 30 high: aspect 3, 300 pixels
    mask[50:56, 30:60] = True  # lying: aspect 0.2
    mask[5:7, 60:62] = True  # speckle: gone in the opening
    mask[20:32, 70:74] = True  # upright but 48 pixels
    boxes = person_blobs(mask, min_area=100)
    assert boxes.tolist() == [[5, 10, 15, 40]]
    assert len(person_blobs(np.zeros((10, 10), bool))) == 0
