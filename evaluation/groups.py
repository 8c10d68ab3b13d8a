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

from pipeline.compiled import kernel

from .tables import ExactSum, Slots, grown

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
    return np.asarray(a, np.int64).reshape(-1)


def _lookup(keys: np.ndarray, values: np.ndarray, query: np.ndarray, missing) -> tuple[np.ndarray, np.ndarray]:
    """The value of each of ``query`` in the map ``keys`` (unique) -> ``values``, ``missing`` where absent; and
    whether it was found."""
    if keys.size == 0:
        return np.full(query.size, missing, values.dtype), np.zeros(query.size, bool)
    order = np.argsort(keys)
    at = np.minimum(np.searchsorted(keys[order], query), keys.size - 1)
    found = keys[order][at] == query
    return np.where(found, values[order][at], missing), found


def _ratio(num: int, den: int) -> float | None:
    return None if den == 0 else num / den


def _f1(p: float | None, r: float | None) -> float | None:
    if p is None or r is None:
        return None
    return 0.0 if p + r == 0 else 2 * p * r / (p + r)


def _clusters(labels: np.ndarray, alone: np.ndarray) -> np.ndarray:
    """Cluster numbers 0.. of elements labelled ``labels``, each element where ``alone`` a cluster of its own."""
    _, inv = np.unique(labels[~alone], return_inverse=True)
    out = np.empty(labels.size, np.int64)
    out[~alone] = inv.reshape(-1)
    out[alone] = (inv.max() + 1 if inv.size else 0) + np.arange(np.count_nonzero(alone))
    return out


def _mitre(key: np.ndarray, response: np.ndarray) -> tuple[int, int]:
    """G-MITRE's numerator and denominator of R(key -> response), partitions as cluster numbers per element."""
    k_size = np.bincount(key)
    in_group = k_size[key] >= 2
    lone = ~in_group & (np.bincount(response)[response] == 1)
    spans = np.unique(key[in_group] * (int(response.max()) + 1) + response[in_group]).size
    return int(in_group.sum()) - spans + int(lone.sum()), key.size - int((k_size >= 2).sum())


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
        self._mitre = np.zeros(4, np.int64)  # recall numerator, denominator; precision numerator, denominator
        self._pairs = self._pos = self._related = self._related_pos = 0
        self._hist = np.zeros((2, self.bins), np.int64)  # [label, bin]
        self._brier = ExactSum()
        self._fp = self._ids = 0
        self._groups = Slots()  # true group ids ever matched
        self._last = _ints()  # the tracked group each was last matched to

    def update(self, frame: GroupFrame) -> None:
        """Score one cycle."""
        gt_id, gt_group = _i(frame.gt_id), _i(frame.gt_group)
        n = gt_id.size
        pos = np.asarray(frame.gt_position, np.float64).reshape(n, 2)
        m_track = _i(frame.matched_track)
        m_row, found = _lookup(gt_id, np.arange(n), _i(frame.matched_gt), -1)
        if not found.all():
            raise ValueError("matched_gt must be counted persons of the frame")
        self._frames += 1

        # Tracked groups: member rows to person rows (-1: a false positive track), excused members dropped.
        g_id, g_track = _i(frame.group_id), _i(frame.group_track)
        if np.unique(g_track).size != g_track.size:
            raise ValueError("a track can be a member of one tracked group only")
        keep = ~np.isin(g_track, _i(frame.excused_track))
        member, _ = _lookup(m_track, m_row, g_track[keep], -1)
        det_ids, det = np.unique(g_id[keep], return_inverse=True)
        det = det.reshape(-1)
        det_size = np.bincount(det, minlength=det_ids.size)

        # True groups: dense numbers of the counted persons' groups.
        grouped = gt_group >= 0
        true_ids, true = np.unique(gt_group[grouped], return_inverse=True)
        true_of = np.full(n, -1, np.int64)
        true_of[grouped] = true.reshape(-1)
        true_size = np.bincount(true_of[grouped], minlength=true_ids.size)

        self._match_groups(member, det, det_ids, det_size, true_of, true_ids, true_size)
        if n:
            response = np.full(n, -1, np.int64)
            response[member[member >= 0]] = det[member >= 0]
            key, response = _clusters(true_of, ~grouped), _clusters(response, response < 0)
            self._mitre += (*_mitre(key, response), *_mitre(response, key))
        self._relations(frame, pos, gt_group, m_row, m_track)

    def _match_groups(self, member, det, det_ids, det_size, true_of, true_ids, true_size) -> None:
        """Metrics 1 and 4: the groups of 2+ members of both sides, matched by their common persons."""
        nt = max(true_ids.size, 1)
        t = true_of[member[member >= 0]]
        d = det[member >= 0][t >= 0]
        both, common = np.unique(d * nt + t[t >= 0], return_counts=True)
        d, t = both // nt, both % nt
        big = np.maximum(det_size[d], true_size[t])
        ok = (det_size[d] >= 2) & (true_size[t] >= 2)
        match = ok & (3 * common >= 2 * big)
        n_true, n_det, tp = int((true_size >= 2).sum()), int((det_size >= 2).sum()), int(match.sum())
        self._true += n_true
        self._detected += n_det
        self._tp23 += tp
        self._tp1 += int((ok & (common == big)).sum())
        self._fp += n_det - tp

        # ID switches: a true group matched to another tracked group id than the one it was last matched to.
        gid, tid = true_ids[t[match]], det_ids[d[match]]
        known = len(self._groups)
        slot = self._groups(gid)
        self._last = grown(self._last, len(self._groups))
        seen = slot < known
        self._ids += int((self._last[slot[seen]] != tid[seen]).sum())
        self._last[slot] = tid

    def _relations(self, frame: GroupFrame, pos, gt_group, m_row, m_track) -> None:
        """Metric 3: the pairs of matched tracks within range, scored by their relation's strength."""
        i, j = _close_pairs(pos, m_row, self.relation_range)
        if i.size == 0:
            return
        a, b = m_row[i], m_row[j]
        label = (gt_group[a] >= 0) & (gt_group[a] == gt_group[b])
        ra, rb = _i(frame.relation_a), _i(frame.relation_b)
        strength = np.asarray(frame.relation_strength, np.float64).reshape(-1)
        if not ra.size == rb.size == strength.size:
            raise ValueError("relation_a, relation_b and relation_strength must have one entry per relation")
        # Pairs of tracks as keys min * K + max over the dense numbers of the K track ids in play.
        ids, dense = np.unique(np.concatenate([m_track, ra, rb]), return_inverse=True)
        t, da, db = np.split(dense.reshape(-1), [m_track.size, m_track.size + ra.size])
        rel_key = np.minimum(da, db) * ids.size + np.maximum(da, db)
        if np.unique(rel_key).size != rel_key.size:
            raise ValueError("a pair of tracks has more than one relation")
        ti, tj = t[i], t[j]
        score, _ = _lookup(rel_key, strength, np.minimum(ti, tj) * ids.size + np.maximum(ti, tj), 0.0)
        related = score >= self.relation_threshold
        self._pairs += i.size
        self._pos += int(label.sum())
        self._related += int(related.sum())
        self._related_pos += int((related & label).sum())
        bin_ = np.minimum((np.clip(score, 0.0, 1.0) * self.bins).astype(np.int64), self.bins - 1)
        self._hist += np.bincount(label * self.bins + bin_, minlength=2 * self.bins).reshape(2, self.bins)
        self._brier.add((score - label) ** 2)

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

        rn, rd, pn, pd = self._mitre.tolist()
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
    m = 0
    for i in range(n):
        for j in range(i + 1, n):
            a, b = rows[i], rows[j]
            if math.hypot(pos[a, 0] - pos[b, 0], pos[a, 1] - pos[b, 1]) <= reach:
                first[m], second[m] = i, j
                m += 1
    return first[:m], second[:m]
