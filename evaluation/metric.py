"""What every sequence metric here shares (CLEAR-MOT, HOTA, OSPA): it is shown the sequence as chunks of whole frames
in frame order, ``add(gt, tracks)`` (``Sequence`` pairs, as evaluation/stream.py gives them), then gives one result
object, ``result()``; the result becomes a dict (``as_dict``) only where JSON is written.

A metric with a global step between two looks at the data (HOTA's alignment, OSPA-T's labels) has ``passes = 2``:
the chunks are shown once, ``next_pass()``, and shown again. ``accumulate`` does that for any set of metrics.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable, Protocol

from .sequence import Sequence


@dataclasses.dataclass(frozen=True)
class Result:
    """A metric's figures; undefined ones are None (NaN is not JSON)."""

    def as_dict(self) -> dict:
        """The figures as plain JSON values, in the order of the fields."""
        return dataclasses.asdict(self)


class Metric(Protocol):
    """A sequence metric; one with ``passes = 2`` also has ``next_pass()``, its global step between the passes."""

    passes: int  # how many times the chunks are shown: 1, or 2 around a global step

    def add(self, gt: Sequence, tracks: Sequence):
        """Accumulate a chunk of whole frames (later than any shown before in this pass)."""

    def result(self) -> Result:
        """The figures over every chunk shown."""


def accumulate(metrics: list[Metric], frames: Iterable[tuple[Sequence, Sequence]]) -> None:
    """Show each of ``metrics`` the chunks of ``frames`` (re-iterable) as many times as it needs."""
    for k in range(max((m.passes for m in metrics), default=0)):
        if k:
            for m in metrics:
                if m.passes > k:
                    m.next_pass()
        for gt, tracks in frames:
            for m in metrics:
                if m.passes > k:
                    m.add(gt, tracks)
