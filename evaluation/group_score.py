"""The groups object of metrics.json, scored from a run's files: groundtruth.csv (with its ``group`` column),
tracks.csv, relations.csv and groups.csv, read a chunk at a time and met frame by frame, so the run and
``crowdsim evaluate`` give the same figures from the same files, in constant memory.

Tracks are mapped to persons by CLEAR-MOT's matching at the run's threshold (the same as the tracking scores'), and
the metrics are evaluation/groups.py's.
"""

from __future__ import annotations

import heapq

import numpy as np

from .clearmot import ClearMot
from .columns import GROUNDTRUTH, GROUPS, RELATIONS
from .groups import GroupFrame, GroupMetrics
from .io import REQUIRED, EvaluationInputError, Ignored, table_chunks
from .score import pct
from .sequence import Sequence

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


def merged(*streams):
    """(frame, [each stream's columns of that frame, or None]) over the union of the streams' frames, in order."""
    def tag(k, stream):
        return ((frame, k, rows) for frame, rows in stream)

    tagged = [tag(k, stream) for k, stream in enumerate(streams)]
    current, parts = None, [None] * len(streams)
    for frame, k, rows in heapq.merge(*tagged, key=lambda item: (item[0], item[1])):
        if frame != current and current is not None:
            yield current, parts
            parts = [None] * len(streams)
        current, parts[k] = frame, rows
    if current is not None:
        yield current, parts


def _ints(rows, name) -> np.ndarray:
    return np.zeros(0, np.int64) if rows is None else rows[name].astype(np.int64)


def score_groups(gt_path, tracks_path, relations_path, groups_path, threshold: float = 1.0,
                 occlusion: bool = True, visible_column: str | None = None, max_range: float | None = None) -> dict:
    """The group metrics of a run's four files (evaluation/groups.py ``GroupMetrics.summary``); the ground truth's
    ignored rows as ``io.Ignored`` says."""
    ignored = Ignored(occlusion, visible_column, max_range)
    streams = (frame_rows(gt_path, (*REQUIRED, *GROUNDTRUTH.pick("group")), ignored.columns),
               frame_rows(tracks_path, REQUIRED), frame_rows(relations_path, RELATIONS_COLUMNS),
               frame_rows(groups_path, GROUPS_COLUMNS))
    cm, metrics = ClearMot(threshold), GroupMetrics()
    for frame, (gt, tracks, relations, groups) in merged(*streams):
        gt_ids, track_ids = _ints(gt, "id"), _ints(tracks, "id")
        gt_xy = np.zeros((0, 2)) if gt is None else np.column_stack([gt["x"], gt["y"]])
        track_xy = np.zeros((0, 2)) if tracks is None else np.column_stack([tracks["x"], tracks["y"]])
        ignore = np.zeros(0, bool) if gt is None else ignored(gt, gt_path)
        result = None
        if len(gt_ids) or len(track_ids):
            seq_gt = Sequence.from_rows(np.full(len(gt_ids), frame), gt_ids, gt_xy, ignore=ignore)
            seq_tr = Sequence.from_rows(np.full(len(track_ids), frame), track_ids, track_xy)
            (_, result), = cm.scored_frames(seq_gt, seq_tr)
        counted = ~ignore
        metrics.update(GroupFrame(
            gt_id=gt_ids[counted], gt_group=_ints(gt, "group")[counted], gt_position=gt_xy[counted],
            matched_gt=result.matched_gt_ids if result else np.zeros(0, np.int64),
            matched_track=result.matched_hyp_ids if result else np.zeros(0, np.int64),
            excused_track=result.excused_hyp_ids if result else np.zeros(0, np.int64),
            relation_a=_ints(relations, "track_a"), relation_b=_ints(relations, "track_b"),
            relation_strength=np.zeros(0) if relations is None else relations["strength"],
            group_id=_ints(groups, "group"), group_track=_ints(groups, "id")))
    return metrics.summary()


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
