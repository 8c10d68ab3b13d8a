"""``crowdsim evaluate`` and ``evaluate-nav`` read their CSVs strictly (issue 28, point 4): UTF-8 with or without a
byte order mark; NaN, inf, ids beyond what a float holds exactly, text that is no number and a ground truth without
its visibility column refused, each as one error naming the file, the line and the column."""

import json

import pytest

from crowdsim.cli import main
from evaluation.group_score import score_groups
from evaluation.io import EvaluationInputError, read_table, read_text, sequence_chunks, table_chunks
from evaluation.navigation import read_nav_run
from evaluation.stream import CsvPair
from test_cli import one_error_line

GT = "frame,t,id,x,y,range,in_range,visible,group\n"
GT_ROWS = ("0,0.00,1,2.0,0.0,2.0,1,1,-1\n0,0.00,2,4.0,1.0,4.1,1,1,-1\n"
           "1,0.04,1,2.04,0.0,2.0,1,1,-1\n1,0.04,2,4.0,1.0,4.1,1,0,-1\n"
           "2,0.08,1,2.08,0.0,2.1,1,1,-1\n2,0.08,2,4.0,1.0,4.1,1,1,-1\n")
TRACKS = "frame,t,id,x,y,vx,vy\n"
TRACK_ROWS = "0,0.00,7,2.05,0.02,1,0\n1,0.04,7,2.09,0.01,1,0\n1,0.04,8,4.05,1.03,0,0\n2,0.08,7,2.12,0.0,1,0\n"
RELATIONS = "frame,t,track_a,track_b,strength\n1,0.04,7,8,0.25\n"
GROUPS = "frame,t,group,id,x,y,age\n"


def write(path, text, encoding="utf-8"):
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return str(path)


def error_of(read) -> str:
    with pytest.raises(EvaluationInputError) as e:
        read()
    return str(e.value)


@pytest.mark.parametrize("rows, expect", [
    ("0,0.00,7,nan,0.02,1,0\n", "line 2, column x must hold finite numbers, got 'nan'"),
    ("0,0.00,7,2.05,0.02,1,0\n1,0.04,7,2.09,inf,1,0\n", "line 3, column y must hold finite numbers, got 'inf'"),
    ("0,-inf,7,2.05,0.02,1,0\n", "line 2, column t must hold finite numbers, got '-inf'"),
    # 1e20 wrapped to INT64_MIN; 2^53 + 1 is read as 2^53, the id of another track
    ("0,0.00,100000000000000000000,2.05,0.02,1,0\n",
     "line 2, column id must hold whole numbers (below 2^53 in size), got '100000000000000000000'"),
    ("0,0.00,9007199254740993,2.05,0.02,1,0\n", "line 2, column id must hold whole numbers"),
    ("0.5,0.00,7,2.05,0.02,1,0\n", "line 2, column frame must hold whole numbers (below 2^53 in size), got '0.5'"),
    ("0,0.00,7,2.05,abc,1,0\n", "line 2, column y: 'abc' is not a number; expected 7 numbers per row"),
    ("0,0.00,7,2.05,0.02,1,0\n1,0.04,7,2.09\n", "line 3 has 4 values; expected 7 numbers per row"),
])
def test_a_bad_value_in_a_tracks_file_is_named_by_file_line_and_column(tmp_path, rows, expect):
    tracks = write(tmp_path / "tracks.csv", TRACKS + rows)
    assert error_of(lambda: list(sequence_chunks(tracks, occlusion=False))).startswith(f"{tracks}: {expect}")


def test_an_unread_column_may_hold_anything_numeric(tmp_path):
    # vx and vy are not scored: a tracker that has no velocity yet may write nan there
    tracks = write(tmp_path / "tracks.csv", TRACKS + "0,0.00,7,2.05,0.02,nan,nan\n")
    (seq,) = sequence_chunks(tracks, occlusion=False)
    assert seq.id.tolist() == [7] and seq.position.tolist() == [[2.05, 0.02]]


def test_the_line_is_the_files_own_across_chunks_blank_lines_and_comments(tmp_path):
    tracks = write(tmp_path / "tracks.csv", TRACKS + "0,0.00,7,2.05,0.02,1,0\n\n# a comment\n   \n"
                   "1,0.04,7,2.09,0.01,1,0  # trailing comment\n2,0.08,7,2.12,nan,1,0\n")  # line 7
    for rows in (1, 2, 3, 100):
        message = error_of(lambda: list(sequence_chunks(tracks, occlusion=False, chunk_rows=rows)))
        assert message == f"{tracks}: line 7, column y must hold finite numbers, got 'nan'"


def test_the_ground_truths_range_and_visibility_are_checked_where_read(tmp_path):
    gt = write(tmp_path / "gt.csv", GT + "0,0.00,1,2.0,0.0,nan,1,1,-1\n0,0.00,2,4.0,1.0,4.1,1,nan,-1\n")
    assert error_of(lambda: list(sequence_chunks(gt, max_range=12.0))) == \
        f"{gt}: line 2, column range must hold finite numbers, got 'nan'"
    assert error_of(lambda: list(sequence_chunks(gt))) == \
        f"{gt}: line 3, column visible must hold 0 or 1, got 'nan'"
    # without --max-range the range is not read, with --no-occlusion the visibility is not
    assert [len(s) for s in sequence_chunks(gt, occlusion=False)] == [2]


def test_relations_and_groups_are_checked_too(tmp_path):
    gt, tracks = write(tmp_path / "gt.csv", GT + GT_ROWS), write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    groups = write(tmp_path / "groups.csv", GROUPS)
    relations = write(tmp_path / "relations.csv", RELATIONS.replace("0.25", "nan"))
    assert error_of(lambda: score_groups(gt, tracks, relations, groups)) == \
        f"{relations}: line 2, column strength must hold numbers from 0 to 1, got 'nan'"
    relations = write(tmp_path / "relations.csv", RELATIONS.replace(",8,", ",1e20,"))
    assert error_of(lambda: score_groups(gt, tracks, relations, groups)).startswith(
        f"{relations}: line 2, column track_b must hold whole numbers")
    groups = write(tmp_path / "groups.csv", GROUPS + "1,0.04,3,7,2,0,inf\n1,0.04,3.5,8,4,1,1\n")  # age unread
    assert error_of(lambda: score_groups(gt, tracks, write(tmp_path / "r.csv", RELATIONS), groups)) == \
        f"{groups}: line 3, column group must hold whole numbers (below 2^53 in size), got '3.5'"


def test_a_file_that_is_not_utf8_is_named_with_its_line(tmp_path):
    tracks = write(tmp_path / "tracks.csv", (TRACKS + TRACK_ROWS).replace("2.09", "2.09 caf\u00e9"), "latin-1")
    assert error_of(lambda: list(sequence_chunks(tracks, occlusion=False))) == \
        f"{tracks}: line 3 is not UTF-8 text (byte 0xe9, 18 bytes into the line); expected a file saved as UTF-8"


def test_a_header_naming_a_column_twice_is_refused(tmp_path):
    tracks = write(tmp_path / "tracks.csv", "frame,t,id,x,y,x\n0,0,7,1,2,3\n")
    assert "names column(s) x twice" in error_of(lambda: list(sequence_chunks(tracks, occlusion=False)))


def test_a_byte_order_mark_scores_the_same_figures_as_without(tmp_path, capsys):
    gt, tracks = write(tmp_path / "gt.csv", GT + GT_ROWS), write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    bom_gt = write(tmp_path / "bom_gt.csv", "\ufeff" + GT + GT_ROWS)
    bom_tracks = write(tmp_path / "bom_tracks.csv", "\ufeff" + TRACKS + TRACK_ROWS)
    assert open(bom_gt, "rb").read(3) == b"\xef\xbb\xbf"
    figures = []
    for k, (g, t) in enumerate(((gt, tracks), (bom_gt, bom_tracks))):
        js = tmp_path / f"{k}.json"
        assert main(["evaluate", "--gt", g, "--tracks", t, "--json", str(js)]) == 0
        figures.append(json.loads(js.read_text())["tracking"])
    capsys.readouterr()
    assert figures[0] == figures[1]
    # 5 counted rows (person 2 occluded in frame 1, where track 8 is excused), person 1 matched in all 3
    # frames, person 2 missed in frames 0 and 2, no false positive
    assert (figures[0]["gt"], figures[0]["matches"], figures[0]["fn"], figures[0]["fp"]) == (5, 3, 2, 0)
    assert figures[0]["mota"] == pytest.approx(0.6)
    assert read_table(bom_tracks)["frame"].tolist() == [0, 1, 1, 2]


def test_the_library_still_reads_visible_only_where_there(tmp_path):
    # crowdsim run scores its own files this way (they have the column); only crowdsim evaluate asks for it
    gt, tracks = write(tmp_path / "gt.csv", TRACKS + TRACK_ROWS), write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    assert sum(len(g) for g, _ in CsvPair(gt, tracks)) == 4
    assert "no column 'visible'" in error_of(lambda: list(sequence_chunks(gt, visible_column="visible")))


def evaluate_fails(capsys, tmp_path, *argv) -> str:
    """The one error line of ``crowdsim evaluate ARGV --json``, which must write nothing."""
    js = tmp_path / "out.json"
    assert main(["evaluate", *argv, "--json", str(js)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and not js.exists()
    return one_error_line(err)


@pytest.mark.parametrize("case, expect", [
    ("nan", "tracks.csv: line 3, column x must hold finite numbers, got 'nan'"),
    ("huge id", "tracks.csv: line 2, column id must hold whole numbers (below 2^53 in size), got "
                "'100000000000000000000'"),
    ("latin-1", "tracks.csv: line 3 is not UTF-8 text (byte 0xe9"),
])
def test_bad_tracks_through_the_command_line(tmp_path, capsys, case, expect):
    rows = {"nan": TRACK_ROWS.replace("2.09", "nan"), "huge id": TRACK_ROWS.replace(",7,", ",100000000000000000000,"),
            "latin-1": TRACK_ROWS.replace("2.09", "2.09 caf\u00e9")}[case]
    gt = write(tmp_path / "gt.csv", GT + GT_ROWS)
    tracks = write(tmp_path / "tracks.csv", TRACKS + rows, "latin-1")
    assert f"{tmp_path}/{expect}" in evaluate_fails(capsys, tmp_path, "--gt", gt, "--tracks", tracks)


def test_nan_relation_strength_through_the_command_line(tmp_path, capsys):
    gt, tracks = write(tmp_path / "gt.csv", GT + GT_ROWS), write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    relations = write(tmp_path / "relations.csv", RELATIONS.replace("0.25", "nan"))
    line = evaluate_fails(capsys, tmp_path, "--gt", gt, "--tracks", tracks, "--relations", relations,
                          "--groups", write(tmp_path / "groups.csv", GROUPS))
    assert line == f"crowdsim: error: {relations}: line 2, column strength must hold numbers from 0 to 1, got 'nan'"


def test_a_ground_truth_without_visible_is_refused_saying_how_to_score_it(tmp_path, capsys):
    gt = write(tmp_path / "gt.csv", "frame,t,id,x,y,range,in_range,group\n0,0.00,1,2.0,0.0,2.0,1,-1\n"
                                    "0,0.00,2,4.0,1.0,4.1,1,-1\n1,0.04,1,2.04,0.0,2.0,1,-1\n")
    tracks = write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    line = evaluate_fails(capsys, tmp_path, "--gt", gt, "--tracks", tracks)
    assert line.startswith(f"crowdsim: error: {gt}: no column 'visible' to tell occluded persons (0) from visible")
    assert "--no-occlusion" in line and "--visible-column NAME" in line
    # as the message says: scored with every row counted
    js = tmp_path / "all.json"
    assert main(["evaluate", "--gt", gt, "--tracks", tracks, "--no-occlusion", "--json", str(js)]) == 0
    assert json.loads(js.read_text())["tracking"]["gt"] == 3
    capsys.readouterr()


def test_swapped_files_are_refused(tmp_path, capsys):
    gt, tracks = write(tmp_path / "gt.csv", GT + GT_ROWS), write(tmp_path / "tracks.csv", TRACKS + TRACK_ROWS)
    line = evaluate_fails(capsys, tmp_path, "--gt", tracks, "--tracks", gt)
    assert line.startswith(f"crowdsim: error: {tracks}: no column 'visible'") and "a tracks file has none" in line


def nav_run(folder, robot="frame,t,x,y,yaw\n0,0.0,0,0,0\n1,0.1,0.05,0,0\n2,0.2,0.1,0,0\n",
            persons="frame,t,id,x,y,vx,vy,radius\n0,0.0,5,3,1,0,0,0.2\n1,0.1,5,3,1,0,0,0.2\n"):
    folder.mkdir()
    write(folder / "robot.csv", robot, "latin-1")
    write(folder / "persons.csv", persons, "latin-1")
    (folder / "navigation.json").write_text(json.dumps({"task": "goal", "goal": [5, 0], "goal_radius": 0.5,
                                                        "robot_radius": 0.3, "time_limit": 10}))
    return folder


def test_evaluate_nav_reads_its_csvs_as_strictly(tmp_path, capsys):
    assert len(read_nav_run(nav_run(tmp_path / "ok")).stamp) == 3
    cases = [(nav_run(tmp_path / "nan", robot="frame,t,x,y,yaw\n0,0.0,0,0,0\n1,0.1,nan,0,0\n"),
              "robot.csv: line 3, column x must hold finite numbers, got 'nan'"),
             (nav_run(tmp_path / "id", persons="frame,t,id,x,y,vx,vy,radius\n0,0.0,1e20,3,1,0,0,0.2\n"),
              "persons.csv: line 2, column id must hold whole numbers (below 2^53 in size), got '1e20'"),
             (nav_run(tmp_path / "latin", persons="frame,t,id,x,y,vx,vy,radius\n0,0.0,5,3,1,0,0,0.2 \u00e9\n"),
              "persons.csv: line 2 is not UTF-8 text (byte 0xe9")]
    for run, expect in cases:
        assert f"{run}/{expect}" in error_of(lambda: read_nav_run(run))
        assert main(["evaluate-nav", str(run)]) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err and f"{run}/{expect}" in one_error_line(err)


def test_small_text_files_are_read_as_the_csvs(tmp_path):
    # for navigation.json: a byte order mark skipped, other bytes than UTF-8 named by their line
    assert read_text(write(tmp_path / "bom.json", "\ufeff{}")) == "{}"
    bad = write(tmp_path / "bad.json", '{"task":\n "caf\u00e9"}', "latin-1")
    assert error_of(lambda: read_text(bad)) == \
        f"{bad}: line 2 is not UTF-8 text (byte 0xe9, 6 bytes into the line); expected a file saved as UTF-8"
    assert error_of(lambda: read_text(tmp_path / "nope.json")) == \
        f"{tmp_path / 'nope.json'}: cannot be read (No such file or directory)"


def test_flags_shares_and_files_that_are_no_csv(tmp_path):
    gt = tmp_path / "gt.csv"
    gt.write_text("frame,t,id,x,y,visible\n0,0.00,1,2.0,0.0,1\n1,0.04,1,2.1,0.0,2\n")
    with pytest.raises(EvaluationInputError, match=r"gt.csv: line 3, column visible must hold 0 or 1, got '2'"):
        list(table_chunks(gt, read=("visible",)))
    relations = tmp_path / "relations.csv"
    relations.write_text("frame,t,track_a,track_b,strength\n1,0.04,7,8,1.5\n")
    with pytest.raises(EvaluationInputError, match=r"line 2, column strength must hold numbers from 0 to 1, got '1.5'"):
        list(table_chunks(relations, ("frame", "track_a", "track_b", "strength")))
    for path in ("/dev/zero", str(tmp_path)):
        with pytest.raises(EvaluationInputError, match="not a regular file"):
            list(table_chunks(path))
