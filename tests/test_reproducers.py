"""Every minimal reproducer of issue 28 (the defects found from outside) as a regression test: the reproducer's own
input files (tests/fuzz_cases/repro/, copied from the fuzzer's repro script) and command, and the outcome the issue
promises: for B (documented usage refused) a success with real output; for T (tracebacks, crashes), H (hangs), N
(nonsense or silent success) and M (confusing messages) one clear error naming the key or flag at fault, or the
behaviour the issue asks for. Each command runs in-process through ``crowdsim.cli.main`` from a temporary folder
holding copies of its input files, and fuzz_cases.promise checks the promise every time: exit 0 or 2, one
``crowdsim: error:`` line and nothing left behind on 2, no traceback, the user's files untouched.

Faults found when a scenario is loaded are checked with ``validate-scenario`` (the same load as ``run``'s, without the
simulation); commands whose checks must come before any work have that work replaced by a function that fails.

Reproducers kept elsewhere (id -> test):
    B1   tests/test_base_merge.py::test_the_readme_own_tracker_example_is_the_shipped_one_and_runs (the README's
         example as it is printed now, a real tracker; the repro's my_trackers.py is the README's old stub, whose
         ``update`` returns None: that is T28 here)
    T29  tests/test_out_paths.py::test_a_full_disk_is_one_error_and_leaves_nothing (a full disk during a run)
    N09  tests/test_out_paths.py::test_the_default_out_keeps_a_scenario_name_inside_runs (a name with ../)
    N16  tests/test_navigation_agree.py::test_run_and_navigate_give_the_same_navigation_metrics
    M06  tests/test_stops.py::test_a_run_stopped_halfway_leaves_nothing[SIGTERM] (a real process)
    M07  tests/test_stops.py::test_a_run_stopped_halfway_leaves_nothing[SIGINT] (a real process)
F1-F5 at the end are what tests/test_fuzz.py found while it was written (inputs in tests/fuzz_cases/found/).

T01-T03 and N15 (--out unusable) and T07, T08 (the dataset generator) have tests of their own too
(tests/test_out_paths.py, tests/test_dataset_robustness.py); here they run on the reproducers' exact inputs.
"""

from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

import pytest

from fuzz_cases.promise import FOUND, REPRO, check, refused, succeeded
from scenarios import load_scenario, scenario_from_dict
from scenarios.loader import read_raw, resolve


class Work(type(Path())):
    """The folder a command runs in; ``copy(*names)`` copies reproducer files into it and returns their paths (to
    pass as the files that must not change)."""

    def copy(self, *names: str, folder: Path = REPRO) -> list[Path]:
        for name in names:
            shutil.copy(folder / name, self / name)
        return [self / name for name in names]


@pytest.fixture
def work(tmp_path):
    return Work(tmp_path)


def no_work(monkeypatch, target: str, what: str):
    """Replace ``target`` (module:function) by one that fails: the command's checks must come before it."""
    module, name = target.split(":")

    def refuse(*args, **kwargs):
        raise AssertionError(f"{what} began before the arguments were checked")
    monkeypatch.setattr(f"{module}.{name}", refuse)


# -- B: documented usage refused ------------------------------------------------------------------------------------

def test_B2_base_can_switch_the_planner_type(work):
    precious = work.copy("base_switch_planner.yaml")
    o = succeeded(check(["validate-scenario", "base_switch_planner.yaml"], work, precious=precious))
    assert "valid scenario 'nd_passers_by'" in o.out
    planner = load_scenario(str(work / "base_switch_planner.yaml"))["robot"]["planner"]
    assert planner == with_part("passers_by", ("robot", "planner"), {"type": "nd"})  # nd's defaults, no zone keys
    # and it runs: the nd planner drives the robot
    out = "out/B2"
    succeeded(check(["run", "base_switch_planner.yaml", "--duration", "0.2", "--quiet", "--out", out], work,
                    precious=precious, outputs=[out]))


def test_B3_base_can_switch_the_tracker_type(work):
    precious = work.copy("base_switch_tracker.yaml")
    o = succeeded(check(["validate-scenario", "base_switch_tracker.yaml"], work, precious=precious))
    assert "valid scenario 'mht_airport'" in o.out
    tracker = load_scenario(str(work / "base_switch_tracker.yaml"))["pipeline"]["tracker"]
    # mht's defaults: none of the base's tuned nnt keys
    assert tracker == with_part("airport_disembarkation", ("pipeline", "tracker"), {"type": "mht"})
    out = "out/B3"
    succeeded(check(["run", "base_switch_tracker.yaml", "--duration", "0.2", "--quiet", "--out", out], work,
                    precious=precious, outputs=[out]))


def with_part(name: str, path: tuple[str, str], part: dict) -> dict:
    """The part at ``path`` of bundled scenario ``name`` validated with only ``part`` given there."""
    raw = read_raw(resolve(name))
    raw[path[0]] = dict(raw.get(path[0], {}), **{path[1]: part})
    return scenario_from_dict(raw)[path[0]][path[1]]


def test_B4_one_agent_type_tweaked_keeps_the_others(work):
    precious = work.copy("agent_type_tweak.yaml")
    succeeded(check(["validate-scenario", "agent_type_tweak.yaml"], work, precious=precious))
    types = load_scenario(str(work / "agent_type_tweak.yaml"))["crowd"]["agent_types"]
    base = load_scenario("airport_disembarkation")["crowd"]["agent_types"]
    assert set(types) == set(base) and len(types) > 1, sorted(types)
    assert types["adult"]["speed_mean"] == 1.2
    assert all(types[k] == base[k] for k in base if k != "adult")


# -- T, H, N, M found at load time: one error naming the file and the key -------------------------------------------

LOAD = [
    # id, file, words the error must hold (besides the file's name)
    ("T09", "max_agents_small.yaml", ["crowd.max_agents"]),
    ("T10", "clusters_over_max_agents.yaml", ["crowd.max_agents"]),
    ("T11", "max_agents_1e8.yaml", ["crowd.max_agents", "--allow-large"]),
    ("T12", "max_agents_1e9.yaml", ["crowd.max_agents", "--allow-large"]),
    ("T13", "map_filter_resolution.yaml", ["pipeline.map_filter.resolution", "--allow-large"]),
    ("T14", "map_far_walls.yaml", ["map.walls[0]", "--allow-large"]),
    ("T15", "laser_one_beam.yaml", ["sensors.lasers[0]"]),
    ("T16", "laser_resolution_tiny.yaml", ["sensors.lasers[0].resolution_deg", "--allow-large"]),
    ("T17", "nd_sectors_9.yaml", ["robot.planner.sectors"]),
    ("T18", "tag_range_inverted.yaml", ["sensors.tag.range_m"]),
    ("T19", "hog_scales_empty.yaml", ["pipeline.detectors.camera_1.hog_scales"]),
    ("T20", "camera_name_quote.yaml", ["sensors.wall_cameras[2].name"]),
    ("T21", "huge_integer.yaml", ["warmup"]),
    ("T22", "deep_nesting.yaml", ["nested"]),
    ("T23", "deep_nesting.xml", ["nested"]),
    ("T24", "pedsim_n_huge.xml", ["clusters[0].count", "line 9", "--allow-large"]),
    ("T30", "rjmcmc_samples_huge.yaml", ["pipeline.tracker.samples", "--allow-large"]),
    ("T31", "rgbd_without_rgb.yaml", ["sensors.depth_cameras[0].rgb"]),
    ("H1", "dt_tiny.yaml", ["dt", "--allow-large"]),
    ("H2", "warmup_huge.yaml", ["warmup", "--allow-large"]),
    ("H3", "depth_camera_4096.yaml", ["sensors.depth_cameras[0]", "--allow-large"]),
    ("N01", "standing_outside.yaml", ["standing[0]"]),
    ("N02", "robot_start_overlaps_wall.yaml", ["robot.start"]),
    ("N03", "robot_start_outside.yaml", ["robot.start"]),
    ("N04", "robot_fast.yaml", ["robot.max_speed"]),
    ("N05", "cluster_spread.yaml", ["clusters[0].spread"]),
    ("N06", "source_size_negative.yaml", ["sources[0].size"]),
    ("N07", "rgbd_up_zero.yaml", ["pipeline.detectors.kinect.up"]),
    ("N08", "duplicate_key.yaml", ["'duration'"]),
    ("M03", "base_missing.yaml", ["base"]),
]


@pytest.mark.parametrize("case, name, words", [pytest.param(*c, id=c[0]) for c in LOAD])
def test_refused_at_load_naming_the_key(work, case, name, words):
    precious = work.copy(name)
    o = check(["validate-scenario", name], work, precious=precious, limit=60)
    line = refused(o, *words)
    assert line.startswith(f"crowdsim: error: {name}: "), line  # the user's file, first
    if case == "N08":  # both lines the key is on
        assert re.search(r"\b2\b.*\b3\b", line), line


# the cost limits are passed on purpose with --allow-large; the validity limits are not
COSTS = ["T11", "T12", "T13", "T14", "T16", "T24", "T30", "H1", "H2", "H3"]
VALIDITY = ["T09", "T10", "N04"]


@pytest.mark.parametrize("case", COSTS + VALIDITY)
def test_allow_large_passes_the_cost_limits_only(work, case):
    name, words = next((n, w) for c, n, w in LOAD if c == case)
    precious = work.copy(name)
    o = check(["validate-scenario", name, "--allow-large"], work, precious=precious, limit=60)
    if case in COSTS:
        succeeded(o)
        assert "valid scenario" in o.out
    else:
        line = refused(o, words[0])
        assert "--allow-large" not in line.replace("--allow-large does not", ""), line


def test_M02_a_duration_below_a_step_names_the_users_file(work, monkeypatch):
    no_work(monkeypatch, "crowdsim.run:run", "the run")
    precious = work.copy("duration_tiny.yaml")
    o = check(["run", "duration_tiny.yaml", "--quiet", "--out", "out/M02"], work, precious=precious)
    line = refused(o, "duration_tiny.yaml", "duration")
    assert "partial" not in line and "/tmp" not in line, line


def test_T28_a_user_tracker_whose_update_returns_none(work, monkeypatch):
    precious = work.copy("user_tracker_none.yaml", "my_trackers.py")
    monkeypatch.syspath_prepend(str(work))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # Python's __pycache__ is no output of crowdsim's
    sys.modules.pop("my_trackers", None)
    try:
        o = check(["run", "user_tracker_none.yaml", "--duration", "0.5", "--quiet", "--out", "out/T28"], work,
                  precious=precious)
    finally:
        sys.modules.pop("my_trackers", None)
    refused(o, "user_tracker_none.yaml", "pipeline.tracker", "GnnTracker", "None")


# -- output paths: checked before the work ---------------------------------------------------------------------------

@pytest.mark.parametrize("case, out, words", [
    pytest.param("T01", "/proc/x", ["--out", "/proc"], id="T01"),
    pytest.param("T02", "my_trackers.py/run", ["--out", "my_trackers.py"], id="T02"),
    pytest.param("T03", "out/" + "x" * 300, ["--out", "300"], id="T03"),
    pytest.param("N15", "", ["--out"], id="N15"),
])
def test_run_out_unusable(work, monkeypatch, case, out, words):
    no_work(monkeypatch, "crowdsim.run:run", "the run")
    precious = work.copy("my_trackers.py")
    o = check(["run", "passers_by", "--duration", "1", "--quiet", "--out", out], work, precious=precious)
    refused(o, *words)


def test_M01_a_bad_seed_is_blamed_on_the_flag(work, monkeypatch):
    no_work(monkeypatch, "crowdsim.run:run", "the run")
    o = check(["run", "passers_by", "--seed", "-1", "--out", "out/M01"], work)
    line = refused(o, "--seed")
    assert "passers_by.yaml" not in line, line


def test_T05_navigate_json_into_a_missing_folder(work, monkeypatch):
    no_work(monkeypatch, "crowdsim.navigate:navigate_main", "navigation")
    o = check(["navigate", "passers_by", "--seeds", "1", "--quiet", "--json", "/nonexistent/n.json"], work)
    refused(o, "--json", "/nonexistent")


# -- crowdsim evaluate ------------------------------------------------------------------------------------------------

E = ["evaluate", "--gt", "gt.csv", "--tracks"]
EVALUATE = [
    # id, arguments, files, words the error must hold
    ("T04", [*E, "tracks.csv", "--json", "/nonexistent/dir/m.json"], [], ["--json", "/nonexistent/dir"]),
    ("T06", [*E, "tracks.csv", "--motchallenge", "/proc/mot"], [], ["--motchallenge", "/proc"]),
    ("T25", [*E, "tracks_latin1.csv"], ["tracks_latin1.csv"], ["tracks_latin1.csv", "UTF-8", "line 2"]),
    ("T26", [*E, "tracks.csv", "--threshold", "nan"], [], ["--threshold"]),
    ("T27", [*E, "tracks.csv", "--relations", "relations_nan.csv", "--groups", "groups_ok.csv"],
     ["relations_nan.csv", "groups_ok.csv"], ["relations_nan.csv", "line 2", "strength"]),
    ("N10", [*E, "tracks_nan.csv"], ["tracks_nan.csv"], ["tracks_nan.csv", "line 2", "column x"]),
    ("N11", ["evaluate", "--gt", "gt_no_visible.csv", "--tracks", "tracks.csv"], ["gt_no_visible.csv"],
     ["gt_no_visible.csv", "visible", "--no-occlusion"]),
    ("N12", [*E, "tracks.csv", "--max-range", "-1"], [], ["--max-range"]),
    ("N13", ["evaluate", "--gt", "tracks.csv", "--tracks", "gt.csv"], [], ["tracks.csv"]),
    ("N14", ["evaluate", "--gt", "gt.csv", "--tracks", "tracks_huge_id.csv", "--json", "out/N14.json"],
     ["tracks_huge_id.csv"], ["tracks_huge_id.csv", "line 2", "id"]),
    ("M04", [*E, "tracks.csv", "--motchallenge", "gt.csv"], [], ["--motchallenge"]),
]


@pytest.mark.parametrize("case, argv, files, words", [pytest.param(*c, id=c[0]) for c in EVALUATE])
def test_evaluate_refuses_naming_the_file_or_flag(work, case, argv, files, words):
    precious = work.copy("gt.csv", "tracks.csv", *files)
    (work / "out").mkdir()
    line = refused(check(argv, work, precious=precious, watch=[work / "out"]), *words)
    if case == "M04":
        assert "--out" not in line, line


def test_M05_a_utf8_bom_is_accepted(work):
    precious = work.copy("gt.csv", "tracks_bom.csv")
    o = succeeded(check(["evaluate", "--gt", "gt.csv", "--tracks", "tracks_bom.csv", "--json", "m.json"], work,
                        precious=precious, outputs=["m.json"]))
    assert "MOTA" in o.out
    tracking = json.loads((work / "m.json").read_text())["tracking"]
    assert tracking["gt"] > 0


# -- the dataset generator (T07, T08) -------------------------------------------------------------------------------

@pytest.mark.parametrize("case, args", [
    pytest.param("T07", ["passers_by", "--route-jitter", "0.1"], id="T07"),
    pytest.param("T08", ["seed001_room_1"], id="T08"),
    pytest.param("T08b", ["seed001_room_1", "--density-scale", "2", "2"], id="T08-density-scale"),
])
def test_dataset_generate_writes_a_whole_dataset(work, case, args):
    out = work / "out" / case
    o = succeeded(check(["dataset", "generate", *args, "--episodes", "1", "--duration", "1", "--quiet",
                         "--out", str(out)], work, outputs=[out], need=["manifest.json"], limit=120))
    assert sorted(p.name for p in out.iterdir()) == ["episode_00000", "manifest.json"], o.report()
    assert any((out / "episode_00000").iterdir())


# -- F: found by tests/test_fuzz.py ------------------------------------------------------------------------------------

@pytest.mark.parametrize("case, name, words", [
    # a 400-digit integer inside a point (T21 was a plain number): OverflowError in the schema's point check
    pytest.param("F1", "huge_integer_in_point.yaml", ["robot.goals[0]"], id="F1"),
    # an XML declaration naming an encoding Python does not know: LookupError from the parser
    pytest.param("F2", "unknown_encoding.xml", ["encoding"], id="F2"),
])
def test_found_refused_at_load(work, case, name, words):
    precious = work.copy(name, folder=FOUND)
    line = refused(check(["validate-scenario", name], work, precious=precious, limit=60), *words)
    assert line.startswith(f"crowdsim: error: {name}: "), line


def test_F4_a_dataset_meta_json_is_strict_json(work):
    # passers_by's sources never stop (stop: .inf): episode_*/meta.json wrote the scenario with Infinity, which is
    # no JSON (jq, JavaScript and most readers refuse it); check's output test reads every JSON strictly
    out = work / "out" / "F4"
    succeeded(check(["dataset", "generate", "passers_by", "--episodes", "1", "--duration", "0.2", "--quiet",
                     "--out", str(out)], work, outputs=[out], need=["manifest.json"], limit=120))


@pytest.mark.parametrize("flag", [
    pytest.param("--motchallenge", id="F3"),  # nothing exported, exit 0
    pytest.param("--visible-column", id="F5"),  # scored with the visible column, as if the flag were not given
])
def test_an_empty_evaluate_flag_is_refused(work, flag):
    # like N15's --out "" (which the issue counts as a nonsense success): an empty value silently ignored
    precious = work.copy("gt.csv", "tracks.csv")
    refused(check([*E, "tracks.csv", flag, ""], work, precious=precious), flag)
