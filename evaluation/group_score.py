"""The groups object of metrics.json, scored from a run's files: groundtruth.csv (with its ``group`` column),
tracks.csv, relations.csv and groups.csv, read a chunk at a time and met frame by frame, so the run and
``crowdsim evaluate`` give the same figures from the same files, in constant memory.

Tracks are mapped to persons by CLEAR-MOT's matching at the run's threshold, the tracking scores' own: a run and
``crowdsim evaluate`` score both from one reading of the ground truth and the tracks (``GroupScore`` fed by
``score.score_tracking``). The metrics are evaluation/groups.py's.
"""

from __future__ import annotations

import numpy as np

from .clearmot import ClearMot
from .columns import GROUPS, RELATIONS
from .groups import GroupFrame, GroupMetrics
from .io import EvaluationInputError, table_chunks
from .score import pct
from .sequence import Sequence
from .stream import CsvPair

RELATIONS_COLUMNS = RELATIONS.pick("frame", "track_a", "track_b", "strength")
GROUPS_COLUMNS = GROUPS.pick("frame", "group", "id")


def frame_rows(path, required: tuple[str, ...], read: tuple[str, ...] = ()):
    """(frame, columns) of each frame of a CSV sorted by frame, in order, a chunk of rows at a time (``required``
    and ``read`` as ``table_chunks`` checks them)."""
    held = None
    for table in table_chunks(path, required, read):
        if held is not None:
            table = {name: np.concatenate([held[name], table[name]]) for name in table}
        frame = table["frame"]
        if (np.diff(frame) < 0).any():
            raise EvaluationInputError(f"{path}: rows not sorted by frame; expected them as a run writes them")
        cut = int(np.searchsorted(frame, frame[-1])) if len(frame) else 0
        starts = np.flatnonzero(np.diff(frame[:cut], prepend=np.nan) != 0) if cut else np.zeros(0, np.int64)
        for a, b in zip(starts, np.append(starts[1:], cut)):
            yield int(frame[a]), {name: column[a:b] for name, column in table.items()}
        held = {name: column[cut:] for name, column in table.items()}
    if held is not None and len(held["frame"]):
        yield int(held["frame"][0]), held


class GroupScore:
    """The group metrics of relations.csv and groups.csv, given the ground truth a chunk at a time with CLEAR-MOT's
    matching of its frames (``add``, the ``matched`` of ``score.counted_chunks``: the tracking scores' reading and
    matching serve both); a frame of the two files that neither the ground truth nor the tracks have is scored with
    no persons. ``result`` once every chunk is given."""

    def __init__(self, relations_path, groups_path):
        self._streams = (frame_rows(relations_path, RELATIONS_COLUMNS), frame_rows(groups_path, GROUPS_COLUMNS))
        self._heads = [next(stream, None) for stream in self._streams]  # each file's next (frame, columns)
        self.metrics = GroupMetrics()

    def add(self, gt: Sequence, results) -> None:
        """A chunk of ground truth (with its ``group`` column) and its frames' (frame, ClearMot FrameResult)."""
        if gt.group is None:
            raise ValueError("GroupScore needs the ground truth's group column (CsvPair(..., groups=True))")
        bounds = gt.bounds(np.array([frame for frame, _ in results], np.int64))
        for k, (frame, result) in enumerate(results):
            self._before(frame)
            rows = slice(bounds[k], bounds[k + 1])
            counted = ~gt.ignore[rows]
            self._update(frame, gt.id[rows][counted], gt.group[rows][counted], gt.position[rows][counted], result)

    def result(self) -> dict:
        self._before(None)
        return self.metrics.summary()

    def _before(self, frame: int | None) -> None:
        """The files' frames before ``frame`` (all that are left: None), scored without persons."""
        while True:
            first = min((head[0] for head in self._heads if head is not None), default=None)
            if first is None or (frame is not None and first >= frame):
                return
            self._update(first, _NO_IDS, _NO_IDS, np.zeros((0, 2)), None)

    def _update(self, frame: int, gt_id, gt_group, gt_position, result) -> None:
        relations, groups = self._take(frame)
        self.metrics.update(GroupFrame(
            gt_id=gt_id, gt_group=gt_group, gt_position=gt_position,
            matched_gt=_NO_IDS if result is None else result.matched_gt_ids,
            matched_track=_NO_IDS if result is None else result.matched_hyp_ids,
            excused_track=_NO_IDS if result is None else result.excused_hyp_ids,
            relation_a=_ints(relations, "track_a"), relation_b=_ints(relations, "track_b"),
            relation_strength=np.zeros(0) if relations is None else relations["strength"],
            group_id=_ints(groups, "group"), group_track=_ints(groups, "id")))

    def _take(self, frame: int) -> list:
        """Each file's columns of ``frame`` (None where it has no row there), the files read on past it."""
        taken = []
        for k, head in enumerate(self._heads):
            if head is not None and head[0] == frame:
                taken.append(head[1])
                self._heads[k] = next(self._streams[k], None)
            else:
                taken.append(None)
        return taken


_NO_IDS = np.zeros(0, np.int64)


def _ints(rows, name) -> np.ndarray:
    return _NO_IDS if rows is None else rows[name].astype(np.int64)


def score_groups(gt_path, tracks_path, relations_path, groups_path, threshold: float = 1.0,
                 occlusion: bool = True, visible_column: str | None = None, max_range: float | None = None) -> dict:
    """The group metrics of a run's four files (evaluation/groups.py ``GroupMetrics.summary``); the ground truth's
    ignored rows as ``io.Ignored`` says. (With the tracking scores too: ``score_tracking(CsvPair(..., groups=True),
    threshold, GroupScore(...).add)``, one reading and matching for both.)"""
    scores, cm = GroupScore(relations_path, groups_path), ClearMot(threshold)
    for gt, tracks in CsvPair(gt_path, tracks_path, occlusion, visible_column, max_range, groups=True):
        scores.add(gt, list(cm.scored_frames(gt, tracks)))
    return scores.result()


def groups_table(groups: dict, extra: dict[str, str] | None = None) -> str:
    """A Markdown table of the group figures: Setti's F1 at T = 2/3 and 1, G-MITRE's F1, the relations' pairwise F1
    and AUC, group MOTA and group ID switches, the true groups counted, and any ``extra`` columns."""
    cells = {"group F1 (T=2/3)": pct(groups["t_2_3"]["f1"]), "group F1 (T=1)": pct(groups["t_1"]["f1"]),
             "G-MITRE F1": pct(groups["gmitre"]["f1"]), "relation F1": pct(groups["pairwise"]["f1"]),
             "relation AUC": "n/a" if groups["pairwise"]["auc"] is None else f"{groups['pairwise']['auc']:.3f}",
             "group MOTA": pct(groups["tracking"]["mota"]), "group IDS": str(groups["tracking"]["id_switches"]),
             "true groups": str(groups["true_groups"]), **(extra or {})}
    return "\n".join(["| " + " | ".join(cells) + " |", "|" + "---|" * len(cells),
                      "| " + " | ".join(cells.values()) + " |"])
