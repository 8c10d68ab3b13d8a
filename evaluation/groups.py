"""Group metrics: detected groups, pairwise social relations and tracked groups against the true groups, streamed
over tracking cycles.

Why: SPENCER's pipeline goes beyond persons: it scores how strongly pairs of tracks are related (social relations)
and tracks groups of tracks. The testbed scores both against the simulator's true groups with the measures the
group detection literature reports, so that numbers are comparable with published ones.

Input per cycle (``GroupFrame``): the counted persons with their true group (the caller has dropped the ignored
ones: occluded or out of range), CLEAR-MOT's matched (person, track) pairs and the tracks it matched to ignored
persons (clearmot.py, ``FrameResult``), the relations and the tracked groups as member rows.

Tracks to persons: a member track matched to a counted person is that person; one matched to an ignored person
(excused) is dropped from its group, as CLEAR-MOT counts it neither right nor wrong; any other member (a false
positive track) stays a member that is no person, so it makes its group bigger and never helps it match. True
groups are the counted persons sharing a group id >= 0. Groups of fewer than two members after this are left out
on both sides of the group counts (1 and 4), as the authors' code of 1 does (GCFF ff_deletesingletons.m).

1. Group precision and recall (``t_2_3``, ``t_1``), after F. Setti, C. Russell, C. Bassetti and M. Cristani,
   "F-Formation Detection: Individuating Free-Standing Conversational Groups in Images", PLOS ONE 10(5):
   e0123783, 2015 (code: franzsetti/GCFF ff_evalgroups.m). A true group G and a detected group D match when
   |G n D| / max(|G|, |D|) >= T, T = 2/3 or 1 (decided on integers). For T > 1/2 a group matches at most one
   group of the other side (groups are disjoint), so the matching is one-to-one. Choice: TP, detected and true
   groups are pooled over the frames, P = TP / detected, R = TP / true; the authors' code averages the per-frame
   P and R instead, with P = R = 1 in frames without any group, which favours sparse scenes.
2. G-MITRE (``gmitre``), after F. Solera, S. Calderara and R. Cucchiara, "Socially Constrained Structural Learning
   for Groups Detection in Crowd", IEEE TPAMI 38(5), 2016 (code: francescosolera/group-detection lossGM.m), on
   the MITRE (MUC) score of M. Vilain et al., "A model-theoretic coreference scoring scheme", MUC-6, 1995. The
   elements are the frame's counted persons. Key: the true groups, a person alone (group -1) a singleton.
   Response: a person matched to a track of a tracked group is in that group, any other a singleton; the
   response is taken over the elements only (a false positive member is no element). MITRE recall
   R(K->R) = sum over key clusters S of (|S| - |p_R(S)|) / sum of (|S| - 1), p_R(S) the response clusters S's
   elements fall in; precision swaps K and R. G-MITRE gives every element k a counterpart k', which joins k where
   k is a singleton and is alone elsewhere; so a singleton of the key adds 1 to the denominator and 1 to the
   numerator when it is a singleton of the response too. Choice: numerators and denominators are pooled over the
   frames, apart for recall and for precision.
3. Pairwise relations (``pairwise``): the pairs of tracks both matched to counted persons whose true positions are
   at most ``relation_range`` apart (3 m: farther pairs are trivially unrelated and would swamp AUC). Label: the
   persons share a true group. Score: the relation's strength for the pair of track ids (either order), 0 where
   the relations lack it (SPENCER's grouping reads a missing relation as strength 0). Related when the strength is
   >= ``relation_threshold``: precision, recall, F1. ROC AUC is the Mann-Whitney statistic of two histograms (one
   per label) of ``bins`` uniform bins on [0, 1] (strengths clipped to it), a positive and a negative in one bin
   counting half: exact when no positive shares a bin with a negative of another score. Brier score: the mean of
   (strength - label)^2, summed exactly (tables.ExactSum).
4. Group tracking (``tracking``): the tracked groups against the true groups, both of two or more members, matched
   per frame by the T = 2/3 rule of 1. Unmatched tracked groups are false positives, unmatched true groups misses;
   a match is an ID switch when the true group was last matched, in any earlier frame, to another tracked group
   id (CLEAR-MOT's rule, Bernardin and Stiefelhagen 2008). MOTA = 1 - (FN + FP + IDS) / true groups.

F1 = 2PR / (P + R), 0 when P = R = 0. Undefined values (a zero denominator) are ``None``. Ids must be unique within a
frame (not checked); a track may belong to one tracked group at most, a pair of tracks have one relation at most
(else ``ValueError``). A pair with a non-finite position is never within range.

Memory: counts, two histograms and, per true group id ever matched, its last tracked group; never per frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pipeline.compiled import by_label, kernel

from .tables import ExactSum

__all__ = ["GroupFrame", "GroupMetrics"]


def _ints() -> np.ndarray:
    return np.zeros(0, np.int64)


@dataclass
class GroupFrame:
    """One tracking cycle as the group metrics see it (see module docstring)."""

    gt_id: np.ndarray = field(default_factory=_ints)  # [n] counted persons
    gt_group: np.ndarray = field(default_factory=_ints)  # [n] their true group, -1 alone
    gt_position: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # [n, 2] m
    matched_gt: np.ndarray = field(default_factory=_ints)  # [k] CLEAR-MOT's matches: person id
    matched_track: np.ndarray = field(default_factory=_ints)  # [k] and track id
    excused_track: np.ndarray = field(default_factory=_ints)  # [e] tracks matched to ignored persons
    relation_a: np.ndarray = field(default_factory=_ints)  # [r] one row per unordered pair of track ids
    relation_b: np.ndarray = field(default_factory=_ints)
    relation_strength: np.ndarray = field(default_factory=lambda: np.zeros(0))
    group_id: np.ndarray = field(default_factory=_ints)  # [m] tracked group of each member row
    group_track: np.ndarray = field(default_factory=_ints)  # [m] member track


def _i(a) -> np.ndarray:
    """``a`` as a contiguous int64 vector: the one layout the kernels are compiled for."""
    return np.ascontiguousarray(a, np.int64).reshape(-1)


def _ratio(num: int, den: int) -> float | None:
    return None if den == 0 else num / den


def _f1(p: float | None, r: float | None) -> float | None:
    if p is None or r is None:
        return None
    return 0.0 if p + r == 0 else 2 * p * r / (p + r)


class GroupMetrics:
    """The group metrics of the module docstring, over the cycles given to ``update``."""

    def __init__(self, relation_range: float = 3.0, relation_threshold: float = 0.5, bins: int = 10000):
        """``relation_range``: largest true distance (m, inclusive) of a scored pair; ``relation_threshold``: the
        strength from which a pair counts as related; ``bins``: histogram bins of the AUC."""
        relation_range = float(relation_range)
        if not np.isfinite(relation_range) or relation_range < 0.0:
            raise ValueError("relation_range must be finite and >= 0")
        if int(bins) < 1:
            raise ValueError("bins must be >= 1")
        self.relation_range, self.relation_threshold, self.bins = relation_range, float(relation_threshold), int(bins)
        self._frames = self._true = self._detected = self._tp23 = self._tp1 = 0
        self._mitre = [0, 0, 0, 0]  # recall numerator, denominator; precision numerator, denominator
        self._pairs = self._pos = self._related = self._related_pos = 0
        self._hist = np.zeros((2, self.bins), np.int64)  # [label, bin]
        self._brier = ExactSum()
        self._fp = self._ids = 0
        self._last: dict[int, int] = {}  # true group id ever matched -> the tracked group it was last matched to

    def update(self, frame: GroupFrame) -> None:
        """Score one cycle."""
        gt_id, gt_group = _i(frame.gt_id), _i(frame.gt_group)
        n = gt_id.size
        pos = np.asarray(frame.gt_position, np.float64).reshape(n, 2)
        m_track, m_gt, g_id, g_track = (_i(frame.matched_track), _i(frame.matched_gt), _i(frame.group_id),
                                        _i(frame.group_track))
        # the kernels below read these by each other's rows (and numba checks no bounds)
        for names, first, second in (("gt_id and gt_group", gt_id, gt_group),
                                     ("matched_gt and matched_track", m_gt, m_track),
                                     ("group_id and group_track", g_id, g_track)):
            if first.size != second.size:
                raise ValueError(f"{names} must have one entry each per row: got {first.size} and {second.size}")
        m_row = _rows(gt_id, m_gt)
        if (m_row < 0).any():
            raise ValueError("matched_gt must be counted persons of the frame")
        self._frames += 1
        # The tracked groups as the persons see them (excused members dropped, false positive tracks in the sizes
        # only), and the true groups as dense numbers of the counted persons' groups.
        response, det_ids, det_size = _response(n, m_row, m_track, _i(frame.excused_track), g_id, g_track)
        true_of, true_ids, true_size = _numbered(gt_group, gt_group >= 0)
        self._match_groups(true_of, true_ids, true_size, response, det_ids, det_size)
        self._mitre = [total + part for total, part in zip(self._mitre, (*_mitre(true_of, response),
                                                                          *_mitre(response, true_of)))]
        self._relations(frame, pos, gt_group, m_row, m_track)

    def _match_groups(self, true_of, true_ids, true_size, response, det_ids, det_size) -> None:
        """Metrics 1 and 4: the groups of 2+ members of both sides, matched by their common persons."""
        n_true, n_det, tp, tp1, matched_true, matched_det = _group_matches(true_of, true_size, response, det_size)
        self._true += n_true
        self._detected += n_det
        self._tp23 += tp
        self._tp1 += tp1
        self._fp += n_det - tp
        # ID switches: a true group matched to another tracked group id than the one it was last matched to (a true
        # group matches one tracked group a frame at most, so the order of the matches does not matter).
        for group, tracked in zip(true_ids[matched_true].tolist(), det_ids[matched_det].tolist()):
            self._ids += self._last.get(group, tracked) != tracked
            self._last[group] = tracked

    def _relations(self, frame: GroupFrame, pos, gt_group, m_row, m_track) -> None:
        """Metric 3: the pairs of matched tracks within range, scored by their relation's strength."""
        i, j = _close_pairs(pos, m_row, self.relation_range)
        if i.size == 0:
            return
        ra, rb = _i(frame.relation_a), _i(frame.relation_b)
        strength = np.ascontiguousarray(frame.relation_strength, np.float64).reshape(-1)
        if not ra.size == rb.size == strength.size:
            raise ValueError("relation_a, relation_b and relation_strength must have one entry per relation")
        score = _relation_strengths(m_track, i, j, ra, rb, strength)
        positives, related, related_pos, squared_error = _tally_pairs(score, gt_group[m_row], i, j,
                                                                      self.relation_threshold, self._hist)
        self._pairs += i.size
        self._pos += positives
        self._related += related
        self._related_pos += related_pos
        self._brier.add(squared_error)

    def _auc(self) -> float | None:
        neg, pos = self._hist
        n_neg, n_pos = int(neg.sum()), int(pos.sum())
        if n_neg == 0 or n_pos == 0:
            return None
        below = np.cumsum(neg) - neg  # negatives in lower bins
        return float((pos * (below + 0.5 * neg)).sum() / (n_pos * n_neg))

    def curves(self, points: int = 201) -> dict[str, np.ndarray]:
        """The relations' ROC (false and true positive rates) and precision-recall curves, a pair called related at
        strength >= each of ``points`` thresholds from 0 to 1 (bin edges of the histograms)."""
        edges = np.linspace(0, self.bins, points).round().astype(np.int64)
        above = np.cumsum(self._hist[:, ::-1], axis=1)[:, ::-1]  # [label, bin]: pairs at that bin or higher
        above = np.concatenate([above, np.zeros((2, 1), np.int64)], axis=1)[:, edges]
        neg, pos = above
        with np.errstate(invalid="ignore", divide="ignore"):
            return {"threshold": edges / self.bins, "fpr": neg / max(neg[0], 1), "tpr": pos / max(pos[0], 1),
                    "precision": np.where(pos + neg > 0, pos / (pos + neg), np.nan), "recall": pos / max(pos[0], 1)}

    def summary(self) -> dict:
        """Totals over the cycles so far as plain, JSON-serialisable Python values (see module docstring)."""

        def setti(tp: int) -> dict:
            p, r = _ratio(tp, self._detected), _ratio(tp, self._true)
            return {"tp": tp, "precision": p, "recall": r, "f1": _f1(p, r)}

        rn, rd, pn, pd = self._mitre
        mp, mr = _ratio(pn, pd), _ratio(rn, rd)
        pp, pr = _ratio(self._related_pos, self._related), _ratio(self._related_pos, self._pos)
        fn = self._true - self._tp23
        return {
            "frames": self._frames,
            "true_groups": self._true,
            "detected_groups": self._detected,
            "t_2_3": setti(self._tp23),
            "t_1": setti(self._tp1),
            "gmitre": {"precision": mp, "recall": mr, "f1": _f1(mp, mr)},
            "pairwise": {"pairs": self._pairs, "positives": self._pos, "precision": pp, "recall": pr,
                         "f1": _f1(pp, pr), "auc": self._auc(), "brier": self._brier.mean()},
            "tracking": {"gt": self._true, "tp": self._tp23, "fp": self._fp, "fn": fn, "id_switches": self._ids,
                         "mota": None if self._true == 0 else 1.0 - (fn + self._fp + self._ids) / self._true},
        }


@kernel
def _close_pairs(pos, rows, reach):
    """The pairs (i, j), i < j, of ``rows`` (indices into ``pos``) whose positions lie within ``reach`` of each
    other, in ``np.triu_indices``' order."""
    n = len(rows)
    first, second = np.empty(n * (n - 1) // 2, np.int64), np.empty(n * (n - 1) // 2, np.int64)
    # a squared distance past this is past ``reach`` whatever the rounding (the relative 1e-9 covers the squares',
    # the absolute 1e-300 their underflow): most pairs are, and cost no hypot
    beyond = reach * reach * (1.0 + 1e-9) + 1e-300
    m = 0
    for i in range(n):
        for j in range(i + 1, n):
            a, b = rows[i], rows[j]
            dx, dy = pos[a, 0] - pos[b, 0], pos[a, 1] - pos[b, 1]
            if not dx * dx + dy * dy > beyond and math.hypot(dx, dy) <= reach:
                first[m], second[m] = i, j
                m += 1
    return first[:m], second[:m]


# The frame's ids (persons, tracks, groups) are arbitrary int64s: the kernels below find them in hash tables, a few
# probes an id whatever its value, where numpy's sorting calls cost their overhead many times over at a crowd's size.


@kernel
def _empty_table(n):
    """Room for ``n`` keys (-1: an empty slot), at least twice as many slots, a power of two."""
    size = 8
    while size < 2 * n:
        size *= 2
    return np.full(size, -1, np.int64)


@kernel
def _slot(table, first, second, a, b):
    """The slot of ``table`` (its entries index ``first`` and ``second``) holding the key (a, b), else the empty one
    where it goes: linear probing from the key's Fibonacci hash (the high bits of a key times 2^64 / golden ratio).
    A key of one id is (id, id)."""
    mask = len(table) - 1
    h = (np.uint64(a) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(b)) * np.uint64(0x9E3779B97F4A7C15)
    s = np.int64(h >> np.uint64(32)) & mask
    while table[s] >= 0 and (first[table[s]] != a or second[table[s]] != b):
        s = (s + 1) & mask
    return s


@kernel
def _rows(keys, query):
    """The index in ``keys`` of each of ``query``, -1 where absent (the first where a key repeats)."""
    table = _empty_table(len(keys))
    for k in range(len(keys)):
        s = _slot(table, keys, keys, keys[k], keys[k])
        if table[s] < 0:
            table[s] = k
    out = np.empty(len(query), np.int64)
    for q in range(len(query)):
        out[q] = table[_slot(table, keys, keys, query[q], query[q])]
    return out


@kernel
def _numbered(values, counted):
    """Dense numbers 0.. of the ``values`` where ``counted``, in order of first appearance (-1 elsewhere); the value
    and the count of each number."""
    table = _empty_table(len(values))
    label = np.full(len(values), -1, np.int64)
    distinct, count = np.empty(len(values), np.int64), np.zeros(len(values), np.int64)
    k = 0
    for e in range(len(values)):
        if counted[e]:
            s = _slot(table, distinct, distinct, values[e], values[e])
            if table[s] < 0:
                table[s] = k
                distinct[k] = values[e]
                k += 1
            label[e] = table[s]
            count[label[e]] += 1
    return label, distinct[:k], count[:k]


@kernel
def _response(n, m_row, m_track, excused, group_id, group_track):
    """The tracked groups as the ``n`` persons see them: each person's group (dense numbers 0.., -1 none), and each
    group's id and size. A member track matched to a person (``m_track[k]`` to row ``m_row[k]``) is that person, an
    ``excused`` one is dropped, any other (a false positive) counts in its group's size only."""
    first = _rows(group_track, group_track)
    excused_at = _rows(excused, group_track)
    kept = np.empty(len(group_track), np.bool_)
    for k in range(len(group_track)):
        if first[k] != k:
            raise ValueError("a track can be a member of one tracked group only")
        kept[k] = excused_at[k] < 0
    group, ids, size = _numbered(group_id, kept)
    match = _rows(m_track, group_track)
    response = np.full(n, -1, np.int64)
    for k in range(len(group_track)):
        if kept[k] and match[k] >= 0:
            response[m_row[match[k]]] = group[k]
    return response, ids, size


@kernel
def _group_matches(true_of, true_size, response, det_size):
    """Metric 1's counts: the true and the tracked groups of two or more members, the matches at T = 2/3
    (3 |G n D| >= 2 max(|G|, |D|)) and at T = 1, and the matched pairs (true, tracked group number). ``true_of`` and
    ``response`` are each person's true and tracked group (-1: none); the sizes count all members (a tracked
    group's false positives too). |G n D| is counted per tracked group over its persons, each true group met in it
    once."""
    start, order = by_label(response, len(det_size))
    common, met_in, met = np.zeros(len(true_size), np.int64), np.full(len(true_size), -1, np.int64), np.empty(
        len(order), np.int64)
    matched_true, matched_det = np.empty(len(det_size), np.int64), np.empty(len(det_size), np.int64)
    n_true = n_det = tp = exact = matches = 0
    for t in range(len(true_size)):
        if true_size[t] >= 2:
            n_true += 1
    for d in range(len(det_size)):
        if det_size[d] < 2:
            continue
        n_det += 1
        k = 0  # the true groups met in d: met[:k]
        for p in range(start[d], start[d + 1]):
            t = true_of[order[p]]
            if t >= 0:
                if met_in[t] != d:
                    met_in[t], common[t], met[k] = d, 0, t
                    k += 1
                common[t] += 1
        for q in range(k):
            t = met[q]
            big = max(det_size[d], true_size[t])
            if true_size[t] >= 2:
                if 3 * common[t] >= 2 * big:
                    tp += 1
                    matched_true[matches] = t
                    matched_det[matches] = d
                    matches += 1
                if common[t] == big:
                    exact += 1
    return n_true, n_det, tp, exact, matched_true[:matches], matched_det[:matches]


@kernel
def _mitre(key, response):
    """G-MITRE's numerator and denominator of R(key -> response), partitions as a cluster number 0.. per element,
    -1 a cluster of its own: per key cluster S of 2+ elements |S| minus the response clusters S falls in, plus 1 per
    element alone on both sides (its counterpart); the denominator is the elements less the key clusters of 2+."""
    nk = nr = 0
    for e in range(len(key)):
        nk, nr = max(nk, key[e] + 1), max(nr, response[e] + 1)
    start, order = by_label(key, nk)
    r_size = np.zeros(nr, np.int64)
    for r in response:
        if r >= 0:
            r_size[r] += 1
    numerator = clusters = 0
    for e in range(len(key)):
        if (key[e] < 0 or start[key[e] + 1] - start[key[e]] == 1) and (response[e] < 0 or r_size[response[e]] == 1):
            numerator += 1
    met_in = np.full(nr, -1, np.int64)  # the key cluster in which each response cluster was last met
    for c in range(nk):
        if start[c + 1] - start[c] >= 2:
            clusters += 1
            numerator += start[c + 1] - start[c]
            for p in range(start[c], start[c + 1]):
                r = response[order[p]]
                if r < 0 or met_in[r] != c:
                    numerator -= 1
                    if r >= 0:
                        met_in[r] = c
    return numerator, len(key) - clusters


@kernel
def _relation_strengths(track, i, j, rel_a, rel_b, strength):
    """The strength of the relation between tracks ``track[i[p]]`` and ``track[j[p]]`` (given in either order), 0
    where the relations lack it; a pair of tracks with more than one relation is a ``ValueError``."""
    r = len(rel_a)
    lo, hi, table = np.empty(r, np.int64), np.empty(r, np.int64), _empty_table(r)
    for k in range(r):
        lo[k], hi[k] = min(rel_a[k], rel_b[k]), max(rel_a[k], rel_b[k])
        s = _slot(table, lo, hi, lo[k], hi[k])
        if table[s] >= 0:
            raise ValueError("a pair of tracks has more than one relation")
        table[s] = k
    out = np.zeros(len(i))
    for p in range(len(i)):
        a, b = track[i[p]], track[j[p]]
        k = table[_slot(table, lo, hi, min(a, b), max(a, b))]
        if k >= 0:
            out[p] = strength[k]
    return out


@kernel
def _tally_pairs(score, group, i, j, threshold, hist):
    """The scored pairs of rows (``i[p]``, ``j[p]``) into ``hist`` [label, bin] (in place; bins uniform on [0, 1],
    scores clipped to it), a pair positive (label 1) when both rows are in one true group (``group`` >= 0): how many
    are positive, how many related (score >= ``threshold``), how many both, and each pair's squared error
    (score - label)^2 for the Brier score."""
    bins = hist.shape[1]
    positives = related = related_pos = 0
    squared_error = np.empty(len(score))
    for p in range(len(score)):
        s = score[p]
        if math.isnan(s):
            raise ValueError("relation strengths must not be NaN")
        positive = 1 if group[i[p]] >= 0 and group[i[p]] == group[j[p]] else 0
        positives += positive
        if s >= threshold:
            related += 1
            related_pos += positive
        hist[positive, min(int(min(max(s, 0.0), 1.0) * bins), bins - 1)] += 1
        error = s - positive
        squared_error[p] = error * error
    return positives, related, related_pos, squared_error
