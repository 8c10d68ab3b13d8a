"""Seed 003's evaluation (crowdsim/experiments/seed003.py): the 2D and 3D matching rules by hand, the re-entry split,
and the pooled rows."""

import numpy as np
import pytest

from crowdsim.experiments.seed003 import Recorded, Scores, row, track_boxes_in
from pipeline.types import DepthFrame, TrackedPersons

K = np.array([[100.0, 0, 80], [0, 100.0, 60], [0, 0, 1]])
# the camera 1 m above odom's origin, level, looking along +x: optical x = -y, optical y = -z, optical z = x
POSE = np.array([[0.0, 0, 1, 0], [-1, 0, 0, 0], [0, -1, 0, 1], [0, 0, 0, 1]])


def image(stamp, ids, full_boxes, visible):
    return DepthFrame(stamp, "kinect", None, np.zeros((0, 3)), None, np.zeros((120, 160, 3), np.uint8),
                      np.asarray(ids, np.int64), None, np.asarray(full_boxes, float).reshape(-1, 4),
                      np.asarray(visible, float), K, POSE)


def tracks(stamp, ids, xy, height=1.7):
    n = len(ids)
    t = TrackedPersons(stamp, "odom", np.asarray(ids, np.int64), np.ones(n, bool), np.zeros(n, bool),
                       np.full(n, -1), np.asarray(xy, float).reshape(-1, 2), np.zeros((n, 2)), np.zeros((n, 2, 2)),
                       np.zeros((n, 2, 2)), np.zeros(n))
    t.height = np.full(n, height)
    return t


# person 7 at (4, 0), 1.7 m: feet at v = 60 + 100 / 4 = 85, head at 60 - 100 0.7 / 4 = 42.5, u = 80; the truth box
# is 42.5 high, 21.25 wide around u = 80. Person 8 (3, -0.8), only 30% visible: u = 80 + 100 0.8 / 3
SEVEN = [70.0, 42.5, 90.0, 85.0]
U8, TOP8, FOOT8 = 80 + 80 / 3, 60 - 70 / 3, 60 + 100 / 3
EIGHT = [U8 - 5, TOP8, U8 + 5, FOOT8]


def test_a_tracks_box_is_its_floor_point_up_its_height_half_as_wide():
    boxes = track_boxes_in(image(0.0, [], [], []), tracks(0.0, [1, 2, 3], [[4, 0], [4, 0.1], [-2, 0]]))
    np.testing.assert_allclose(boxes[0], [80 - 10.625, 42.5, 80 + 10.625, 85], atol=1e-9)
    np.testing.assert_allclose(boxes[1], [80 - 2.5 - 10.625, 42.5, 80 - 2.5 + 10.625, 85], atol=1e-9)  # 2.5 px left
    assert (boxes[2] == 0).all()  # behind the camera: no box


def test_2d_and_3d_scores_and_the_reentry_split_by_hand():
    scores = Scores()
    # t 0: 7 matched by track 1 at (4, 0.1): 2D IoU 18.75 / 23.75 (2.5 px off), 3D 0.1 m; track 9 on the hardly
    # visible 8 is no false positive; track 4 at (4, 0.5) is 12.5 px off (IoU 8.75 / 33.75 < 0.5) and 0.5 m off: a
    # false positive in both
    scores.update(Recorded(image(0.0, [7, 8], [SEVEN, EIGHT], [0.9, 0.3]), np.array([7, 8]),
                           np.array([[4.0, 0.0], [3.0, -0.8]])),
                  tracks(0.0, [1, 9, 4], [[4, 0.1], [3, -0.8], [4, 0.5]]))
    # t 0.5: 7 has left; track 1 stays, a false positive
    scores.update(Recorded(image(0.5, [], [], []), np.zeros(0, np.int64), np.zeros((0, 2))),
                  tracks(0.5, [1], [[4, 0.1]]))
    # t 2: 7 is back, on track 2: a switch after 2 s away, a re-entry; t 2.1: on track 3, a switch of the other kind
    for stamp, track in ((2.0, 2), (2.1, 3)):
        scores.update(Recorded(image(stamp, [7], [SEVEN], [0.9]), np.array([7]), np.array([[4.0, 0.0]])),
                      tracks(stamp, [track], [[4, 0]]))
    counts = scores.counts()
    # instances, matches, FP, FN, ID switches, re-entries, summed quality (IoU in 2D, metres in 3D)
    np.testing.assert_allclose(counts["2d"], [3, 3, 2, 0, 2, 1, 18.75 / 23.75 + 2], atol=1e-9)
    np.testing.assert_allclose(counts["3d"], [3, 3, 2, 0, 2, 1, 0.1], atol=1e-9)


def test_rows_pool_the_runs_instances():
    def run(situation, motion, counts):
        return {"situation": situation, "motion": motion, "counts": {"full": {"2d": counts, "3d": counts}}}

    results = {"runs": [run("group", "still", [10, 8, 1, 2, 1, 0, 6.0]),
                        run("running", "still", [30, 30, 0, 0, 1, 1, 27.0]),
                        run("group", "arc", [5, 5, 5, 0, 0, 0, 4.0])]}
    # still: 40 instances, 38 matches (IoU 33), FP 1, FN 2, 2 switches (1 re-entry)
    motp, mota, fp, fn, ids, reentries = row(results, "full", "2d", motion="still")
    assert motp == pytest.approx(100 * 33 / 38) and mota == pytest.approx(100 * (1 - 5 / 40))
    assert (fp, fn, ids, reentries) == (pytest.approx(2.5), pytest.approx(5.0), 2, 1)
    assert row(results, "full", "3d", situation="group")[0] == pytest.approx(10 / 13)  # metres, not %
    assert row(results, "full", "2d", situation="side_by_side")[4:] == (0, 0)
