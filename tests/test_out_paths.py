"""Output paths checked before any work: a folder this user can make with a legal name, new or empty; a new file in
an existing folder; each fault one line naming the flag. And one file written whole or not at all."""

import os

import pytest

from crowdsim.cli import main
from crowdsim.outdir import RunDirError, check_out_dir, check_out_file, write_file


def one_error(capsys) -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and err[0].startswith("crowdsim: error: "), err
    return err[0]


@pytest.mark.parametrize("out, words", [
    ("/proc/crowdsim-run", ["cannot write in /proc"]),
    ("FILE/run", ["is a file; expected a folder there"]),
    ("x" * 300, ["a name of 300 bytes", "at most 255"]),
    ("", ["--out: empty"]),
])
def test_run_refuses_an_unusable_out_before_any_work(tmp_path, monkeypatch, capsys, out, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "FILE").write_text("mine")
    assert main(["run", "passers_by", "--duration", "1", "--quiet", "--out", out]) == 2
    line = one_error(capsys)
    for w in words:
        assert w in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["FILE"] and (tmp_path / "FILE").read_text() == "mine"


def test_json_and_motchallenge_are_checked_before_scoring(tmp_path, capsys):
    gt = tmp_path / "gt.csv"
    gt.write_text("frame,t,id,x,y,vx,vy,visible\n0,0.00,1,2.0,0.0,1.0,0.0,1\n")
    tracks = tmp_path / "tracks.csv"
    tracks.write_text("frame,t,id,x,y,vx,vy\n0,0.00,7,2.05,0.02,1.0,0.0\n")
    base = ["evaluate", "--gt", str(gt), "--tracks", str(tracks)]
    assert main([*base, "--json", str(tmp_path / "missing" / "m.json")]) == 2
    assert "the folder" in one_error(capsys) and not (tmp_path / "missing").exists()
    assert main([*base, "--motchallenge", str(gt)]) == 2
    assert one_error(capsys).startswith(f"crowdsim: error: --motchallenge {gt}: is a file; expected a new or empty")
    assert main([*base, "--threshold", "nan"]) == 2 and "--threshold nan" in one_error(capsys)
    assert main([*base, "--max-range", "-1"]) == 2 and "--max-range -1.0" in one_error(capsys)
    assert main([*base, "--json", str(tmp_path / "m.json"), "--motchallenge", str(tmp_path / "mot")]) == 0
    assert (tmp_path / "m.json").is_file() and sorted(os.listdir(tmp_path / "mot")) == ["gt.txt", "tracks.txt"]


def test_the_default_out_keeps_a_scenario_name_inside_runs(tmp_path, monkeypatch, capsys):
    path = tmp_path / "escape.yaml"
    path.write_text("base: passers_by\nname: ../../escaped\nwarmup: 0\n")
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    assert main(["run", str(path), "--duration", "0.2", "--quiet"]) == 0
    (made,) = (work / "runs").iterdir()
    assert made.name.startswith("_.._escaped-") and (made / "metrics.json").is_file()
    assert not list(tmp_path.glob("escaped*")) and not list((tmp_path / "a").glob("escaped*"))


def test_check_out_file_and_write_file(tmp_path):
    check_out_file(tmp_path / "new.json", "--json")
    (tmp_path / "old.json").write_text("mine")
    with pytest.raises(RunDirError, match="--json .*old.json: already exists"):
        check_out_file(tmp_path / "old.json", "--json")
    write_file(tmp_path / "new.json", "{}\n")
    assert (tmp_path / "new.json").read_text() == "{}\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.json", "old.json"]  # no temporary file left
    check_out_dir(tmp_path / "made" / "deeper")  # parents to make: fine, and nothing made by the check
    assert not (tmp_path / "made").exists()
    with pytest.raises(RunDirError, match="already exists and is not empty"):
        check_out_dir(tmp_path)


def test_a_full_disk_is_one_error_and_leaves_nothing(tmp_path, monkeypatch, capsys):
    import errno

    import crowdsim.run

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "out" / "tracks.csv"))

    monkeypatch.setattr(crowdsim.run, "plot_run", full, raising=False)
    monkeypatch.setattr(crowdsim.run.CsvWriter, "close", full)
    assert main(["run", "passers_by", "--duration", "0.2", "--quiet", "--out", str(tmp_path / "out")]) == 2
    line = one_error(capsys)
    assert "No space left on device" in line and "nothing was kept" in line
    assert list(tmp_path.iterdir()) == []
