"""``crowdsim experiment tune`` on a tiny study: the recorded scans measure a pipeline as the run does, a study
resumes from its storage, and best.yaml is a scenario that loads and carries the best trial's pipeline."""

import json

import optuna
import pytest
import yaml

from crowdsim.experiments.tune import SCENARIO, Recorded, suggest, tune
from crowdsim.loop import Simulation
from scenarios import load_scenario
from crowdsim.scoring import score_cycles


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
