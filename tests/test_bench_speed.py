"""``crowdsim bench speed``: each figure measured in processes of their own for each tree, side by side (the
mechanism; the figures themselves are the machine's, so no test asserts a time)."""

import json
import re
from pathlib import Path

from crowdsim.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_a_figure_of_two_trees_side_by_side(tmp_path, capsys):
    figures = tmp_path / "speed.json"
    assert main(["bench", "speed", "--quick", "--rounds", "1", "--figures", "crowd_20", "--against", str(ROOT),
                 "--json", str(figures)]) == 0
    line = [x for x in capsys.readouterr().out.splitlines() if x.startswith("crowd_20 steps_per_cpu_s")]
    assert len(line) == 1 and re.search(r"[\d,.]+\s+[\d,.]+\s+[\d.]+x$", line[0])
    samples = json.loads(figures.read_text())["samples"]
    for tree in ("ours", "theirs"):  # one measurement each, of the figure asked for only
        assert list(samples[tree]) == ["crowd_20"]
        (steps,) = samples[tree]["crowd_20"]["steps_per_cpu_s"]
        assert steps > 0


def test_a_folder_that_holds_no_checkout_is_one_error(tmp_path, capsys):
    assert main(["bench", "speed", "--against", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--against {tmp_path}: expected a checkout of crowdsim" in err
    assert main(["bench", "speed", "--rounds", "0"]) == 2
    assert "--rounds 0: expected at least 1" in capsys.readouterr().err
