"""Ground truth and tracks as aligned chunks of whole frames, from CSV files or from Sequences in memory.

Why: a run of any length is scored in constant memory, so the metrics see the two sequences a chunk of frames at a
time, both chunks covering the same frames, in frame order; the metrics that need two passes (HOTA's global
alignment, OSPA-T's labels) iterate the source twice, which reads the files twice.
"""

from __future__ import annotations

import numpy as np

from .io import CHUNK_ROWS, sequence_chunks
from .sequence import Sequence, frames_of


def aligned(gt_chunks, track_chunks):
    """Pairs (gt, tracks) of Sequences that cover the same frames, in frame order, from two iterators of chunks of
    whole frames in frame order: a frame is given out once both sides are known to have all its rows."""
    streams = [iter(gt_chunks), iter(track_chunks)]
    buffers: list[Sequence | None] = [None, None]
    done = [False, False]
    while True:
        for k in (0, 1):
            if not done[k] and (buffers[k] is None or not len(buffers[k])):
                chunk = next(streams[k], None)
                if chunk is None:
                    done[k] = True
                else:
                    buffers[k] = chunk if buffers[k] is None else Sequence.join([buffers[k], chunk])
        if all(done) and not any(b is not None and len(b) for b in buffers):
            return
        # frames up to the last one each unfinished side holds are complete on both sides
        bound = min((int(buffers[k].frame[-1]) for k in (0, 1) if not done[k]), default=None)
        parts = []
        for k in (0, 1):
            b = buffers[k]
            if b is None:
                parts.append(_EMPTY)
                continue
            cut = len(b) if bound is None else int(np.searchsorted(b.frame, bound, side="right"))
            parts.append(b.select(np.arange(cut)))
            buffers[k] = b.select(np.arange(cut, len(b)))
        if len(parts[0]) or len(parts[1]):
            yield parts[0], parts[1]


_EMPTY = Sequence(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2)))


class CsvPair:
    """A ground-truth file and a track file (the layout ``crowdsim run`` writes) as aligned chunks, read anew at
    each iteration; with ``groups``, the ground truth's group column too. After an iteration, ``gt_rows``, ``gt_ignored`` and ``first_frame`` (of either file; None when
    both are empty) describe what was read."""

    def __init__(self, gt_path, tracks_path, occlusion: bool = True, visible_column: str | None = None,
                 max_range: float | None = None, chunk_rows: int = CHUNK_ROWS, groups: bool = False):
        self.gt_path, self.tracks_path = gt_path, tracks_path
        self.options = {"occlusion": occlusion, "visible_column": visible_column, "max_range": max_range,
                        "groups": groups}
        self.chunk_rows = chunk_rows
        self.gt_rows = self.gt_ignored = 0
        self.first_frame = None

    def gt_chunks(self):
        return sequence_chunks(self.gt_path, chunk_rows=self.chunk_rows, **self.options)

    def track_chunks(self):
        return sequence_chunks(self.tracks_path, occlusion=False, chunk_rows=self.chunk_rows)

    def __iter__(self):
        self.gt_rows = self.gt_ignored = 0
        self.first_frame = None
        for gt, tracks in aligned(self.gt_chunks(), self.track_chunks()):
            if self.first_frame is None:
                self.first_frame = int(frames_of(gt, tracks)[0])
            self.gt_rows += len(gt)
            self.gt_ignored += int(gt.ignore.sum())
            yield gt, tracks


class SequencePair:
    """Ground truth and tracks held in memory as aligned chunks of ``chunk_frames`` frames each (all frames in one
    chunk when None): the metrics' streaming path on data a caller already has."""

    def __init__(self, gt: Sequence, tracks: Sequence, chunk_frames: int | None = None):
        self.gt, self.tracks, self.chunk_frames = gt, tracks, chunk_frames

    def __iter__(self):
        frames = frames_of(self.gt, self.tracks)
        step = self.chunk_frames or max(len(frames), 1)
        starts = frames[::step]
        gb, tb = self.gt.bounds(starts), self.tracks.bounds(starts)
        for k in range(len(starts)):
            yield self.gt.select(np.arange(gb[k], gb[k + 1])), self.tracks.select(np.arange(tb[k], tb[k + 1]))
