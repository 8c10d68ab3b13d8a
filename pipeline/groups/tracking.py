"""Group tracking by composition (SPENCER's ``tracked_groups.py``; seed 000 D2.5 Sec. 3: "more robust when group
splits and merges happen frequently" than tracking centroids).

A memory holds the last ``memory`` member sets seen (300, as SPENCER's), each with its group id and since when that
exact set has existed. Each cycle, clusters in the order of their smallest track id take the id of the remembered
set that is a subset or a superset of theirs, the largest such, the oldest among equals, unless another cluster took
that id this cycle; else a new id. A group's age is how long its exact member set has existed: it restarts at any
change of members, as SPENCER's. Our one departure: only clusters of two or more take part. SPENCER lets single
persons take ids and enter the memory too, so a new pair could take the id one of its members had alone, and a
person's solitude would fill the memory.

The memory is a table of ``memory + 1`` slots (one more for the set just added, before the oldest goes), scanned
whole for each cluster by one kernel: a few hundred slots, each set's 64-bit signature (a bit per track id modulo
64) ruling out most before its members are compared.
"""

from __future__ import annotations

import numpy as np

from pipeline.compiled import by_label, kernel
from pipeline.types import TrackedGroups

_NEXT_ENTRY, _NEXT_ID, _CLOCK = range(3)  # the counters' places


class CompositionTracker:
    def __init__(self, memory: int = 300):
        self.memory_size = memory
        self.reset()

    def reset(self) -> None:
        slots = self.memory_size + 1
        self.members = np.zeros((slots, 8), np.int64)  # each slot's member set, ascending (as wide as a cycle's tracks)
        self.size = np.zeros(slots, np.int64)
        self.group = np.zeros(slots, np.int64)  # its group id
        self.entry = np.full(slots, -1, np.int64)  # the order in which sets were first remembered; -1: a free slot
        self.touched = np.zeros(slots, np.int64)  # when the set was last seen, in ticks of the clock: the oldest goes
        self.signature = np.zeros(slots, np.int64)
        self.since = np.zeros(slots)  # since when the exact set has existed
        self.counters = np.zeros(3, np.int64)  # the next entry, the next group id, the clock

    def update(self, stamp: float, frame: str, track_id: np.ndarray, position: np.ndarray,
               labels: np.ndarray) -> TrackedGroups:
        """The groups of this cycle's clusters (``labels`` 0..k-1, one per track) of two or more tracks."""
        if not len(track_id) == len(position) == len(labels) or (len(labels) and np.min(labels) < 0):
            raise ValueError(f"track_id, position and labels: expected one entry each per track and labels >= 0, got "
                             f"{len(track_id)}, {len(position)} and {len(labels)} entries")
        if len(track_id) > self.members.shape[1]:  # room for a cluster of all the tracks
            wider = np.zeros((len(self.members), max(len(track_id), 2 * self.members.shape[1])), np.int64)
            wider[:, :self.members.shape[1]] = self.members
            self.members = wider
        ids, centroid, member_group, member_track, age = _track(
            float(stamp), np.ascontiguousarray(track_id, np.int64), np.ascontiguousarray(position, np.float64),
            np.ascontiguousarray(labels, np.int64), self.members, self.size, self.group, self.entry, self.touched,
            self.signature, self.since, self.counters, self.memory_size)
        return TrackedGroups(stamp, frame, ids, centroid, member_group, member_track, age)


@kernel
def _common(a, na, b, nb):
    """How many of the ascending ``a[:na]`` are among the ascending ``b[:nb]``."""
    p = q = common = 0
    while p < na and q < nb:
        if a[p] == b[q]:
            common += 1
            p += 1
            q += 1
        elif a[p] < b[q]:
            p += 1
        else:
            q += 1
    return common


@kernel
def _track(stamp, track_id, position, labels, members, size, group, entry, touched, signature, since, counters,
           memory):
    """One cycle of ``CompositionTracker`` (module docstring) on the memory's slots, in place: the clusters' group
    ids, centroids, members (as ``TrackedGroups`` lists them) and ages. A set's signature has a bit per track id
    modulo 64: a set with a bit the other lacks is not the other's subset."""
    k = 0
    for c in labels:
        k = max(k, c + 1)
    start, order = by_label(labels, k)  # label c's tracks, in their order: order[start[c]:start[c + 1]]
    # the clusters of two or more, by their smallest track id (then label): an insertion sort, as they are few
    first, clusters = np.empty(k, np.int64), np.empty(k, np.int64)
    m = 0
    for c in range(k):
        if start[c + 1] - start[c] < 2:
            continue
        first[c] = track_id[order[start[c]]]
        for p in range(start[c] + 1, start[c + 1]):
            first[c] = min(first[c], track_id[order[p]])
        p = m
        while p > 0 and first[clusters[p - 1]] > first[c]:
            clusters[p] = clusters[p - 1]
            p -= 1
        clusters[p] = c
        m += 1
    live = 0
    for q in range(len(entry)):
        if entry[q] >= 0:
            live += 1

    ids, age = np.empty(m, np.int64), np.empty(m)
    centroid, member_group = np.empty((m, 2)), np.empty(start[k], np.int64)
    member_track = np.empty(start[k], np.int64)
    cluster, out = np.empty(len(labels), np.int64), 0
    for g in range(m):
        c = clusters[g]
        s = start[c + 1] - start[c]
        bits = np.int64(0)
        for p in range(s):  # the members ascending, for comparing sets
            t = track_id[order[start[c] + p]]
            bits |= np.int64(1) << (t & 63)
            r = p
            while r > 0 and cluster[r - 1] > t:
                cluster[r] = cluster[r - 1]
                r -= 1
            cluster[r] = t
        best = same = -1
        for q in range(len(entry)):
            if entry[q] < 0 or ((signature[q] & ~bits) != 0 and (bits & ~signature[q]) != 0):
                continue
            common = _common(members[q], size[q], cluster, s)
            if common != size[q] and common != s:
                continue  # neither a subset nor a superset
            if common == size[q] and common == s:
                same = q
            taken = False
            for h in range(g):
                if ids[h] == group[q]:
                    taken = True
                    break
            if not taken and (best < 0 or size[q] > size[best] or (size[q] == size[best] and (
                    since[q] < since[best] or (since[q] == since[best] and entry[q] < entry[best])))):
                best = q
        group_id = group[best] if best >= 0 else counters[_NEXT_ID]
        counters[_NEXT_ID] = max(counters[_NEXT_ID], group_id + 1)
        if same >= 0:  # a set already remembered keeps its entry (its place among equals), seen now
            since[same] = since[same] if since[same] < stamp else stamp
            slot = same
        else:
            slot = 0
            while entry[slot] >= 0:
                slot += 1
            for p in range(s):
                members[slot, p] = cluster[p]
            size[slot], signature[slot] = s, bits
            entry[slot], since[slot] = counters[_NEXT_ENTRY], stamp
            counters[_NEXT_ENTRY] += 1
            live += 1
        group[slot], touched[slot] = group_id, counters[_CLOCK]
        counters[_CLOCK] += 1
        while live > memory:  # forget the set seen longest ago
            oldest = -1
            for q in range(len(entry)):
                if entry[q] >= 0 and (oldest < 0 or touched[q] < touched[oldest]):
                    oldest = q
            entry[oldest] = -1
            live -= 1
        ids[g] = group_id
        a = stamp - since[slot]
        age[g] = a if a > 0.0 else 0.0
        x = y = 0.0  # the members' positions summed in track order, as np.bincount sums them
        for p in range(start[c], start[c + 1]):
            x += position[order[p], 0]
            y += position[order[p], 1]
            member_group[out], member_track[out] = group_id, track_id[order[p]]
            out += 1
        centroid[g, 0], centroid[g, 1] = x / s, y / s
    return ids, centroid, member_group[:out], member_track[:out], age
