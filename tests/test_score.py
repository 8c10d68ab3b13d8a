"""The tracking object: HOTA and OSPA see only what counts, as CLEAR-MOT does."""

import pytest

from evaluation import Sequence
from evaluation.score import score_tracking
from evaluation.stream import SequencePair


def test_tracks_on_ignored_persons_are_left_out_of_hota_and_ospa():
    # person 1 tracked exactly by 10 in two frames; person 2 occluded in both and followed by track 20
    gt = Sequence.from_rows([0, 0, 1, 1], [1, 2, 1, 2], [[0, 0], [5, 0], [0, 0], [5, 0]],
                            ignore=[False, True, False, True])
    tracks = Sequence.from_rows([0, 0, 1, 1], [10, 20, 10, 20], [[0, 0], [5, 0], [0, 0], [5, 0]])
    s = score_tracking(SequencePair(gt, tracks))
    # what counts is one person tracked exactly: every measure perfect; were track 20 counted, DetA would be 2/3
    # and OSPA (two tracks for one person, c = 1) 0.5 a frame
    assert (s["mota"], s["fp"], s["hota"], s["deta"], s["assa"], s["loca"]) == (1.0, 0, 1.0, 1.0, 1.0, 1.0)
    assert s["ospa_m"] == 0.0 and s["ospa_t_m"] == 0.0
    assert s["hota_per_alpha"]["alpha"][0] == pytest.approx(0.05)
