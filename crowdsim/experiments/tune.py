"""``crowdsim experiment tune``: Optuna searches the detector's, fusion's and tracker's parameters for MOTA on the
airport's training seeds, as seed 000 did with pySMAC (Sec. IV-E), and reports the best on held-out seeds.

The training seeds' scans are recorded once (``recorded``); each trial runs its pipeline on them and scores MOTA as
the run does (seed 000's evaluation: 1 m, 20 m range, occluded ignored), which a test shows is the run's own MOTA.
The sampler is Optuna's TPE, seeded, so a study of the same trials gives the same parameters. The recordings and
each trial's runs go to the command's engine (``--workers``, ``--ray``: crowdsim/workers.py); ``--batch B`` asks B
trials at once, so that more runs than seeds are in flight, and tells their results in order. Which parameters are
tried depends on B (a trial is drawn knowing the results of the batches before its own), never on the engine or
the number of workers. With ``--storage`` (e.g. ``sqlite:///study.db``) a study resumes where it stopped. The
result: ``best.yaml``, a scenario file that starts from the airport (``base:``) and sets the best pipeline;
``history.png``, every trial's MOTA and the best so far; ``results.json``, the best against the airport's own
pipeline on the held-out seeds. Needs the ``tune`` extra (optuna).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import yaml
from tqdm import tqdm

from pipeline.assemble import TRACKERS, build_part
from scenarios import load_scenario
from scenarios.format import PIPELINE
from scenarios.schema import validate
from scenarios.typed import plain, typed

from .. import workers
from ..workers import Engine, run_all, runner
from .recorded import detect, record, track

SCENARIO = "airport_disembarkation"
TRAIN_SEEDS = (100, 101, 102)  # tuned on; the evaluation's seeds (1-20) and the held-out ones are never among them
HELD_OUT_SEEDS = (200, 201, 202, 203, 204)


def suggest(trial) -> dict:
    """A pipeline section from the trial: the detector (geometric or learned, and its parameters), the fusion
    distance, the map filter, and the tracker's parts and thresholds (ranges round seed 000's values and the
    airport's own). ``v_min`` may reach 0: the initiation logic without its velocity gate, which then confirms
    standing persons too."""
    kind = trial.suggest_categorical("detector", ["laser_segments", "adaboost", "forest"])
    detector = {"jump_distance": trial.suggest_float("jump_distance", 0.2, 0.6),
                "min_points": trial.suggest_int("min_points", 2, 6)}
    if kind == "laser_segments":
        detector |= {"type": kind, "max_width": trial.suggest_float("max_width", 0.5, 1.2),
                     "min_bulge": trial.suggest_float("min_bulge", 0.0, 0.08)}
    else:
        detector |= {"type": "laser_learned", "model": kind, "threshold": trial.suggest_float("threshold", 0.1, 0.9)}
    tracker = {"type": "nnt",
               "association": trial.suggest_categorical("association", ["greedy", "global"]),
               "process_noise": trial.suggest_float("process_noise", 0.02, 1.0, log=True),
               "gate_chi2": trial.suggest_float("gate_chi2", 5.0, 30.0),
               "motion": trial.suggest_categorical("motion", ["cv", "imm"]),
               "initiation": trial.suggest_categorical("initiation", ["none", "base", "extended"]),
               "deletion": trial.suggest_categorical("deletion", ["fixed", "young_mature"])}
    if tracker["initiation"] == "none":
        tracker["n_confirm"] = trial.suggest_int("n_confirm", 2, 8)
    else:
        tracker["n_min"] = trial.suggest_int("n_min", 2, 8)
        tracker["v_min"] = trial.suggest_float("v_min", 0.0, 0.3)
    if tracker["deletion"] == "fixed":
        tracker["n_delete"] = trial.suggest_int("n_delete", 3, 50)
    else:
        tracker["n_delete_young"] = trial.suggest_int("n_delete_young", 5, 40)
        tracker["n_delete_mature"] = tracker["n_delete_young"] + trial.suggest_int("n_delete_mature_more", 0, 80)
        tracker["mature_after"] = trial.suggest_int("mature_after", 10, 150)
    pipeline = {"detector": detector, "fusion": {"type": "nearest",
                                                 "distance": trial.suggest_float("fusion_distance", 0.2, 0.8)},
                "tracker": tracker, "map_filter": None}
    if trial.suggest_categorical("map_filter", [True, False]):
        pipeline["map_filter"] = {"inflation": trial.suggest_float("map_inflation", 0.0, 0.4),
                                  "max_occupied": trial.suggest_float("map_max_occupied", 0.0, 0.2)}
    return pipeline


class Recorded:
    """The airport's scans over ``seeds`` (recorded once), on which pipeline sections' MOTA is measured; ``run`` is
    where the recordings and the measurements run (``run_all``, or a ``runner``'s for many calls on one engine)."""

    def __init__(self, seeds, duration: float, progress: bool = False, run=run_all):
        self.scenario = load_scenario(SCENARIO)
        self.run = run
        self.runs = run(_recording, list(seeds), duration, desc="recording", unit="seed", progress=progress)

    def mota(self, pipeline: dict | None) -> float:
        """Mean MOTA (%) over the recorded seeds of ``pipeline`` (None: the airport's own)."""
        return self.motas([pipeline])[0]

    def motas(self, pipelines: list[dict | None]) -> list[float]:
        """``[mota(p) for p in pipelines]``, every (pipeline, seed) run at once on the engine."""
        tasks = [(p, cycles) for p in pipelines for cycles in self.runs]
        scores = np.array(self.run(_mota, tasks, self.scenario, progress=False))
        return [float(np.mean(row)) for row in scores.reshape(len(pipelines), len(self.runs))]


def _recording(seed: int, duration: float) -> list:
    """The airport's scans from ``seed``: one task of ``Recorded``."""
    return record(load_scenario(SCENARIO), seed, duration)


def _mota(task, scenario) -> float:
    """MOTA (%) of a pipeline section (None: the scenario's own) on one recorded run: one task of ``motas``."""
    pipeline, cycles = task
    spec = (scenario.pipeline if pipeline is None
            else typed(validate(pipeline, PIPELINE, "<tune>", "pipeline"), PIPELINE))
    detections = detect(cycles, spec, scenario.map)
    tracker = build_part(plain(spec.tracker), TRACKERS)
    return 100 * track(cycles, detections, tracker, scenario.evaluation.threshold)[0]["all"].mota


def tune(out: Path, trials: int, storage: str | None = None, study_name: str = "crowdsim-airport",
         duration: float = 60.0, seed: int = 0, progress: bool = True, train_seeds=TRAIN_SEEDS,
         held_out_seeds=HELD_OUT_SEEDS, engine: Engine = Engine(), batch: int = 1) -> dict:
    """Run ``trials`` more trials of the study (new, or resumed from ``storage``), ``batch`` at a time, and write
    best.yaml, history.png and results.json into ``out``; returns the results."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(study_name=study_name, storage=storage, direction="maximize", load_if_exists=True,
                                sampler=optuna.samplers.TPESampler(seed=seed))
    with runner(engine) as run:
        train = Recorded(train_seeds, duration, progress, run)
        with tqdm(total=trials, unit="trial", disable=not progress, desc="tune") as bar:
            for first in range(0, trials, batch):
                asked = [study.ask() for _ in range(min(batch, trials - first))]
                try:
                    values = train.motas([suggest(t) for t in asked])
                except BaseException:  # a stop or a failure: the study (in its storage) keeps these as failed
                    for t in asked:
                        study.tell(t, state=optuna.trial.TrialState.FAIL)
                    raise
                for t, value in zip(asked, values):
                    study.tell(t, value)
                bar.update(len(asked))
        best = suggest(optuna.trial.FixedTrial(study.best_params))
        held_out_best, held_out_airport = Recorded(held_out_seeds, duration, progress, run).motas([best, None])
    results = {"trials": len(study.trials), "best_train_mota": study.best_value, "best_params": study.best_params,
               "train_seeds": list(train_seeds), "held_out_seeds": list(held_out_seeds), "duration_s": duration,
               "held_out_mota_best": held_out_best, "held_out_mota_airport": held_out_airport}
    (out / "best.yaml").write_text(f"# crowdsim experiment tune: the best of {len(study.trials)} trials, MOTA "
                                   f"{study.best_value:.1f}% on seeds {list(train_seeds)}\n"
                                   + yaml.safe_dump({"base": SCENARIO, "name": f"{SCENARIO}_tuned",
                                                     "pipeline": best}, sort_keys=False))
    _plot(out / "history.png", [t.value for t in study.trials if t.value is not None])
    (out / "results.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


def _plot(path: Path, values: list[float]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(values, ".", label="trial")
    ax.plot(np.maximum.accumulate(values), "-", label="best so far")
    ax.set_xlabel("trial")
    ax.set_ylabel("MOTA on the training seeds [%]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_arguments(parser) -> None:
    from ..cli import add_out_argument

    parser.add_argument("--trials", type=int, default=50, help="trials (default 50)")
    parser.add_argument("--storage", help="an Optuna storage to keep and resume the study, e.g. sqlite:///study.db")
    parser.add_argument("--duration", type=float, default=60.0, help="s of each airport run (default 60)")
    parser.add_argument("--seed", type=int, default=0, help="the sampler's seed (default 0)")
    parser.add_argument("--batch", type=int, default=1,
                        help="trials asked at once, run side by side (default 1: each trial knows every earlier "
                             "result); the trials tried depend on it, not on --workers or --ray")
    workers.add_arguments(parser)
    add_out_argument(parser, "tune")


def main(args) -> int:
    """``crowdsim experiment tune``."""
    from ..cli import UsageError, check_duration, run_dir
    from ..outdir import write_directory

    try:
        import optuna  # noqa: F401
    except ImportError as e:
        raise UsageError(f'experiment tune: needs {e.name}: pip install -e ".[tune]"') from None
    check_duration(args)
    if args.batch < 1:
        raise UsageError(f"--batch {args.batch}: expected a count of trials >= 1")
    engine = Engine(args.workers, args.ray)
    out = run_dir(args, "tune")
    r = write_directory(out, lambda tmp: tune(tmp, args.trials, args.storage, duration=args.duration,
                                              seed=args.seed, engine=engine, batch=args.batch))
    print(f"{r['trials']} trials; best MOTA {r['best_train_mota']:.1f}% on the training seeds; held out: "
          f"{r['held_out_mota_best']:.1f}% against the airport's own {r['held_out_mota_airport']:.1f}%; "
          f"{out / 'best.yaml'}")
    return 0
