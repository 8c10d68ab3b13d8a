"""Scoring a detector's output in a dataset against the dataset's ground truth, as DR-SPAAM scores its detectors: AP,
peak F1 and EER at association radii of 0.3 m and 0.5 m (evaluation/detection.py says how).

Who counts as ground truth. DR-SPAAM scores only the persons its laser saw. On JRDB an annotation is valid when more
than ``min_close_points=5`` scan points lie within 0.4 m of its centre (``_get_regression_target`` in
dr_spaam/dr_spaam/dataset/jrdb_dataset.py of github.com/VisualComputingInstitute/2D_lidar_person_detection); the
others are written out as ``occluded`` and dropped before matching (``gts_xy = gts_xy[gts_occluded == 0]`` in
``evaluate_drow``, dr_spaam/dr_spaam/utils/precision_recall.py). DROW's annotations are all valid
(dr_spaam/dr_spaam/dataset/drow_dataset.py): they were drawn by hand on the scans. We know which beam hit whom, so
the rule is exact here: a person counts in a frame when at least ``min_beams`` beams of the detector's laser hit
them (default 6, DR-SPAAM's "more than 5"), or for the fused detections, of any one laser: the persons table's
``<laser>.beams``, not points near the centre, which may be a neighbour's or a wall's. As in DR-SPAAM, a person who
does not count is dropped, not ignored: a detection of them is a false positive.

Frames. A laser's detector is scored on the frames its laser scanned (sensors.h5 lasers/<name>/frame), the fused
detections on every frame. Positions are compared in the world frame: the detections' world_x, world_y (brought
there with the true world_T_odom) against the persons' x, y. The dataset streams episode by episode and frame by
frame; what is kept is DetectionAccumulator's confidence and flags per detection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evaluation.detection import RADII, DetectionAccumulator, DetectionScores

from .layout import FUSED, DatasetError
from .reader import Dataset, Episode

MIN_BEAMS = 6  # DR-SPAAM's JRDB rule: more than 5 points of the scan on the person


@dataclass(frozen=True)
class DetectorEvaluation:
    """One detector scored on one split: the counts, and per association radius the curve and its scores."""

    folder: str
    detector: str
    split: str
    min_beams: int
    episodes: int
    frames: int
    n_gt: int
    n_detections: int
    scores: dict[float, DetectionScores]

    def as_dict(self) -> dict:
        """The counts and per radius AP, peak F1, EER and their thresholds (NaN as None, for JSON), not the curves."""
        def scalars(s: DetectionScores) -> dict:
            values = {k: getattr(s, k) for k in ("ap", "peak_f1", "peak_f1_threshold", "eer", "eer_threshold")}
            return {k: None if math.isnan(v) else v for k, v in values.items()}

        counts = ("folder", "detector", "split", "min_beams", "episodes", "frames", "n_gt", "n_detections")
        radii = {f"{r:g}": scalars(s) for r, s in self.scores.items()}
        return {**{k: getattr(self, k) for k in counts}, "radii": radii}


def evaluate_detector(folder: Path, detector: str = FUSED, split: str = "test", radii: tuple[float, ...] = RADII,
                      min_beams: int = MIN_BEAMS) -> DetectorEvaluation:
    """Score ``detector``'s rows of detections.parquet (a laser's name, or "fusion") over the episodes of ``split``
    against the persons hit by at least ``min_beams`` beams (module docstring). DatasetError for a folder that is no
    dataset, an unknown split or detector, an empty split, or no person to score against."""
    if min_beams < 1:
        raise DatasetError(f"--min-beams: expected at least 1 beam, got {min_beams}")
    episodes = Dataset(folder).episodes(split)
    if not episodes:
        raise DatasetError(f"{folder}: split {split!r} holds no episode; expected a split with episodes")
    scoreable = set().union(*(ep.detectors() & {FUSED, *ep.lasers} for ep in episodes))
    if detector not in scoreable:
        raise DatasetError(f"{folder}: no detector {detector!r} in split {split!r}; expected one of "
                           f"{', '.join(sorted(scoreable)) or '(none: the split holds no laser or fused detection)'}")
    episodes = [ep for ep in episodes if detector in (FUSED, *ep.lasers)]  # episode k runs scenario k mod S
    acc, frames = DetectionAccumulator(radii), 0
    for ep in episodes:
        frames += _add_episode(acc, ep, detector, min_beams)
        ep.close()
    if acc.n_gt == 0:
        who = "any laser" if detector == FUSED else detector
        raise DatasetError(f"{folder}: no person in split {split!r} is hit by {min_beams} or more beams of {who}; "
                           "expected ground truth to score against (try a smaller --min-beams)")
    return DetectorEvaluation(str(folder), detector, split, min_beams, len(episodes), frames, acc.n_gt,
                              acc.n_detections, acc.scores())


def _add_episode(acc: DetectionAccumulator, ep: Episode, detector: str, min_beams: int) -> int:
    """Add the episode's frames to ``acc``; the number of frames scored."""
    beams = [f"{laser}.beams" for laser in (ep.lasers if detector == FUSED else [detector])]
    scored = np.ones(ep.frames, bool)  # the fused detections: every frame; a laser's: the frames it scanned
    if detector != FUSED:
        scored = np.isin(np.arange(ep.frames), ep.sensor(detector)["frame"][()])
    persons = ep.iter_frames("persons", ["x", "y", *beams])
    detections = ep.iter_frames("detections", ["detector", "confidence", "world_x", "world_y"])
    for (frame, p), (_, d) in zip(persons, detections, strict=True):
        if not scored[frame]:
            continue
        seen = np.max([p[c] for c in beams], axis=0) >= min_beams
        mine = d["detector"] == detector
        acc.add(np.column_stack([d["world_x"][mine], d["world_y"][mine]]), d["confidence"][mine],
                np.column_stack([p["x"][seen], p["y"][seen]]))
    return int(scored.sum())


def detection_table(results: list[DetectorEvaluation]) -> str:
    """One row per evaluation: detector, split, episodes, frames, GT, detections, then AP, peak F1 and EER in % at
    each radius; a last line says who counted as ground truth."""
    radii = list(results[0].scores)
    head = ["detector", "split", "episodes", "frames", "GT", "detections",
            *(f"{name}@{r:g}" for r in radii for name in ("AP", "peakF1", "EER"))]
    rows = [[e.detector, e.split, str(e.episodes), str(e.frames), str(e.n_gt), str(e.n_detections),
             *(f"{100 * getattr(e.scores[r], k):.1f}" for r in radii for k in ("ap", "peak_f1", "eer"))]
            for e in results]
    width = [max(len(row[k]) for row in [head, *rows]) for k in range(len(head))]
    lines = ["  ".join(c.ljust(w) if k < 2 else c.rjust(w) for k, (c, w) in enumerate(zip(row, width)))
             for row in [head, *rows]]
    rules = sorted({e.min_beams for e in results})
    return "\n".join([*lines, f"GT: persons hit by at least {'/'.join(map(str, rules))} beams of the detector's "
                      "laser (fusion: of any laser), as DR-SPAAM; AP, peak F1, EER in % at association radii "
                      f"{', '.join(f'{r:g}' for r in radii)} m"])
