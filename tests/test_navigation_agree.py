"""``crowdsim run`` and ``crowdsim navigate`` score one seed's episode alike, to the last bit (issue 28, point 8).

The run writes what the navigation metrics read (robot.csv, persons.csv, following.csv) at full precision and
scores it back from the files (``read_nav_run``), navigate scores the same values in memory; acceleration and jerk,
second and third differences of the positions, showed any rounding (passers_by seed 1: a peak acceleration of 0.62
m/s^2 from the files written to 4 decimals, against the robot's own 0.50 in memory). A goal episode and a following
one (following.csv), a few seconds each."""

import json
import math

import numpy as np
import pytest

from crowdsim.loop import Simulation
from crowdsim.navigate import episode_metrics
from crowdsim.run import EXACT, PERSONS_FORMAT, CsvWriter, run
from evaluation.columns import PERSONS
from evaluation.navigation import navigation_metrics, read_nav_run
from evaluation.navigation_report import json_safe
from scenarios import load_scenario

SEED, DURATION = 3, 4.0  # s: past the robot's first accelerations, with people about


def same(a: dict, b: dict) -> None:
    """The same keys and the very same values (NaN equal to NaN), of the same kind."""
    assert a.keys() == b.keys()
    for key in a:
        x, y = a[key], b[key]
        assert type(x) is type(y), (key, x, y)
        assert x == y or (isinstance(x, float) and math.isnan(x) and math.isnan(y)), (key, x, y)


@pytest.mark.parametrize("name", ["passers_by", "person_following"])
def test_run_and_navigate_give_the_same_navigation_metrics(tmp_path, name):
    scenario = load_scenario(name, seed=SEED, duration=DURATION)
    metrics = run(scenario, tmp_path / "run", progress=False)
    in_memory = episode_metrics(Simulation(scenario), SEED, DURATION)
    assert metrics["frames"] > 50 and np.isfinite(in_memory["peak_linear_jerk"])
    assert in_memory["min_distance"] < 10.0  # people about: the social figures read persons.csv
    same(metrics["navigation"], in_memory)
    # evaluate-nav's reading of the directory, and metrics.json's figures (NaN and inf as null)
    same(navigation_metrics(read_nav_run(tmp_path / "run")), in_memory)
    saved = json.loads((tmp_path / "run" / "metrics.json").read_text())["navigation"]
    assert saved == json.loads(json.dumps(json_safe(in_memory)))
    if name == "person_following":
        assert (tmp_path / "run" / "following.csv").exists() and math.isfinite(in_memory["in_band_share"])


def test_exact_columns_read_back_as_the_same_floats(tmp_path):
    """persons.csv's format: every float64 (tiny, huge, negative zero, the sum that is not 0.3) reads back as
    itself, the integer columns stay whole, a block boundary changes nothing."""
    rng = np.random.default_rng(0)
    n = 5000  # more than a block of rows
    rows = np.column_stack([np.arange(n), np.cumsum(np.full(n, 0.04)) + 10.0, rng.integers(0, 99, n),
                            rng.normal(size=(n, 4)) * 10.0 ** rng.integers(-300, 300, (n, 4)), np.full(n, 0.25)])
    rows[:5, 3] = [-0.0, 0.1 + 0.2, 5e-324, 1.7976931348623157e308, 1.5008]
    writer = CsvWriter(tmp_path, PERSONS, PERSONS_FORMAT)
    writer.write(rows[:100])
    writer.write(rows[100:])
    writer.close()
    text = (tmp_path / "persons.csv").read_text()
    back = np.loadtxt(text.splitlines()[1:], delimiter=",")
    assert back.tobytes() == rows.tobytes() and text.splitlines()[1].split(",")[2].isdigit()
    assert EXACT % 1.5008 == "1.5008" and ",1.5008," in text.splitlines()[5]  # the shortest that reads back
