"""Output directories are written whole or not at all; a killed writer's temporary directory is removed by the next
write into the same parent once its process is gone, and nothing else is touched."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from crowdsim.outdir import RunDirError, _host, remove_stale, write_directory


def test_a_finished_write_appears_whole_and_a_failed_one_leaves_nothing(tmp_path):
    out = tmp_path / "a" / "run"
    assert write_directory(out, lambda tmp: (tmp / "x.txt").write_text("done")) == 4
    assert (out / "x.txt").read_text() == "done" and os.listdir(tmp_path / "a") == ["run"]

    def fail(tmp):
        (tmp / "half.txt").write_text("half")
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError):
        write_directory(tmp_path / "b" / "run", fail)
    assert os.listdir(tmp_path) == ["a"]  # neither the directory nor the parents it made
    with pytest.raises(RunDirError, match="not empty"):
        write_directory(out, lambda tmp: None)
    assert (out / "x.txt").read_text() == "done"


def test_a_write_killed_outright_is_cleaned_up_by_the_next_write_in_its_folder(tmp_path):
    script = textwrap.dedent(f"""
        import time
        from crowdsim.outdir import write_directory
        def slow(tmp):
            (tmp / "part.txt").write_text("x")
            print("writing", flush=True)
            time.sleep(60)
        write_directory({str(tmp_path / 'killed')!r}, slow)
    """)
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline() == "writing\n"
    # a live process's temporary directory, a dead one's from another host, and a file of the user stay untouched
    alive = tmp_path / f".other.crowdsim-partial-{_host()}-{os.getpid()}-abc"
    elsewhere = tmp_path / f".far.crowdsim-partial-{_host()}x-{child.pid}-abc"
    for folder in (alive, elsewhere):
        folder.mkdir()
    (tmp_path / ".notes.txt").write_text("mine")
    os.kill(child.pid, signal.SIGKILL)
    child.wait()
    left = [p.name for p in tmp_path.iterdir() if p.name.startswith(".killed.")]
    assert len(left) == 1 and not (tmp_path / "killed").exists()  # kill -9: nothing under its name
    write_directory(tmp_path / "next", lambda tmp: None)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([alive.name, elsewhere.name, ".notes.txt", "next"])
    assert remove_stale(tmp_path) == []
