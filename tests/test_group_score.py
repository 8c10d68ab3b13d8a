"""The group scores from a run's files (evaluation/group_score.py): fed by the tracking scores' own reading and
CLEAR-MOT matching, with the frames that only relations.csv or groups.csv has scored as frames without persons."""

import pytest

from evaluation.group_score import GroupScore, score_groups
from evaluation.score import score_tracking
from evaluation.stream import CsvPair

GT = ("frame,t,id,x,y,range,in_range,visible,group\n"
      "0,0.00,1,0.0,0.0,1.0,1,1,5\n0,0.00,2,1.0,0.0,1.0,1,1,5\n"
      "1,0.04,1,0.0,0.0,1.0,1,1,5\n1,0.04,2,1.0,0.0,1.0,1,1,5\n")
TRACKS = ("frame,t,id,x,y,vx,vy\n"
          "0,0.00,7,0.05,0.0,0,0\n0,0.00,8,1.05,0.0,0,0\n1,0.04,7,0.05,0.0,0,0\n1,0.04,8,1.05,0.0,0,0\n")
RELATIONS = "frame,t,track_a,track_b,strength\n0,0.00,7,8,0.9\n"
# frame 4 has a tracked group but neither ground truth nor tracks: a false positive group
GROUPS = ("frame,t,group,id,x,y,age\n0,0.00,3,7,0.5,0,0\n0,0.00,3,8,0.5,0,0\n1,0.04,3,7,0.5,0,0.04\n"
          "1,0.04,3,8,0.5,0,0.04\n4,0.16,9,7,0.5,0,0\n4,0.16,9,8,0.5,0,0\n")


@pytest.fixture
def files(tmp_path):
    paths = []
    for name, text in (("gt.csv", GT), ("tracks.csv", TRACKS), ("relations.csv", RELATIONS), ("groups.csv", GROUPS)):
        (tmp_path / name).write_text(text)
        paths.append(tmp_path / name)
    return paths


def test_group_scores_worked_by_hand(files):
    groups = score_groups(*files)
    # frames 0 and 1: the true group {1, 2} is tracked as group 3; frame 4: group 9 of two unmatched tracks
    assert (groups["frames"], groups["true_groups"], groups["detected_groups"]) == (3, 2, 3)
    assert groups["tracking"] == {"gt": 2, "tp": 2, "fp": 1, "fn": 0, "id_switches": 0, "mota": 0.5}
    # the pair of persons 1 m apart in frames 0 and 1, related (0.9) in frame 0 only
    pairwise = groups["pairwise"]
    assert (pairwise["pairs"], pairwise["positives"], pairwise["precision"], pairwise["recall"]) == (2, 2, 1.0, 0.5)


def test_one_reading_gives_both_scores_as_each_alone(files):
    gt, tracks, relations, groups = files
    group_score = GroupScore(relations, groups)
    tracking = score_tracking(CsvPair(gt, tracks, groups=True), 1.0, group_score.add)
    assert tracking == score_tracking(CsvPair(gt, tracks), 1.0)
    assert group_score.result() == score_groups(*files)
