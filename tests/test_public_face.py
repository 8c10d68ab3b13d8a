"""The public face: ``import crowdsim`` gives every public name and stays cheap; ``crowdsim.Error`` catches every
error a user can cause, each naming the file, key or flag; each experiment and benchmark is a subcommand with only
its own flags."""

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

import crowdsim
from crowdsim.cli import build_parser, main

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("crowdsim", "evaluation", "scenarios", "pipeline", "sensors")
# exceptions that never reach a user: raised and caught inside one module
INTERNAL = {("scenarios.reader", "_Refused")}


def test_every_public_name_resolves():
    assert "Error" in crowdsim.__all__ and "Simulation" in crowdsim.__all__
    for name in crowdsim.__all__:
        assert getattr(crowdsim, name) is not None, name
    assert set(crowdsim.__all__) <= set(dir(crowdsim))
    from crowdsim.loop import Frame, Simulation
    from pipeline.types import TrackedPersons

    assert (crowdsim.Simulation, crowdsim.Frame, crowdsim.TrackedPersons) == (Simulation, Frame, TrackedPersons)
    with pytest.raises(AttributeError, match="no attribute 'nonesuch'"):
        crowdsim.nonesuch  # noqa: B018


def test_import_is_cheap_and_registers_the_environments():
    """The simulator, the pipeline and the evaluation are imported on first use, not by ``import crowdsim``."""
    code = ("import sys, crowdsim, gymnasium; heavy = [m for m in ('crowdsim.loop', 'pipeline', 'evaluation', "
            "'scenarios', 'mujoco') if m in sys.modules]; assert not heavy, heavy; "
            "assert 'crowdsim/Navigate-v0' in gymnasium.registry and 'crowdsim/Follow-v0' in gymnasium.registry")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def _error_classes():
    """(module, class name) of every class in the packages whose base's name ends in Error or Exception."""
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ClassDef) and any(
                        (b.id if isinstance(b, ast.Name) else getattr(b, "attr", "")).endswith(("Error", "Exception"))
                        for b in node.bases):
                    yield module, node.name


def test_every_error_class_is_a_crowdsim_error():
    found = set(_error_classes()) - INTERNAL
    assert {name for _, name in found} >= {"ScenarioError", "RunDirError", "EvaluationInputError", "DatasetError",
                                           "DiskFullError", "UsageError"}
    for module, name in found:
        assert issubclass(getattr(importlib.import_module(module), name), crowdsim.Error), f"{module}.{name}"


def _raised(fn, *args, **kwargs) -> crowdsim.Error:
    with pytest.raises(crowdsim.Error) as e:
        fn(*args, **kwargs)
    return e.value


def test_each_user_error_is_a_crowdsim_error_naming_its_cause(tmp_path):
    from crowdsim.datasets import Dataset
    from crowdsim.outdir import check_out_dir

    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nbogus_key: 1\n")
    e = _raised(crowdsim.load_scenario, str(bad))
    assert type(e).__name__ == "ScenarioError" and str(bad) in str(e) and "bogus_key" in str(e)

    used = tmp_path / "used"
    used.mkdir()
    (used / "kept").write_text("x")
    e = _raised(check_out_dir, used)
    assert type(e).__name__ == "RunDirError" and str(used) in str(e)

    gt, tracks = tmp_path / "gt.csv", tmp_path / "tracks.csv"
    gt.write_text("frame,id,x,y,visible\n1,1,0,0,1\n")
    tracks.write_text("frame,id,x,yy\n1,1,0,0\n")
    e = _raised(crowdsim.score_tracking, crowdsim.CsvPair(gt, tracks))
    assert type(e).__name__ == "EvaluationInputError" and str(tracks) in str(e) and "y" in str(e)

    e = _raised(Dataset, tmp_path / "nowhere")
    assert type(e).__name__ == "DatasetError" and "nowhere" in str(e)

    args = build_parser().parse_args(["experiment", "table2", "--seeds", "0"])
    e = _raised(args.func, args)
    assert type(e).__name__ == "UsageError" and "--seeds" in str(e)


def test_the_command_line_prints_any_crowdsim_error_as_one_line(monkeypatch, capsys):
    class Fresh(crowdsim.Error):
        pass

    def fails(args):
        raise Fresh("somewhere.yaml: key: expected something")

    monkeypatch.setattr("crowdsim.cli._cmd_scenarios", fails)
    assert main(["scenarios"]) == 2
    assert capsys.readouterr().err == "crowdsim: error: somewhere.yaml: key: expected something\n"


# --- experiments and benchmarks: one subcommand each, with its own flags ------------------------------------------

def test_each_registered_command_parses_with_its_defaults():
    from crowdsim.bench import BENCHMARKS
    from crowdsim.experiments import EXPERIMENTS

    for group, commands in (("experiment", EXPERIMENTS), ("bench", BENCHMARKS)):
        for command in commands:
            args = build_parser().parse_args([group, command.name])
            assert args.what == command.name and callable(args.func)
    defaults = {name: build_parser().parse_args(["experiment", name]) for name in ("table2", "groups", "seed003")}
    assert [defaults[n].seeds for n in ("table2", "groups", "seed003")] == [20, 5, 1]
    assert defaults["table2"].duration is None and defaults["groups"].duration == 60.0


def test_an_experiment_refuses_another_experiments_flag_in_one_line(capsys):
    for argv, flag in ((["experiment", "groups", "--minutes", "3"], "--minutes 3"),
                       (["experiment", "seed001", "--seeds", "1"], "--seeds 1"),
                       (["bench", "sim", "--crowdnav", "python"], "--crowdnav python")):
        with pytest.raises(SystemExit) as e:
            build_parser().parse_args(argv)
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"crowdsim: error: crowdsim {argv[0]} {argv[1]}: ") \
            and f"unrecognized arguments: {flag}" in err


def test_bench_without_a_name_runs_the_loop_benchmark(monkeypatch, tmp_path):
    import crowdsim.bench.parts as parts

    runs = []
    monkeypatch.setattr(parts, "run_benchmarks", lambda **kw: runs.append(kw))
    figures = tmp_path / "figures.json"
    assert main(["bench"]) == 0
    assert main(["bench", "--quick", "--json", str(figures)]) == 0
    assert main(["bench", "loop", "--quick"]) == 0
    assert runs == [{"json_path": None, "quick": False}, {"json_path": str(figures), "quick": True},
                    {"json_path": None, "quick": True}]
