"""``crowdsim experiment tune`` on a tiny study: the recorded scans measure a pipeline as the run does, a study
resumes from its storage, best.yaml is a scenario that loads and carries the best trial's pipeline, and a batch of
trials gives the same study on any number of workers."""

import json

import optuna
import pytest
import yaml

import crowdsim.experiments.tune as tune_module
from crowdsim.cli import main
from crowdsim.experiments.tune import SCENARIO, Recorded, suggest, tune
from crowdsim.loop import Simulation
from crowdsim.scoring import score_cycles
from crowdsim.workers import Engine
from scenarios import load_scenario


def test_recorded_mota_is_the_runs_own():
    recorded = Recorded([5], duration=3.0)
    sim = Simulation(load_scenario(SCENARIO, duration=3.0))
    sim.reset(5)
    sim.warm_up()
    run = score_cycles(sim.frames(3.0), sim.scenario["evaluation"]["threshold"])
    assert recorded.mota(None) == pytest.approx(100 * run.mota, abs=1e-12)


def test_a_study_resumes_and_writes_a_scenario_of_its_best_trial(tmp_path):
    storage = f"sqlite:///{tmp_path / 'study.db'}"
    kw = dict(duration=2.0, progress=False, train_seeds=(100,), held_out_seeds=(200,), storage=storage)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first = tune(tmp_path / "a", 3, **kw)
    second = tune(tmp_path / "b", 2, **kw)
    assert first["trials"] == 3 and second["trials"] == 5  # the second run went on with the same study
    study = optuna.load_study(study_name="crowdsim-airport", storage=storage)
    assert second["best_train_mota"] == max(t.value for t in study.trials) == study.best_value
    best = yaml.safe_load((tmp_path / "b" / "best.yaml").read_text())
    assert best["base"] == SCENARIO and best["pipeline"] == suggest(optuna.trial.FixedTrial(study.best_params))
    scenario = load_scenario(str(tmp_path / "b" / "best.yaml"))
    assert scenario["pipeline"]["tracker"]["association"]["type"] == best["pipeline"]["tracker"]["association"]
    # the held-out figure is the best pipeline's MOTA on the held-out seed, measured again here
    held_out = Recorded([200], 2.0)
    assert second["held_out_mota_best"] == held_out.mota(best["pipeline"])
    assert second["held_out_mota_airport"] == held_out.mota(None)
    assert json.loads((tmp_path / "b" / "results.json").read_text()) == second
    assert (tmp_path / "b" / "history.png").stat().st_size > 5_000


def test_a_batch_of_trials_gives_the_same_study_on_one_or_two_workers(tmp_path):
    kw = dict(duration=1.0, progress=False, train_seeds=(100, 101), held_out_seeds=(200,), batch=2)
    (tmp_path / "one").mkdir()
    (tmp_path / "two").mkdir()
    one = tune(tmp_path / "one", 3, engine=Engine(1), **kw)
    two = tune(tmp_path / "two", 3, engine=Engine(2), **kw)
    assert one["trials"] == 3  # batches of 2 and 1
    assert one == two
    assert (tmp_path / "one" / "best.yaml").read_bytes() == (tmp_path / "two" / "best.yaml").read_bytes()


def test_a_batch_that_fails_is_kept_in_the_storage_as_failed_trials(tmp_path, monkeypatch):
    def broken(task, scenario):
        raise RuntimeError("a broken pipeline")

    monkeypatch.setattr(tune_module, "_mota", broken)
    storage = f"sqlite:///{tmp_path / 'study.db'}"
    with pytest.raises(RuntimeError, match="a broken pipeline"):
        tune(tmp_path, 5, storage=storage, duration=1.0, progress=False, train_seeds=(100,), batch=2)
    study = optuna.load_study(study_name="crowdsim-airport", storage=storage)
    assert [t.state for t in study.trials] == [optuna.trial.TrialState.FAIL] * 2  # the first batch, not run on


def test_a_batch_below_one_is_refused(tmp_path, capsys):
    assert main(["experiment", "tune", "--batch", "0", "--out", str(tmp_path / "t")]) == 2
    assert "--batch 0: expected a count of trials >= 1" in capsys.readouterr().err
    assert not (tmp_path / "t").exists()
