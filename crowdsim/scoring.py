"""CLEAR-MOT of the loop's Frames as they come: the scorer, not the loop, scores each cycle."""

from __future__ import annotations

from evaluation.clearmot import ClearMot, ClearMotResult, FrameResult


class CycleScorer:
    """Scores each Frame's tracks against its ground truth (the persons tagged out of range or unseen ignored)."""

    def __init__(self, threshold: float):
        self.clearmot = ClearMot(threshold)

    def __call__(self, frame) -> FrameResult:
        truth, tracks = frame.groundtruth, frame.tracks
        return self.clearmot.update(truth.track_id, truth.position, tracks.track_id, tracks.position,
                                    frame.gt_tags.ignore)

    def result(self) -> ClearMotResult:
        return self.clearmot.result()


def score_cycles(frames, threshold: float) -> ClearMotResult:
    """The CLEAR-MOT of ``frames`` (the Frames of one run, in order)."""
    scorer = CycleScorer(threshold)
    for frame in frames:
        scorer(frame)
    return scorer.result()
