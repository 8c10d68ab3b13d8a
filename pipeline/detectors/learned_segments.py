"""Laser people detection with a learned segment classifier: seed 000's boosted segment classifier ("Towards a
robust people tracking framework" Sec. II-A and IV-C; "Taking a closer look" Sec. III-A; the ROS book chapter Sec.
3.2), after Arras, Martinez Mozos & Burgard, "Using boosted features for the detection of people in 2D range data",
ICRA 2007.

The scan is cut into segments by jump distance (as ``laser_segments``), each segment of at least ``min_points``
returns gets the 13 geometric features of ``segment_features``, and a trained classifier gives it the probability of
being a person: the detection's confidence. Segments at or above ``threshold`` are detections. Two classifiers are
shipped in ``models/``: AdaBoost over decision stumps (Arras et al.'s boosting) and a random forest of 15 trees of
depth at most 10 (what seed 000's "Taking a closer look" Sec. III-A found best). Both were trained with scikit-learn by
``crowdsim experiment train-detector`` (crowdsim/experiments/train_detector.py says on which data) and are stored as
plain arrays, so running them needs no scikit-learn and no pickle: the stumps as JSON, the forest's nodes as an .npz
(walked by a compiled loop, pipeline/compiled.py).

A model file also holds the detection threshold chosen on validation seeds (peak F1 at 0.5 m) and the position
model measured on training data: the centre lies ``offset + per_width * width`` behind the segment's centroid along
the ray (``laser_segments`` uses offset 0 and pi/8 per metre of width, the geometry of a round body).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.compiled import kernel, pairwise
from pipeline.params import param
from pipeline.types import DetectedPersons, LaserScan

from .laser_segments import JUMP_DISTANCE, MIN_POINTS, POSITION_VARIANCE
from .segment_features import FEATURE_NAMES, Segments, jump_segments, segment_features

MODELS_DIR = Path(__file__).parent / "models"
MODEL_FILES = {"adaboost": "adaboost.json", "forest": "forest.npz"}
STUMPS_FORMAT = "crowdsim-segment-stumps/1"
FOREST_FORMAT = "crowdsim-segment-forest/1"


@dataclass(frozen=True)
class Stumps:
    """Discrete AdaBoost (SAMME) over decision stumps: stump t votes ``left[t]`` (+1 person, -1 not) when feature
    ``feature[t]`` <= ``threshold[t]``, else ``right[t]``, with weight ``weight[t]`` = log((1 - e_t) / e_t). The
    probability is 1 / (1 + exp(-F)), F = sum_t weight[t] vote_t: AdaBoost fits an additive logistic model in which
    F estimates the log-odds (Friedman, Hastie & Tibshirani, "Additive logistic regression", Ann. Stat. 2000, Sec.
    4), and 0.5 is its own decision sign(F) (Arras et al. 2007). scikit-learn's ``predict_proba`` orders segments
    the same, but from the weighted mean vote, which squeezes them into 0.12..0.88; its ``decision_function`` is
    2 F / sum(weight)."""

    feature: np.ndarray
    threshold: np.ndarray
    left: np.ndarray
    right: np.ndarray
    weight: np.ndarray

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """P(person) of each row of ``x`` [n, 13]."""
        x = np.asarray(x, np.float32)  # as scikit-learn's trees compare
        votes = np.where(x[:, self.feature] <= self.threshold, self.left, self.right)
        return 0.5 * (1.0 + np.tanh(0.5 * (votes @ self.weight)))  # the logistic function, without overflow


@dataclass(frozen=True)
class Forest:
    """Binary decision trees laid end to end: node i tests ``x[feature[i]] <= threshold[i]`` and goes to ``left[i]``
    or ``right[i]`` (-1 at a leaf, where ``value[i]`` is the leaf's share of persons); tree k starts at
    ``roots[k]``. The probability is the trees' mean leaf value (scikit-learn's ``predict_proba``)."""

    feature: np.ndarray
    threshold: np.ndarray
    left: np.ndarray
    right: np.ndarray
    value: np.ndarray
    roots: np.ndarray

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        """P(person) of each row of ``x`` [n, 13]."""
        out = np.empty(len(x))
        _forest(np.asarray(x, np.float32), self.feature, self.threshold, self.left, self.right, self.value,
                self.roots, out)
        return out


@kernel
def _forest(x, feature, threshold, left, right, value, roots, out):
    """Each row of ``x`` down every tree to its leaf (right where the feature is above the threshold, as
    scikit-learn's trees go; left for NaN); ``out`` the leaves' mean, summed as numpy's ``mean`` sums."""
    leaves = np.empty(len(roots))
    for r in range(len(x)):
        for t in range(len(roots)):
            node = roots[t]
            while left[node] >= 0:
                node = right[node] if x[r, feature[node]] > threshold[node] else left[node]
            leaves[t] = value[node]
        out[r] = pairwise(leaves, 0, len(roots)) / len(roots)


@dataclass(frozen=True)
class SegmentModel:
    """A trained classifier with its detection threshold, its position model and how it was made (``info``)."""

    classifier: Stumps | Forest
    threshold: float
    offset: float
    per_width: float
    info: dict = field(default_factory=dict)

    def header(self, fmt: str) -> dict:
        return {"format": fmt, "features": list(FEATURE_NAMES), "threshold": self.threshold,
                "position": {"offset": self.offset, "per_width": self.per_width}, "info": self.info}

    def save(self, path: Path) -> None:
        """Write the model: stumps as JSON (floats written exactly), a forest as an .npz of plain arrays."""
        c = self.classifier
        if isinstance(c, Stumps):
            arrays = {k: getattr(c, k).tolist() for k in ("feature", "threshold", "left", "right", "weight")}
            Path(path).write_text(json.dumps({**self.header(STUMPS_FORMAT), "stumps": arrays}, indent=1) + "\n")
        else:
            with open(path, "wb") as f:  # np.savez would append .npz to a name without it
                np.savez_compressed(f, meta=np.array(json.dumps(self.header(FOREST_FORMAT))),
                                    **{k: getattr(c, k) for k in ("feature", "threshold", "left", "right", "value",
                                                                  "roots")})


def load_model(model: str | Path) -> SegmentModel:
    """A shipped model by name (``adaboost``, ``forest``) or a model file (.json stumps, .npz forest)."""
    path = MODELS_DIR / MODEL_FILES[model] if model in MODEL_FILES else Path(model)
    if path.suffix not in (".json", ".npz") or not path.is_file():
        raise ValueError(f"model: expected {', '.join(MODEL_FILES)} or the path of a .json or .npz model file "
                         f"(crowdsim experiment train-detector writes them), got {str(model)!r}")
    if path.suffix == ".json":
        meta = _checked(json.loads(path.read_text()), STUMPS_FORMAT, path)
        s = meta["stumps"]
        classifier = Stumps(np.asarray(s["feature"], np.int64), np.asarray(s["threshold"], float),
                            np.asarray(s["left"], float), np.asarray(s["right"], float),
                            np.asarray(s["weight"], float))
    else:
        with np.load(path, allow_pickle=False) as z:
            meta = _checked(json.loads(str(z["meta"])), FOREST_FORMAT, path)
            classifier = Forest(*(z[k] for k in ("feature", "threshold", "left", "right", "value", "roots")))
    pos = meta["position"]
    return SegmentModel(classifier, float(meta["threshold"]), float(pos["offset"]), float(pos["per_width"]),
                        meta.get("info", {}))


def _checked(meta: dict, fmt: str, path: Path) -> dict:
    if meta.get("format") != fmt or tuple(meta.get("features", ())) != FEATURE_NAMES:
        raise ValueError(f"{path}: expected a {fmt} model over the features {', '.join(FEATURE_NAMES)}")
    return meta


def candidates(scan: LaserScan, jump_distance: float, min_points: int) -> tuple[Segments, np.ndarray, np.ndarray]:
    """The scan's segments, which of them are candidates (at least ``min_points`` returns) and the candidates'
    features [c, 13]. Features are computed on the whole scan, so neighbours' jump distances count every segment."""
    seg = jump_segments(scan, jump_distance)
    keep = seg.count >= min_points
    return seg, keep, segment_features(seg, scan.range_max)[keep]


def push_back(centroid: np.ndarray, width: np.ndarray, offset: float, per_width: float) -> np.ndarray:
    """Body centres [n, 2]: each centroid moved ``offset + per_width * width`` away from the sensor along its ray."""
    ray = centroid / np.maximum(np.linalg.norm(centroid, axis=1), 1e-9)[:, None]
    return centroid + ray * (offset + per_width * width)[:, None]


@dataclass(eq=False)
class LearnedSegmentDetector:
    """The ``laser_learned`` detector; ``threshold`` left out becomes the model's when the detector is made."""

    model: str = param("forest", "adaboost (Arras et al. 2007's boosted stumps, seed 000 Sec. II-A), forest (15 trees "
                                 "of depth 10, seed 000 Sec. III-A: best there), or the path of a .json/.npz model "
                                 "`crowdsim experiment train-detector --out` wrote")
    threshold: float | None = param(None, "least person probability detected; left out: the model's own (peak F1 on "
                                          "validation seeds)", kind="float", min=0.0, max=1.0)
    jump_distance: float = param(**JUMP_DISTANCE)
    min_points: int = param(**MIN_POINTS)
    position_variance: float = param(**POSITION_VARIANCE)

    def __post_init__(self):
        self.segment_model = load_model(self.model)
        self.threshold = self.segment_model.threshold if self.threshold is None else float(self.threshold)
        self.reset()

    def reset(self) -> None:
        """Detection ids start again from 0."""
        self._next_id = 0

    def score(self, scan: LaserScan) -> tuple[np.ndarray, np.ndarray]:
        """Every candidate segment's body centre [c, 2] (sensor frame) and probability of being a person [c]."""
        seg, keep, x = candidates(scan, self.jump_distance, self.min_points)
        width = x[:, FEATURE_NAMES.index("width")]
        model = self.segment_model
        return push_back(seg.centroid[keep], width, model.offset, model.per_width), model.classifier.predict_proba(x)

    def detect(self, scan: LaserScan) -> DetectedPersons:
        centre, p = self.score(scan)
        keep = p >= self.threshold
        out = DetectedPersons.on_floor(scan.stamp, scan.frame, "laser2d", self._next_id, centre[keep],
                                       self.position_variance, p[keep])
        self._next_id += len(out.detection_id)
        return out
