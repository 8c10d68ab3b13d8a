"""Social relations between tracked persons from their coherent motion: SPENCER's relation stage (seed 000: D2.5 Sec.
3 and the ROS book chapter, Linder & Arras 2016, Sec. 5.1; indicators after Moussaid et al. 2010).

For every pair of tracks, three indicators: their distance, the difference of their speeds, and the difference of
their headings, each heading taken from the track's velocity and set to 0 below ``min_speed`` (0.1 m/s), as
SPENCER's ``spatial_relations.cpp`` does (a slow track's heading is 0 rad, not "none", so a slow track against a
mover differs by the mover's own heading). Pairs past any gate (farther than 3 m, speeds more than 1 m/s apart, or
headings more than pi/4 apart; strict) get strength 0.1 without the classifier; the others get the classifier's
probability that the two walk together.

Classifiers (``load_model``): ``spencer``, the released default of SPENCER, a linear nu-SVC on the raw indicators
with libsvm's Platt sigmoid; ``svm``, ours, a linear SVM on the cubic monomials of the standardised indicators (the
function class of a cubic polynomial kernel) with a Platt sigmoid fitted on held-out seeds; ``forest``, ours, a
random forest whose leaves hold the share of related pairs, shipped tabulated (``RelationTable``). Ours are trained
on pairs of tracker output labelled by the true groups of the persons the tracks matched (``crowdsim experiment
train-relations``), so they learn the tracker's noise; they ship in ``models/`` as plain arrays.

``LongTermRelations`` is SPENCER's optional temporal smoothing (``long_term_relations.py``).
"""

from __future__ import annotations

import functools
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.compiled import kernel

MODELS_DIR = Path(__file__).parent / "models"
MODEL_FILES = {"svm": "relations_svm.npz", "forest": "relations_forest.npz"}
MODEL_FORMAT = "crowdsim-relations/1"
GATED_STRENGTH = 0.1  # spatial_relations.cpp: a gated pair is related with probability 0.1
INDICATORS = ("distance", "speed_difference", "heading_difference")


@functools.lru_cache(maxsize=64)
def pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows (i, j) of every pair i < j of ``n`` (read-only: shared between calls)."""
    i, j = np.triu_indices(n, 1)
    i.flags.writeable = j.flags.writeable = False
    return i, j


def indicators(position: np.ndarray, velocity: np.ndarray, min_speed: float = 0.1, i: np.ndarray | None = None,
               j: np.ndarray | None = None):
    """(i, j, x) for the pairs of tracks (rows) i and j, every pair i < j when not given: x [pairs, 3] holds the
    distance (m), the speed difference (m/s) and the heading difference (rad, in [0, pi]; a track slower than
    ``min_speed`` heads at 0 rad)."""
    if i is None:
        i, j = pairs(len(position))
    distance = np.hypot(position[i, 0] - position[j, 0], position[i, 1] - position[j, 1])
    return i, j, np.column_stack([distance, *motion_differences(velocity, min_speed, i, j)])


def motion_differences(velocity: np.ndarray, min_speed: float, i: np.ndarray,
                       j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The speed and heading differences of the pairs of rows (i, j), as ``indicators`` defines them."""
    speed, heading = _motion(velocity, min_speed)
    return _pair_differences(speed, heading, np.ascontiguousarray(i, np.int64), np.ascontiguousarray(j, np.int64))


def _motion(velocity: np.ndarray, min_speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Each track's speed and heading (0 rad below ``min_speed``), by numpy's hypot and arctan2 (the values the
    classifiers were trained on)."""
    speed = np.hypot(velocity[:, 0], velocity[:, 1])
    return speed, np.where(speed >= min_speed, np.arctan2(velocity[:, 1], velocity[:, 0]), 0.0)


@kernel
def _difference(speed, heading, a, b):
    """The speed and heading differences of tracks a and b (headings in [-pi, pi]: the difference wraps once at
    most)."""
    turn = abs(heading[a] - heading[b])
    return abs(speed[a] - speed[b]), min(turn, 2 * math.pi - turn)


@kernel
def _pair_differences(speed, heading, i, j):
    """``_difference`` of each pair of rows (i, j)."""
    ds, turn = np.empty(len(i)), np.empty(len(i))
    for p in range(len(i)):
        ds[p], turn[p] = _difference(speed, heading, i[p], j[p])
    return ds, turn


@kernel
def _gated(position, speed, heading, near, limits):
    """The pairs of tracks i < j inside the three gates, as their place in ``pairs``' order, and their indicators.
    The squared distance is checked first (``near``: the distance gate squared, widened past any rounding): a
    crowd's pairs are most of them farther, and cost no hypot."""
    n = len(position)
    at, x = np.empty(n * (n - 1) // 2, np.int64), np.empty((n * (n - 1) // 2, 3))
    k = m = 0
    for a in range(n):
        for b in range(a + 1, n):
            dx, dy = position[a, 0] - position[b, 0], position[a, 1] - position[b, 1]
            if dx * dx + dy * dy <= near:
                distance = math.hypot(dx, dy)
                ds, turn = _difference(speed, heading, a, b)
                if distance <= limits[0] and ds <= limits[1] and turn <= limits[2]:
                    at[m], x[m, 0], x[m, 1], x[m, 2] = k, distance, ds, turn
                    m += 1
            k += 1
    return at[:m], x[:m]


def monomials(z: np.ndarray, powers: np.ndarray) -> np.ndarray:
    """The products prod_k z[:, k] ** powers[m, k] for each row of ``powers`` [m, d], as products of columns (a
    power of an array by an array of exponents is ten times slower)."""
    factors = _factors(powers.tobytes(), powers.shape)
    out = np.ones((len(z), len(powers)))
    ones_z = np.column_stack([z, np.ones(len(z))])
    for column in factors.T:
        out *= ones_z[:, column]
    return out


@functools.lru_cache(maxsize=8)
def _factors(key: bytes, shape: tuple[int, int]) -> np.ndarray:
    """[m, degree] column indices whose product is each monomial (index d: the constant 1)."""
    powers = np.frombuffer(key, np.int64).reshape(shape)
    degree = int(powers.sum(axis=1).max())
    rows = [sum(([k] * int(p) for k, p in enumerate(row)), []) for row in powers]
    return np.array([r + [shape[1]] * (degree - len(r)) for r in rows], np.int64).reshape(shape[0], degree)


def monomial_powers(dim: int, degree: int) -> np.ndarray:
    """Every exponent vector of ``dim`` variables of total degree 1..``degree`` (the constant is the intercept)."""
    rows = [p for p in itertools.product(range(degree + 1), repeat=dim) if 0 < sum(p) <= degree]
    return np.array(sorted(rows, key=lambda p: (sum(p), [-v for v in p])), np.int64)


@dataclass(frozen=True)
class PlattSvm:
    """A linear SVM on monomials of the standardised indicators: f = monomials((x - mean) / scale) . weight +
    intercept, and P(related) = 1 / (1 + exp(platt_a f + platt_b)) (Platt 1999, as libsvm's
    ``sigmoid_predict``), clamped to [1e-7, 1 - 1e-7] as libsvm's ``svm_predict_probability`` does."""

    mean: np.ndarray
    scale: np.ndarray
    powers: np.ndarray
    weight: np.ndarray
    intercept: float
    platt_a: float
    platt_b: float

    def decision(self, x: np.ndarray) -> np.ndarray:
        return monomials((x - self.mean) / self.scale, self.powers) @ self.weight + self.intercept

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        p = 0.5 * (1.0 - np.tanh(0.5 * (self.platt_a * self.decision(x) + self.platt_b)))  # logistic, no overflow
        return np.clip(p, 1e-7, 1 - 1e-7)


# SPENCER's released default (tracking/groups/spencer_social_relations/models/groups_probabilistic_small.model, the
# `svm_filename` default of spatial_relations.cpp): a linear nu-SVC on the raw indicators, no scaling. rho, probA and
# probB as the file prints them; the weights computed from its 2,501 support vectors (sum of coefficient x vector).
SPENCER = PlattSvm(mean=np.zeros(3), scale=np.ones(3), powers=np.eye(3, dtype=np.int64),
                   weight=np.array([-1.875462017868918, -0.5596792850946883, -0.9133788466043510]),
                   intercept=3.03765, platt_a=-1.55322, platt_b=-0.0123641)


@dataclass(frozen=True)
class RelationTable:
    """A classifier tabulated on a regular grid over the gates' box (``tabulate``): P(related) at the grid point
    nearest each row. A few array operations whatever the classifier: a random forest's own walk takes a numpy step
    per level of its trees, ten times the cost at a crowd's size."""

    lower: np.ndarray  # the indicators at grid point (0, 0, 0)
    step: np.ndarray  # the grid's spacing in each indicator
    values: np.ndarray  # [distance, speed difference, heading difference] P(related)

    @property
    def upper(self) -> np.ndarray:
        return self.lower + self.step * (np.array(self.values.shape) - 1)

    def predict_proba(self, x: np.ndarray) -> np.ndarray:
        k = np.rint((x - self.lower) / self.step).astype(np.int64)
        k = np.minimum(np.maximum(k, 0), self._last)  # np.clip costs as much as the rest
        return self._flat[k @ self._strides].astype(float)

    @functools.cached_property
    def _last(self) -> np.ndarray:
        return np.array(self.values.shape) - 1

    @functools.cached_property
    def _flat(self) -> np.ndarray:
        return np.ascontiguousarray(self.values).ravel()

    @functools.cached_property
    def _strides(self) -> np.ndarray:
        """The flat index's step per grid step of each indicator."""
        return np.cumprod((self.values.shape[1:] + (1,))[::-1])[::-1]


def tabulate(classifier, upper: np.ndarray, step: np.ndarray, samples: int = 3) -> RelationTable:
    """``classifier``'s P(related) on the grid of spacing ``step`` from 0 to ``upper`` (each a whole number of
    steps): at each point the mean over the ``samples``^3 points spread evenly across its cell, as float32. The mean
    over the cell, not the value at its centre: a forest's boundary has structure finer than the grid (30 trees'
    thresholds), which sampling at points alone aliases into isolated cells, so relations near 0.5 flicker."""
    counts = np.rint(np.asarray(upper) / step).astype(int) + 1
    axes = [np.arange(c) * h for c, h in zip(counts, step)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(counts))
    offsets = (np.arange(samples) - (samples - 1) / 2) / samples
    total = np.zeros(len(grid))
    for shift in itertools.product(offsets, repeat=len(counts)):
        total += classifier.predict_proba(grid + np.array(shift) * step)
    values = (total / samples ** len(counts)).astype(np.float32).reshape(counts)
    return RelationTable(np.zeros(len(counts)), np.asarray(step, float), values)


def save_model(path: Path, classifier: PlattSvm | RelationTable, info: dict) -> None:
    """A trained classifier as an .npz of plain arrays and a JSON header (no pickle)."""
    kind = "svm" if isinstance(classifier, PlattSvm) else "table"
    arrays = {name: np.asarray(getattr(classifier, name)) for name in classifier.__dataclass_fields__}
    header = {"format": MODEL_FORMAT, "kind": kind, "indicators": list(INDICATORS), "info": info}
    np.savez_compressed(path, header=np.array(json.dumps(header)), **arrays)


def load_model(model: str | Path) -> PlattSvm | RelationTable:
    """``spencer``, a shipped model by name (``svm``, ``forest``), or the path of one ``save_model`` wrote."""
    if model == "spencer":
        return SPENCER
    path = MODELS_DIR / MODEL_FILES[model] if model in MODEL_FILES else Path(model)
    try:
        with np.load(path) as data:
            header = json.loads(str(data["header"]))
            arrays = {name: data[name] for name in data.files if name != "header"}
    except (OSError, ValueError, KeyError) as e:
        raise ValueError(f"model: {path} is not a relation model ({e}); expected spencer, {', '.join(MODEL_FILES)} "
                         "or an .npz written by `crowdsim experiment train-relations`") from None
    if header.get("format") != MODEL_FORMAT:
        raise ValueError(f"model: {path} has format {header.get('format')!r}; expected {MODEL_FORMAT}")
    if header["kind"] == "svm":
        return PlattSvm(**{k: (float(v) if v.ndim == 0 else v) for k, v in arrays.items()})
    return RelationTable(**arrays)


class RelationEstimator:
    """Every pair of tracks and its strength: the gates, then the classifier on the pairs they pass."""

    def __init__(self, model: str = "spencer", max_distance: float = 3.0, max_speed_difference: float = 1.0,
                 max_heading_difference: float = np.pi / 4, min_speed: float = 0.1):
        self.classifier = load_model(model)
        self.limits = np.array([max_distance, max_speed_difference, max_heading_difference])
        if isinstance(self.classifier, RelationTable) and (self.limits > self.classifier.upper + 1e-9).any():
            raise ValueError(f"model: {model} is tabulated up to the gates {self.classifier.upper.round(4).tolist()} "
                             f"({', '.join(INDICATORS)}); expected gates within them, not "
                             f"{self.limits.round(4).tolist()}")
        self.min_speed = min_speed

    def strengths(self, position: np.ndarray, velocity: np.ndarray):
        """(i, j, strength) of every pair i < j of tracks by row: the classifier on the pairs inside the gates,
        found by one pass over the pairs (``_gated``)."""
        i, j = pairs(len(position))
        speed, heading = _motion(velocity, self.min_speed)
        at, features = _gated(np.ascontiguousarray(position, np.float64), speed, heading,
                              (self.limits[0] + 1e-9) ** 2, self.limits)
        strength = np.full(len(i), GATED_STRENGTH)
        if len(at):
            strength[at] = self.classifier.predict_proba(features)
        return i, j, strength


class LongTermRelations:
    """SPENCER's long-term relations (``long_term_relations.py``): each pair's strength moves towards the current
    one at most ``growth`` per second up and ``decay`` per second down, ``fast_decay`` when the two are farther than
    ``max_distance``; a new pair starts at 0, and a pair goes when either track does. The defaults are the rates its
    callback uses (0.5 in 3.5 s, 40 s, 5 s; its launch file's values never reach the callback)."""

    def __init__(self, growth: float = 0.5 / 3.5, decay: float = 0.5 / 40, fast_decay: float = 0.5 / 5,
                 max_distance: float = 4.0):
        self.growth, self.decay, self.fast_decay, self.max_distance = growth, decay, fast_decay, max_distance
        self.reset()

    def reset(self) -> None:
        self.keys = np.zeros(0, np.int64)  # a * 2**32 + b of each remembered pair (a < b track ids), sorted
        self.values = np.zeros(0)
        self.stamp: float | None = None

    def smooth(self, stamp: float, a: np.ndarray, b: np.ndarray, strength: np.ndarray,
               distance: np.ndarray) -> np.ndarray:
        """The smoothed strengths of pairs (a, b) of track ids at ``stamp``; pairs not given are forgotten."""
        dt = 0.0 if self.stamp is None else stamp - self.stamp
        self.stamp = stamp
        key = np.minimum(a, b) * (1 << 32) + np.maximum(a, b)
        rows = np.searchsorted(self.keys, key)
        known = rows < len(self.keys)
        known[known] = self.keys[rows[known]] == key[known]
        held = np.where(known, self.values[np.minimum(rows, max(len(self.keys) - 1, 0))] if len(self.keys) else 0.0,
                        0.0)
        far = distance > self.max_distance
        target = np.where(far, 0.0, strength)
        down = np.where(far, self.fast_decay, self.decay) * dt
        out = np.where(target >= held, np.minimum(held + self.growth * dt, target), np.maximum(held - down, target))
        order = np.argsort(key)
        self.keys, self.values = key[order], out[order]
        return out
