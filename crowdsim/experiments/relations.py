"""Training the relation classifiers on tracker output (``crowdsim experiment train-relations``), and the per-cycle
data the group experiment scores.

Why tracker output: the classifier runs on tracks, whose velocities are noisier than the crowd's (a track's speed
lags a person who stops, its heading swings at low speed), so it is trained on what it will see. Each airport run
(the bundled pipeline, 60 s from the warm-up) gives, every ``EVERY``-th cycle, the pairs of tracks that CLEAR-MOT
matched to two counted persons and that pass SPENCER's gates (only those reach the classifier); the label is whether
the two persons share a true group. Seeds: training 1100-1119, calibration 1120-1124 (the Platt sigmoid is fitted
there, as Platt 1999 fits it on data the SVM did not see), held out 1200 on (``crowdsim experiment groups``); none is
a seed any other evaluation uses.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.groups.relations import (INDICATORS, MODEL_FILES, MODELS_DIR, PlattSvm, RelationTable, indicators,
                                       monomial_powers, monomials, save_model, tabulate)
from pipeline.types import TrackedPersons
from scenarios import load_scenario
from scenarios.typed import Scenario

from .seeds import map_seeds
from ..workers import Engine

SCENARIO = "airport_disembarkation"
TRAIN_SEED, CALIBRATION_SEEDS, HELD_OUT_SEED = 1100, list(range(1120, 1125)), 1200
DURATION = 60.0  # s of each run
EVERY = 5  # cycles between the cycles sampled (0.4 s at 12.5 Hz: consecutive cycles are nearly the same pairs)
DEGREE = 3  # of the SVM's monomials
SVM_C = 1.0
FOREST = {"n_estimators": 30, "max_depth": 8, "min_samples_leaf": 20}
GATES = np.array([3.0, 1.0, np.pi / 4])  # SPENCER's; only pairs inside reach a classifier
# the forest's grid: 2 cm, 2 cm/s and 1 degree, finer than a track's noise (0.1 m/s in speed); 354,246 points
TABLE_STEP = np.array([0.02, 0.02, np.pi / 180])
TABLE_SAMPLES = 3  # per indicator: each grid value is the forest's mean over 27 points of its cell


@dataclass(frozen=True)
class GroupCycle:
    """One tracking cycle as the group stage and its evaluation see it: the tracks (odom), the counted ground truth
    (odom, with true group ids), and CLEAR-MOT's matches (person, track) and excused tracks."""

    stamp: float
    tracks: TrackedPersons
    gt: TrackedPersons
    matched_gt: np.ndarray
    matched_track: np.ndarray
    excused: np.ndarray
    queued: np.ndarray  # [counted persons] standing in a queue (the crowd's state, for the queue check)

    def from_groundtruth(self) -> "GroupCycle":
        """The same cycle with the counted persons themselves as the tracks (what a perfect tracker would give)."""
        return GroupCycle(self.stamp, self.gt, self.gt, self.gt.track_id, self.gt.track_id, np.zeros(0, np.int64),
                          self.queued)


def airport() -> Scenario:
    """The bundled airport with SPENCER's relation model (the data do not depend on it, and retraining does not
    need the shipped models)."""
    scenario = load_scenario(SCENARIO)
    pipeline = scenario.pipeline
    return scenario.replace(pipeline=pipeline.replace(groups=pipeline.groups.replace(model="spencer")))


def collect(seed: int, duration: float = DURATION) -> list[GroupCycle]:
    """Every tracking cycle of an airport run from ``seed``."""
    from crowdsim.loop import Simulation
    from crowdsim.scoring import CycleScorer

    sim = Simulation(airport())
    sim.reset(seed)
    sim.warm_up()
    score = CycleScorer(sim.scenario.evaluation.threshold)
    out = []
    for f in sim.frames(duration):
        gt = f.groundtruth.select(~f.gt_tags.ignore)
        queued = np.isin(gt.track_id, f.agents.id[sim.crowd.queued >= 0])
        matched = score(f)
        out.append(GroupCycle(f.stamp, f.tracks, gt, matched.matched_gt_ids, matched.matched_hyp_ids,
                              matched.excused_hyp_ids, queued))
    return out


def collect_seeds(seeds: list[int], duration: float = DURATION, engine: Engine = Engine(),
                  progress: bool = True) -> list[list[GroupCycle]]:
    """``collect`` of each seed, in order, on ``engine``."""
    return map_seeds(collect, seeds, duration, engine=engine, desc="simulating", progress=progress)


def labelled_pairs(cycle: GroupCycle, min_speed: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """(indicators [k, 3], related [k]) of the pairs of tracks matched to two counted persons, inside the gates."""
    tracks, gt = cycle.tracks, cycle.gt
    rows = np.flatnonzero(np.isin(tracks.track_id, cycle.matched_track))
    person = cycle.matched_gt[np.argsort(cycle.matched_track)][np.searchsorted(np.sort(cycle.matched_track),
                                                                               tracks.track_id[rows])]
    group = gt.group_id[np.searchsorted(gt.track_id, person)] if len(gt) else np.zeros(0, np.int64)
    i, j, x = indicators(tracks.position[rows], tracks.velocity[rows], min_speed)
    inside = (x <= GATES).all(axis=1)
    related = (group[i] >= 0) & (group[i] == group[j])
    return x[inside], related[inside]


def pairs_of(runs: list[list[GroupCycle]], every: int = EVERY, groundtruth: bool = False):
    """``labelled_pairs`` of every ``every``-th cycle of ``runs``, stacked."""
    parts = [labelled_pairs(c.from_groundtruth() if groundtruth else c) for run in runs for c in run[::every]]
    return (np.concatenate([p[0] for p in parts]).reshape(-1, 3),
            np.concatenate([p[1] for p in parts]).astype(bool))


def platt(decision: np.ndarray, related: np.ndarray) -> tuple[float, float]:
    """Platt's sigmoid P = 1 / (1 + exp(a f + b)) fitted by maximum likelihood on decision values ``f``."""
    from sklearn.linear_model import LogisticRegression

    fit = LogisticRegression(C=1e6).fit(decision[:, None], related)
    return -float(fit.coef_[0, 0]), -float(fit.intercept_[0])


def train_svm(x: np.ndarray, y: np.ndarray, x_cal: np.ndarray, y_cal: np.ndarray) -> PlattSvm:
    """A linear SVM (scikit-learn's LinearSVC: L2-regularised, squared hinge loss) on the cubic monomials of the
    standardised indicators, and Platt's sigmoid on the calibration pairs."""
    from sklearn.svm import LinearSVC

    mean, scale = x.mean(axis=0), x.std(axis=0)
    powers = monomial_powers(x.shape[1], DEGREE)
    svm = LinearSVC(C=SVM_C, dual=False, max_iter=10_000)  # squared hinge, solved in the primal (liblinear)
    svm.fit(monomials((x - mean) / scale, powers), y)
    draft = PlattSvm(mean, scale, powers, svm.coef_[0].copy(), float(svm.intercept_[0]), -1.0, 0.0)
    a, b = platt(draft.decision(x_cal), y_cal)
    return PlattSvm(mean, scale, powers, draft.weight, draft.intercept, a, b)


def train_forest(x: np.ndarray, y: np.ndarray) -> RelationTable:
    """A random forest, tabulated over the gates' box on ``TABLE_STEP``'s grid, each cell's mean."""
    from sklearn.ensemble import RandomForestClassifier

    from .train_detector import forest_from_sklearn

    forest = forest_from_sklearn(RandomForestClassifier(**FOREST, random_state=0).fit(x.astype(np.float32), y))
    return tabulate(forest, GATES, TABLE_STEP, TABLE_SAMPLES)


def train(n_seeds: int = 20, duration: float = DURATION, engine: Engine = Engine(), progress: bool = True):
    """The two classifiers (``svm``, ``forest``) trained on ``n_seeds`` training seeds, and what they were made
    from."""
    train_seeds = list(range(TRAIN_SEED, TRAIN_SEED + n_seeds))
    runs = collect_seeds(train_seeds + CALIBRATION_SEEDS, duration, engine, progress)
    return fit(runs[:n_seeds], runs[n_seeds:], train_seeds, duration)


def fit(train_runs: list[list[GroupCycle]], calibration_runs: list[list[GroupCycle]], train_seeds: list[int],
        duration: float) -> dict:
    """The two classifiers fitted on the runs' labelled pairs, each with how it was made."""
    import sklearn

    x, y = pairs_of(train_runs)
    x_cal, y_cal = pairs_of(calibration_runs)
    info = {"scenario": SCENARIO, "train_seeds": [train_seeds[0], train_seeds[-1]],
            "calibration_seeds": [CALIBRATION_SEEDS[0], CALIBRATION_SEEDS[-1]], "duration_s": duration,
            "every": EVERY, "pairs": int(len(y)), "related": int(y.sum()), "indicators": list(INDICATORS),
            "scikit_learn": sklearn.__version__}
    return {"svm": (train_svm(x, y, x_cal, y_cal), {**info, "estimator": {"C": SVM_C, "degree": DEGREE}}),
            "forest": (train_forest(x, y), {**info, "estimator": FOREST, "table_step": TABLE_STEP.tolist(),
                                            "table_samples": TABLE_SAMPLES})}


def save_models(models: dict, out: Path = MODELS_DIR) -> list[Path]:
    """Each model under its shipped name in ``out``, replaced whole (written beside, then renamed)."""
    paths = []
    for name, (classifier, info) in models.items():
        path = Path(out) / MODEL_FILES[name]
        tmp = path.with_name(f".{path.stem}.{os.getpid()}.partial.npz")
        save_model(tmp, classifier, info)
        os.replace(tmp, path)
        paths.append(path)
    return paths
