"""Evaluation of people tracking against the simulator's ground truth."""

from evaluation.clearmot import ClearMot, FrameResult, evaluate
from evaluation.sequence import Sequence

__all__ = ["ClearMot", "FrameResult", "Sequence", "evaluate"]
