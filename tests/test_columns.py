"""evaluation/columns.py: each CSV's columns declared once, for its writer (crowdsim/run.py) and its readers."""

import pytest

from crowdsim.run import csv_format
from evaluation.columns import GROUNDTRUTH, RELATIONS, TRACKS


def test_a_reader_picks_only_declared_columns():
    assert RELATIONS.pick("frame", "strength") == ("frame", "strength")
    with pytest.raises(ValueError, match="relations.csv has no column"):
        RELATIONS.pick("frame", "weight")


def test_header_and_formats_follow_the_declaration():
    assert GROUNDTRUTH[:len(TRACKS)] == TRACKS and GROUNDTRUTH.file == "groundtruth.csv"
    assert TRACKS.header == "frame,t,id,x,y,vx,vy"
    fmt = dict(zip(GROUNDTRUTH, csv_format(GROUNDTRUTH)))
    assert [fmt[c] for c in ("frame", "t", "id", "x", "beams", "visible", "group")] == \
        ["%d", "%.2f", "%d", "%.4f", "%d", "%d", "%d"]
