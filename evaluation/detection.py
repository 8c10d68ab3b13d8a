"""Person-detection scores as the 2D-laser detector papers report them: the precision-recall curve over all frames at
an association radius, its average precision (AP), peak F1 and equal error rate (EER).

Why: detectors (pipeline/detectors) are compared with the numbers of

    L. Beyer, A. Hermans, T. Linder, K. O. Arras and B. Leibe, "Deep Person Detection in 2D Range Data" (DROW),
    IEEE Robotics and Automation Letters 3(3):2726-2733, 2018, and
    D. Jia, A. Hermans and B. Leibe, "DR-SPAAM: A Spatial-Attention and Auto-regressive Model for Person Detection
    in 2D Range Data", IROS 2020,

which report AP, peak F1 and EER at association radii of 0.3 m and 0.5 m (AP_0.3, AP_0.5). The definitions below
follow their evaluation code: ``prec_rec_2d``, ``peakf1`` and ``eer`` in github.com/VisualComputingInstitute/DROW,
v2/utils/__init__.py, carried over as ``_prec_rec_2d``, ``_eval_prec_rec``, ``_peakf1`` and ``_eer`` into
github.com/VisualComputingInstitute/2D_lidar_person_detection, dr_spaam/dr_spaam/utils/precision_recall.py (called
from ``get_precision_recall`` there). This module is our own code.

Matching (``_prec_rec_2d``). The detections of all frames are admitted one at a time in descending confidence.
After each admission the frame's admitted detections and its ground truth are matched by a maximum matching
(``linear_sum_assignment`` on a 0/1 "farther than the radius" cost) in which a detection and a person may pair when
their distance is <= the radius (the bound counts as inside). The true positives at that point are the matched
pairs summed over frames: one person is matched by at most one detection and one detection matches at most one
person, and a detection's partner may change as lower-confidence detections come in. So it is neither greedy
nearest-neighbour nor a matching fixed at one threshold.

We get the same counts with one assignment per frame instead of one per detection. The size of a maximum matching
grows by 0 or 1 when a detection is admitted; call a detection a true positive when it grows. The detections that
can be matched together form a (transversal) matroid, so the true positives are the greedy basis in confidence
order, which is also the unique maximum-weight matching when every detection weighs a distinct positive amount
decreasing with confidence (here its rank). ``linear_sum_assignment`` with those weights gives it; the count of
true positives among the detections admitted down to any threshold is then the size of DROW's maximum matching
there. Per detection we keep only its confidence and that flag (one flag per radius) plus the total ground-truth
count, so a dataset streams through in memory proportional to its number of detections.

Curve (``_prec_rec_2d``). At threshold t, with k(t) detections of confidence >= t over all frames, TP(t) of them
true positives and N ground-truth persons over all frames, precision = TP/k and recall = TP/N. A frame with
detections and no ground truth adds false positives; a frame with neither adds nothing.

- AP (``_eval_prec_rec``: ``sklearn.metrics.auc(recall, precision)``): the trapezoid rule over the curve's points,
  without the interpolated precision envelope of PASCAL VOC.
- Peak F1 (``_peakf1``): the largest 2PR/(P + R) over the curve's points (0 where P + R = 0).
- EER (``_eer``): of the points with recall > 0, the one where |P - R| is smallest (the highest threshold on a tie),
  reported as (P + R)/2. The name is kept from the papers; it is a score, higher is better.

Where we differ from DR-SPAAM/DROW:

- Ties. They make one point per detection, so detections of equal confidence give points that no threshold
  reaches, in an order left to the sort. We make one point per distinct confidence (the detections >= t are all
  admitted together). With distinct confidences, as a network's outputs nearly always are, the curves are equal.
- AP start. ``auc`` integrates from the first point (r_1, p_1), leaving out recall [0, r_1]; we integrate from
  (0, p_1), adding r_1 * p_1 <= 1/N. A perfect detector then scores AP = 1 rather than 1 - 1/N; on their test sets
  (N in the thousands) the difference is below the digits they print.
- Degenerate inputs. They fail with no detection or no true positive; we give an empty curve (no detection) and
  0 for the scores with NaN thresholds. With no ground truth at all recall is undefined: ``ValueError``.
- They score only ground truth with more than 5 laser points (at least 6) within 0.4 m (``occluded`` flag); which
  persons count is the caller's choice here: pass only those (crowdsim/datasets/detection_eval.py).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from evaluation.tables import grown
from pipeline.lsap import linear_sum_assignment

__all__ = ["DetectionAccumulator", "DetectionScores", "detection_scores", "frame_true_positives", "pr_scores",
           "score_detections"]

RADII = (0.3, 0.5)  # the association radii (m) DR-SPAAM reports


@dataclass(frozen=True)
class DetectionScores:
    """The precision-recall curve at one association radius and the scores taken from it.

    ``precision``, ``recall`` and ``thresholds`` have one entry per distinct detection confidence, thresholds
    descending (recall ascending); entry i counts the detections with confidence >= thresholds[i]."""

    radius: float
    precision: np.ndarray
    recall: np.ndarray
    thresholds: np.ndarray
    ap: float
    peak_f1: float
    peak_f1_threshold: float  # admit detections >= this to get peak_f1 (NaN without a curve)
    eer: float
    eer_threshold: float  # the threshold of the EER point (NaN when no detection is a true positive)
    n_gt: int
    n_detections: int


def _points(a, name: str) -> np.ndarray:
    """``a`` as a finite float [n, 2] array; an empty list or array is [0, 2]."""
    a = np.asarray(a, dtype=float)
    if a.size == 0:
        a = a.reshape(0, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"{name} must have shape [n, 2], got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite")
    return a


def _radii(radii) -> tuple[float, ...]:
    out = tuple(float(r) for r in np.atleast_1d(np.asarray(radii, dtype=float)))
    if not out or not all(np.isfinite(r) and r > 0 for r in out):
        raise ValueError(f"association radii must be positive and finite, got {radii!r}")
    if len(set(out)) != len(out):
        raise ValueError(f"association radii must be distinct, got {radii!r}")
    return out


def frame_true_positives(det_conf: np.ndarray, within: np.ndarray) -> np.ndarray:
    """Which detections of one frame are true positives (bool [n]) given ``within`` [n, m], True where detection i
    may match person j (distance <= radius).

    Detection i is a true positive when admitting it, after every detection of higher confidence (ties in index
    order), makes the frame's maximum matching one larger: the counts DROW's per-threshold matching gives (see the
    module docstring). Solved as one maximum-weight assignment with weights decreasing in confidence."""
    n = len(det_conf)
    tp = np.zeros(n, dtype=bool)
    rows = np.flatnonzero(within.any(axis=1))  # detections with someone in reach
    if not len(rows):
        return tp
    sub = within[rows]
    sub = sub[:, sub.any(axis=0)]
    if sub.sum(axis=0).max() == 1 and sub.sum(axis=1).max() == 1:  # isolated pairs: nothing to choose
        tp[rows] = True
        return tp
    order = np.argsort(-det_conf[rows], kind="stable")
    weight = np.empty(len(rows))
    weight[order] = np.arange(len(rows), 0, -1)  # distinct, positive, higher for higher confidence
    r, c = linear_sum_assignment(np.where(sub, -weight[:, None], 0.0))
    tp[rows[r[sub[r, c]]]] = True  # pairs out of reach cost 0 and are only padding
    return tp


def pr_scores(det_conf: np.ndarray, is_tp: np.ndarray, n_gt: int, radius: float = float("nan")) -> DetectionScores:
    """The curve and its scores from every detection's confidence and true-positive flag and the ground-truth count
    (the flags as ``frame_true_positives`` gives them, frame by frame). Raises ValueError when ``n_gt`` is 0."""
    det_conf = np.asarray(det_conf, dtype=float).ravel()
    is_tp = np.asarray(is_tp, dtype=bool).ravel()
    if len(det_conf) != len(is_tp):
        raise ValueError("one true-positive flag per detection is needed")
    if n_gt <= 0:
        raise ValueError("no ground truth in any frame: recall, and so AP, peak F1 and EER, are undefined")
    order = np.argsort(-det_conf, kind="stable")
    conf = det_conf[order]
    tp_cum = np.cumsum(is_tp[order])
    last = np.r_[conf[1:] != conf[:-1], True] if len(conf) else np.zeros(0, dtype=bool)  # end of each tie block
    admitted = np.flatnonzero(last) + 1
    tp = tp_cum[last]
    precision = tp / admitted
    recall = tp / n_gt
    thresholds = conf[last]
    if not len(thresholds):
        ap = peak_f1 = eer = 0.0
        f1_thr = eer_thr = float("nan")
    else:
        ap = float(np.trapezoid(np.r_[precision[0], precision], np.r_[0.0, recall]))
        denom = precision + recall
        f1 = np.divide(2 * precision * recall, denom, out=np.zeros_like(denom), where=denom > 0)
        i = int(np.argmax(f1))
        peak_f1, f1_thr = float(f1[i]), float(thresholds[i])
        hit = np.flatnonzero(recall > 0)
        if len(hit):
            j = hit[int(np.argmin(np.abs(precision[hit] - recall[hit])))]
            eer, eer_thr = float((precision[j] + recall[j]) / 2), float(thresholds[j])
        else:
            eer, eer_thr = 0.0, float("nan")
    return DetectionScores(float(radius), precision, recall, thresholds, ap, peak_f1, f1_thr, eer, eer_thr,
                           int(n_gt), len(det_conf))


class DetectionAccumulator:
    """Scores detections frame by frame at several association radii at once, keeping per detection only its
    confidence and one true-positive flag per radius (so a simulation loop or a long dataset can feed it)."""

    def __init__(self, radii: Sequence[float] | float = RADII):
        self.radii = _radii(radii)
        self.n_gt = 0
        self.n_detections = 0
        self._conf = np.zeros(0)
        self._tp = np.zeros((0, len(self.radii)), dtype=bool)

    def add(self, det_xy, det_conf, gt_xy) -> None:
        """One frame: detection positions [n, 2] (m), their confidences [n], ground-truth positions [m, 2] (m), all
        in one frame of reference. Either side may be empty."""
        det_xy, gt_xy = _points(det_xy, "detection positions"), _points(gt_xy, "ground-truth positions")
        det_conf = np.asarray(det_conf, dtype=float).ravel()
        if len(det_conf) != len(det_xy):
            raise ValueError(f"{len(det_xy)} detections but {len(det_conf)} confidences")
        if not np.isfinite(det_conf).all():
            raise ValueError("detection confidences must be finite")
        n = len(det_xy)
        self.n_gt += len(gt_xy)
        if not n:
            return
        flags = np.zeros((n, len(self.radii)), dtype=bool)
        if len(gt_xy):
            dist = np.hypot(det_xy[:, None, 0] - gt_xy[None, :, 0], det_xy[:, None, 1] - gt_xy[None, :, 1])
            for k, r in enumerate(self.radii):
                flags[:, k] = frame_true_positives(det_conf, dist <= r)
        end = self.n_detections + n
        self._conf = grown(self._conf, end)
        self._tp = grown(self._tp, end)
        self._conf[self.n_detections:end] = det_conf
        self._tp[self.n_detections:end] = flags
        self.n_detections = end

    def scores(self) -> dict[float, DetectionScores]:
        """The curve and scores per radius over every frame added so far. ValueError without any ground truth."""
        conf = self._conf[:self.n_detections]
        return {r: pr_scores(conf, self._tp[:self.n_detections, k], self.n_gt, r) for k, r in enumerate(self.radii)}


def detection_scores(frames: Iterable, radii: Sequence[float] = RADII) -> dict[float, DetectionScores]:
    """AP, peak F1, EER and the curve at each radius, keyed by radius, in one pass over ``frames``: an iterable (a
    generator is fine) of (detection positions [n, 2], detection confidences [n], ground-truth positions [m, 2]).
    ValueError when no frame has ground truth."""
    acc = DetectionAccumulator(radii)
    for det_xy, det_conf, gt_xy in frames:
        acc.add(det_xy, det_conf, gt_xy)
    return acc.scores()


def score_detections(frames: Iterable, radius: float = 0.5) -> DetectionScores:
    """AP, peak F1, EER and the curve at one association radius (m); ``frames`` as for ``detection_scores``."""
    return detection_scores(frames, (radius,))[float(radius)]
