"""``crowdsim experiment train-detector``: trains the ``laser_learned`` detector's two segment classifiers (AdaBoost
over decision stumps, a random forest) on this testbed's own labelled scans and compares them with the geometric
``laser_segments`` detector on held-out seeds.

Data. The airport scenario (``airport_disembarkation``, its warm-up, then ``DURATION`` s) is run on seeds no
evaluation uses: training seeds 1000..1000+N-1 (N = ``--seeds``, default 20), validation seeds 2000-2002 (the
detection threshold), test seeds 3000-3002 (the tables); the tracking evaluations elsewhere use seeds 1-20. Every
``EVERY``-th laser cycle of both lasers is kept (5 Hz of 25, so successive scans differ). Each scan is segmented
and featured exactly as the detector does it (``learned_segments.candidates``); a segment is a person when more
than half of its returns hit one person (``LaserScan.person_id``, simulation-only).

Models (scikit-learn, needs the ``[train]`` extra). AdaBoost: discrete AdaBoost (SAMME) over ``N_STUMPS``
decision stumps, as Arras, Martinez Mozos & Burgard (ICRA 2007) boost single-feature threshold classifiers. Random
forest: 15 trees of depth at most 10, seed 000's setting ("Taking a closer look" Sec. III-A). Both are converted to the
numpy-only form of ``pipeline.detectors.learned_segments`` and saved with the threshold of peak F1 at 0.5 m on the
validation seeds and the position model fitted on the training persons (centre = centroid pushed back along the
ray by offset + per_width x width, least squares).

Scores (evaluation/detection.py): AP, peak F1 and EER at 0.3 m and 0.5 m, over every kept scan of the test seeds,
in each laser's frame, in two tables by who counts as ground truth: (1) every person hit by at least 1 beam of
that scan's laser, i.e. everyone the laser saw (the thresholds are chosen for this one); (2) those hit by at least
``MIN_BEAMS`` = 6 beams, crowdsim/datasets/detection_eval.py's rule after DR-SPAAM, comparable with ``crowdsim
dataset evaluate-detector``. A detection of anyone not counted is a false positive, so (2) penalises detecting
persons seen by 3 to 5 beams. The learned detectors are scored on every candidate segment with its score (the
whole curve); the geometric detector gives confidence 1 to each detection, so its curve is one point.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from crowdsim.datasets.detection_eval import MIN_BEAMS
from crowdsim.experiments.seeds import map_seeds
from crowdsim import workers
from crowdsim.workers import Engine
from evaluation.detection import RADII, DetectionScores, detection_scores
from pipeline.detectors.laser_segments import SegmentDetector
from pipeline.detectors.learned_segments import MODEL_FILES, Forest, SegmentModel, Stumps, candidates, push_back
from pipeline.detectors.segment_features import FEATURE_NAMES, Segments
from pipeline.frames import inverse, transform_points

SCENARIO = "airport_disembarkation"
TRAIN_SEED = 1000  # training seeds TRAIN_SEED .. TRAIN_SEED + N - 1
VALIDATION_SEEDS = tuple(range(2000, 2003))
TEST_SEEDS = tuple(range(3000, 3003))
DURATION = 30.0  # s recorded per seed after the scenario's warm-up
EVERY = 5  # keep every 5th laser cycle
N_STUMPS = 100
FOREST = {"n_estimators": 15, "max_depth": 10}  # seed 000, "Taking a closer look" Sec. III-A
JUMP_DISTANCE, MIN_POINTS = 0.4, 3  # the detector's defaults (scenarios/format.py)
GT_MIN_BEAMS = (1, MIN_BEAMS)  # who counts as ground truth, per table (module docstring)
QUICK = {"seeds": 4, "validation": VALIDATION_SEEDS[:1], "test": TEST_SEEDS[:1], "duration": 10.0}


FIELDS = ("x", "person", "centroid", "target", "seg_scan", "gt", "gt_beams", "gt_scan", "geometric", "geo_scan")


@dataclass
class Scans:
    """The candidate segments of many scans, with their labels and each scan's ground truth and geometric
    detections; rows of a kind are tied to their scan by an index (``*_scan``)."""

    x: np.ndarray  # [n, 13] features
    person: np.ndarray  # [n] bool label
    centroid: np.ndarray  # [n, 2] sensor frame
    target: np.ndarray  # [n, 2] the centre of the person the segment is (NaN for no person)
    seg_scan: np.ndarray  # [n]
    gt: np.ndarray  # [g, 2] the persons hit by the scan
    gt_beams: np.ndarray  # [g] by how many of its beams
    gt_scan: np.ndarray
    geometric: np.ndarray  # [d, 2] laser_segments' detections
    geo_scan: np.ndarray
    n_scans: int

    @staticmethod
    def join(parts: list[Scans]) -> Scans:
        """One batch of several, scan indices renumbered."""
        first = np.cumsum([0] + [p.n_scans for p in parts[:-1]])
        joined = {}
        for name in FIELDS:
            rows = [getattr(p, name) for p in parts]
            joined[name] = np.concatenate([r + f for r, f in zip(rows, first)] if name.endswith("_scan") else rows)
        return Scans(**joined, n_scans=sum(p.n_scans for p in parts))

    def frames(self, xy: np.ndarray, conf: np.ndarray, scan: np.ndarray, min_beams: int):
        """(detections, confidences, ground truth: the persons hit by ``min_beams`` or more beams) per scan, for
        ``detection_scores``; ``scan`` sorted."""
        seen = self.gt_beams >= min_beams
        gt, gt_scan = self.gt[seen], self.gt_scan[seen]
        d = np.searchsorted(scan, np.arange(self.n_scans + 1))
        g = np.searchsorted(gt_scan, np.arange(self.n_scans + 1))
        for k in range(self.n_scans):
            yield xy[d[k]:d[k + 1]], conf[d[k]:d[k + 1]], gt[g[k]:g[k + 1]]


def label_segments(seg: Segments, person_id: np.ndarray) -> np.ndarray:
    """Per segment the id of the person who got more than half of its returns, else -1 (``person_id``: per beam)."""
    pid = person_id[seg.beam]
    hit = pid >= 0
    pairs, counts = np.unique(np.stack([seg.label[hit], pid[hit]]), axis=1, return_counts=True)
    owner = np.full(len(seg.start), -1, np.int64)
    major = counts * 2 > seg.count[pairs[0]]  # at most one person per segment can pass
    owner[pairs[0, major]] = pairs[1, major]
    return owner


def collect(seed: int, duration: float, every: int = EVERY) -> Scans:
    """Run the airport scenario on ``seed`` and label the candidate segments of every ``every``-th laser cycle."""
    from crowdsim.loop import Simulation
    from scenarios import load_scenario

    sim = Simulation(load_scenario(SCENARIO))
    sim.reset(seed)
    sim.warm_up()
    lasers = {laser.name: laser for laser in sim.lasers}
    geometric = SegmentDetector(JUMP_DISTANCE, MIN_POINTS)
    parts: dict[str, list] = {k: [] for k in FIELDS}
    n = 0
    for k, frame in enumerate(sim.frames(duration)):
        if k % every:
            continue
        agents = frame.agents
        for scan in frame.scans:
            xy = transform_points(inverse(lasers[scan.frame].pose_in(frame.robot_pose)), agents.position)
            ids, beams = np.unique(scan.person_id[scan.person_id >= 0], return_counts=True)
            seen = xy[np.searchsorted(agents.id, ids)]
            seg, keep, x = candidates(scan, JUMP_DISTANCE, MIN_POINTS)
            owner = label_segments(seg, scan.person_id)[keep]
            target = np.full((len(owner), 2), np.nan)
            target[owner >= 0] = xy[np.searchsorted(agents.id, owner[owner >= 0])]
            det = geometric.detect(scan).position[:, :2]
            for name, value in (("x", x), ("person", owner >= 0), ("centroid", seg.centroid[keep]),
                                ("target", target), ("seg_scan", np.full(len(x), n)), ("gt", seen),
                                ("gt_beams", beams), ("gt_scan", np.full(len(seen), n)), ("geometric", det),
                                ("geo_scan", np.full(len(det), n))):
                parts[name].append(value)
            n += 1
    return Scans(**{k: np.concatenate(v) for k, v in parts.items()}, n_scans=n)


def collect_seeds(seeds: list[int], duration: float, engine: Engine) -> list[Scans]:
    """``collect`` of each of ``seeds``, in order, on ``engine``."""
    return map_seeds(collect, seeds, duration, engine=engine, desc="simulating")


def stumps_from_sklearn(ada) -> Stumps:
    """The stumps of a fitted two-class ``AdaBoostClassifier`` (SAMME over depth-1 trees); a stump that never split
    votes its root's class on both sides."""
    person = int(np.flatnonzero(ada.classes_ == ada.classes_.max())[0])  # the second class: True / 1
    rows = []
    for tree in (e.tree_ for e in ada.estimators_):
        vote = np.where(tree.value[:, 0, :].argmax(axis=1) == person, 1.0, -1.0)
        split = tree.node_count > 1
        rows.append((tree.feature[0] if split else 0, tree.threshold[0] if split else 0.0,
                     vote[tree.children_left[0]] if split else vote[0],
                     vote[tree.children_right[0]] if split else vote[0]))
    feature, threshold, left, right = (np.array(c) for c in zip(*rows))
    return Stumps(feature.astype(np.int64), threshold.astype(float), left, right,
                  np.asarray(ada.estimator_weights_[:len(rows)], float))


def forest_from_sklearn(rf) -> Forest:
    """The trees of a fitted two-class ``RandomForestClassifier`` laid end to end, leaves holding P(person)."""
    person = int(np.flatnonzero(rf.classes_ == rf.classes_.max())[0])
    parts, roots, offset = [], [], 0
    for tree in (e.tree_ for e in rf.estimators_):
        left, right = tree.children_left, tree.children_right
        value = tree.value[:, 0, :]
        parts.append((tree.feature, tree.threshold, np.where(left >= 0, left + offset, -1),
                      np.where(right >= 0, right + offset, -1), value[:, person] / value.sum(axis=1)))
        roots.append(offset)
        offset += tree.node_count
    feature, threshold, left, right, value = (np.concatenate(c) for c in zip(*parts))
    return Forest(feature.astype(np.int64), threshold.astype(float), left.astype(np.int64), right.astype(np.int64),
                  value.astype(float), np.asarray(roots, np.int64))


def fit_position(data: Scans) -> tuple[float, float]:
    """(offset, per_width): the least-squares line of the along-ray distance from a person segment's centroid to
    the person's centre against the segment's width."""
    person = data.person
    c, t = data.centroid[person], data.target[person]
    along = ((t - c) * c).sum(axis=1) / np.linalg.norm(c, axis=1)
    width = data.x[person, FEATURE_NAMES.index("width")]
    per_width, offset = np.polyfit(width, along, 1)
    return float(offset), float(per_width)


def position_error(data: Scans, offset: float, per_width: float) -> float:
    """Mean distance (m) between the person segments' centre estimates and their persons' centres."""
    p = data.person
    centre = push_back(data.centroid[p], data.x[p, FEATURE_NAMES.index("width")], offset, per_width)
    return float(np.linalg.norm(centre - data.target[p], axis=1).mean())


def learned_scores(data: Scans, model: SegmentModel, min_beams: int) -> dict[float, DetectionScores]:
    """Every candidate segment as a detection with the model's probability, scored at both radii."""
    xy = push_back(data.centroid, data.x[:, FEATURE_NAMES.index("width")], model.offset, model.per_width)
    p = model.classifier.predict_proba(data.x)
    return detection_scores(data.frames(xy, p, data.seg_scan, min_beams), RADII)


def geometric_scores(data: Scans, min_beams: int) -> dict[float, DetectionScores]:
    conf = np.ones(len(data.geometric))
    return detection_scores(data.frames(data.geometric, conf, data.geo_scan, min_beams), RADII)


def table(rows: dict[str, dict[float, DetectionScores]]) -> str:
    """One row per detector: ground truth and detections, then AP, peak F1 and EER in % at each radius."""
    head = ["detector", "GT", "detections", *(f"{k}@{r:g}" for r in RADII for k in ("AP", "peakF1", "EER"))]
    body = [[name, str(s[RADII[0]].n_gt), str(s[RADII[0]].n_detections),
             *(f"{100 * getattr(s[r], k):.1f}" for r in RADII for k in ("ap", "peak_f1", "eer"))]
            for name, s in rows.items()]
    width = [max(len(row[k]) for row in [head, *body]) for k in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) if k == 0 else c.rjust(w) for k, (c, w) in enumerate(zip(row, width)))
                     for row in [head, *body])


def train(n_seeds: int = 20, quick: bool = False, engine: Engine = Engine()) -> tuple[dict[str, SegmentModel], str]:
    """Collect, train, choose thresholds and score: the two models and the report (tables and notes)."""
    try:
        import sklearn
        from sklearn.ensemble import AdaBoostClassifier, RandomForestClassifier
        from sklearn.tree import DecisionTreeClassifier
    except ImportError as e:
        raise ImportError('crowdsim experiment train-detector needs scikit-learn: pip install -e ".[train]"') from e
    n_seeds, val_seeds, test_seeds, duration = ((QUICK["seeds"], QUICK["validation"], QUICK["test"],
                                                 QUICK["duration"]) if quick else
                                                (n_seeds, VALIDATION_SEEDS, TEST_SEEDS, DURATION))
    if not 1 <= n_seeds <= VALIDATION_SEEDS[0] - TRAIN_SEED:
        raise ValueError(f"--seeds: expected 1 to {VALIDATION_SEEDS[0] - TRAIN_SEED} training seeds, got {n_seeds}")
    train_seeds = list(range(TRAIN_SEED, TRAIN_SEED + n_seeds))
    parts = collect_seeds([*train_seeds, *val_seeds, *test_seeds], duration, engine)
    data, val, test = (Scans.join(parts[a:b]) for a, b in ((0, n_seeds), (n_seeds, n_seeds + len(val_seeds)),
                                                           (n_seeds + len(val_seeds), len(parts))))
    offset, per_width = fit_position(data)
    x = data.x.astype(np.float32)
    estimators = {"adaboost": AdaBoostClassifier(DecisionTreeClassifier(max_depth=1), n_estimators=N_STUMPS,
                                                 random_state=0),
                  "forest": RandomForestClassifier(**FOREST, n_jobs=engine.workers, random_state=0)}
    convert = {"adaboost": stumps_from_sklearn, "forest": forest_from_sklearn}
    info = {"scenario": SCENARIO, "train_seeds": [train_seeds[0], train_seeds[-1]],
            "validation_seeds": [val_seeds[0], val_seeds[-1]], "duration_s": duration, "every": EVERY,
            "segments": len(data.person), "persons": int(data.person.sum()), "scikit_learn": sklearn.__version__}
    models = {}
    for name in tqdm(estimators, desc="training", unit="model"):
        params = {k: v for k, v in estimators[name].get_params().items() if k in ("n_estimators", "max_depth")}
        classifier = convert[name](estimators[name].fit(x, data.person))
        draft = SegmentModel(classifier, 0.5, offset, per_width)
        threshold = learned_scores(val, draft, GT_MIN_BEAMS[0])[0.5].peak_f1_threshold
        models[name] = SegmentModel(classifier, threshold, offset, per_width, {**info, "estimator": params})
    tables = []
    for min_beams in GT_MIN_BEAMS:
        rows = {"laser_segments (geometric)": geometric_scores(test, min_beams)}
        rows |= {f"laser_learned {name}": learned_scores(test, model, min_beams) for name, model in models.items()}
        tables.append(f"GT: persons hit by >= {min_beams} beam(s) of the scan's laser\n{table(rows)}")
    notes = (f"test seeds {test_seeds[0]}-{test_seeds[-1]} of {SCENARIO}: {test.n_scans} scans ({duration:g} s each, "
             f"every {EVERY}th cycle of both lasers); AP, peak F1, EER in %\n"
             f"trained on seeds {train_seeds[0]}-{train_seeds[-1]}: {len(data.person)} segments, "
             f"{int(data.person.sum())} persons; thresholds (peak F1 @0.5 m, GT >= {GT_MIN_BEAMS[0]} beam, on "
             f"validation seeds {val_seeds[0]}-{val_seeds[-1]}): "
             + ", ".join(f"{k} {m.threshold:.3f}" for k, m in models.items())
             + f"\nposition: centroid + ({offset:.3f} + {per_width:.3f} x width) along the ray; mean error on "
             f"validation persons {position_error(val, offset, per_width):.3f} m (laser_segments' pi/8 x width: "
             f"{position_error(val, 0.0, np.pi / 8):.3f} m)")
    return models, "\n\n".join([*tables, notes])


def save_models(models: dict[str, SegmentModel], out: Path) -> list[Path]:
    """Each model under its shipped file name in ``out``, replaced whole (written beside, then renamed)."""
    paths = []
    for name, model in models.items():
        path = Path(out) / MODEL_FILES[name]
        tmp = path.with_name(f".{path.name}.{os.getpid()}.partial{path.suffix}")
        model.save(tmp)
        os.replace(tmp, path)
        paths.append(path)
    return paths


def add_arguments(parser) -> None:
    from .training import add_models_out_argument

    parser.add_argument("--seeds", type=int, default=20, help=f"training seeds, from {TRAIN_SEED} (default 20)")
    parser.add_argument("--quick", action="store_true", help="4 short training seeds, 1 validation and 1 test seed (a "
                                                             "smoke test, not models to ship)")
    workers.add_arguments(parser)
    add_models_out_argument(parser, "pipeline/detectors/models/")


def main(args) -> int:
    """``crowdsim experiment train-detector``."""
    import time

    from pipeline.detectors.learned_segments import MODELS_DIR

    from ..cli import UsageError
    from .training import saved, sizes, training_out

    if not 1 <= args.seeds <= VALIDATION_SEEDS[0] - TRAIN_SEED:
        raise UsageError(f"--seeds: expected 1 to {VALIDATION_SEEDS[0] - TRAIN_SEED} training seeds, got {args.seeds}")
    if args.workers < 1:
        raise UsageError(f"--workers: expected at least 1 process, got {args.workers}")
    out = training_out(args)
    t0 = time.perf_counter()
    models, report = train(args.seeds, quick=args.quick, engine=Engine(args.workers, args.ray))
    paths = saved(models, save_models, out, MODELS_DIR)
    print(report)
    print(f"{time.perf_counter() - t0:.0f} s; models: " + sizes(paths))
    return 0
