"""Group tracking by composition (SPENCER's ``tracked_groups.py``; seed 000 D2.5 Sec. 3: "more robust when group
splits and merges happen frequently" than tracking centroids).

A memory holds the last ``memory`` member sets seen (300, as SPENCER's), each with its group id and since when that
exact set has existed. Each cycle, clusters in the order of their smallest track id take the id of the remembered
set that is a subset or a superset of theirs, the largest such, the oldest among equals, unless another cluster took
that id this cycle; else a new id. A group's age is how long its exact member set has existed: it restarts at any
change of members, as SPENCER's. Our one departure: only clusters of two or more take part. SPENCER lets single
persons take ids and enter the memory too, so a new pair could take the id one of its members had alone, and a
person's solitude would fill the memory.
"""

from __future__ import annotations

from collections import Counter, OrderedDict

import numpy as np

from pipeline.types import TrackedGroups

NONE = frozenset()  # the entries of a track in none


class CompositionTracker:
    def __init__(self, memory: int = 300):
        self.memory_size = memory
        self.reset()

    def reset(self) -> None:
        self.memory: OrderedDict[int, tuple[frozenset, int, float]] = OrderedDict()  # entry -> (members, id, since)
        self.by_track: dict[int, set[int]] = {}  # track id -> the entries that hold it
        self.by_members: dict[frozenset, int] = {}  # member set -> its entry
        self.next_entry = 0
        self.next_id = 0

    def update(self, stamp: float, frame: str, track_id: np.ndarray, position: np.ndarray,
               labels: np.ndarray) -> TrackedGroups:
        """The groups of this cycle's clusters (``labels``, one per track) of two or more tracks."""
        by_label: dict[int, list[int]] = {}
        for t, label in zip(track_id.tolist(), labels.tolist()):
            by_label.setdefault(label, []).append(t)
        clusters = sorted(((min(m), label, m) for label, m in by_label.items() if len(m) >= 2))
        used, ids, ages = set(), [], []
        for _, _, members in clusters:
            members = frozenset(members)
            group_id = self._match(members, used)
            if group_id is None:
                group_id = self.next_id
            self.next_id = max(self.next_id, group_id + 1)
            used.add(group_id)
            ids.append(group_id)
            ages.append(max(0.0, stamp - self._remember(members, group_id, stamp)))
        sizes = np.bincount(labels, minlength=1)
        centroid = np.column_stack([np.bincount(labels, position[:, k], minlength=1) for k in (0, 1)]) / np.maximum(
            sizes, 1)[:, None]
        picked = np.array([label for _, label, _ in clusters], np.int64)
        return TrackedGroups(stamp, frame, np.array(ids, np.int64), centroid[picked].reshape(-1, 2),
                             np.repeat(np.array(ids, np.int64), sizes[picked]),
                             np.array([t for _, _, m in clusters for t in m], np.int64), np.array(ages, float))

    def _match(self, members: frozenset, used: set[int]) -> int | None:
        """The id of the largest (then oldest, then first remembered) subset or superset of ``members`` not used this
        cycle. The entries holding all members are the supersets; for a pair, the only subset (the memory holds no
        single persons) is itself, among them. A larger cluster also counts, for each entry holding any member, how
        many it holds: all of its own, a subset."""
        held_by = [self.by_track.get(t, NONE) for t in members]
        if len(members) == 2:
            candidates = held_by[0] & held_by[1]
        else:
            hits = Counter()
            for entries in held_by:
                hits.update(entries)
            candidates = [e for e, k in hits.items() if k == len(members) or k == len(self.memory[e][0])]
        best, best_key = None, None
        for entry in candidates:
            held, group_id, since = self.memory[entry]
            key = (len(held), -since, -entry)
            if group_id not in used and (best_key is None or key > best_key):
                best, best_key = group_id, key
        return best

    def _remember(self, members: frozenset, group_id: int, stamp: float) -> float:
        """Store ``members`` as the newest entry; since when this exact set has existed. A set already remembered
        keeps its entry (and so its place among equals in ``_match``), moved to the newest end."""
        old = self.by_members.get(members)
        if old is not None:
            since = min(stamp, self.memory[old][2])
            self.memory[old] = (members, group_id, since)
            self.memory.move_to_end(old)
            return since
        since = stamp
        entry = self.next_entry
        self.next_entry += 1
        self.memory[entry] = (members, group_id, since)
        self.by_members[members] = entry
        for t in members:
            self.by_track.setdefault(t, set()).add(entry)
        while len(self.memory) > self.memory_size:
            self._forget(next(iter(self.memory)))
        return since

    def _forget(self, entry: int) -> None:
        members, _, _ = self.memory.pop(entry)
        del self.by_members[members]
        for t in members:
            held = self.by_track[t]
            held.discard(entry)
            if not held:
                del self.by_track[t]
