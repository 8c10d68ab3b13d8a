"""Evaluation of people tracking against the simulator's ground truth."""

from evaluation.clearmot import ClearMot, ClearMotResult, FrameResult, evaluate
from evaluation.sequence import Sequence

__all__ = ["ClearMot", "ClearMotResult", "FrameResult", "Sequence", "evaluate"]
