"""Nearest-neighbour people tracker on the ground plane (the SPENCER NNT, seed 000 Sec. II-B, III, V, Table II).

Why: the testbed needs a fast, deterministic multi-person tracker that turns per-frame detections (already in the
locally fixed tracking frame, e.g. ``odom``) into persistent person tracks with ids, so that CLEAR-MOT can score the
perception pipeline. The seed paper's tracker is a Kalman filter per person with nearest-neighbour data association
on the Mahalanobis distance, made robust in crowds by a few cheap extensions (Sec. III); it runs at kHz (Table II).
The tracker is given its parts as objects (as Stone Soup's trackers are given their initiator, deleter and
associator), so Table II's rows are configurations of this one tracker and a test can hand it a fake:

* motion model (``pipeline.tracking.motion``, ``.imm``): ``ConstantVelocity`` (Eq. 1-2), ``ConstantAcceleration``,
  ``CoordinatedTurn`` (an EKF), ``Brownian``, or an ``IMM`` over several of them (Sec. III-A, V-D);
* association (``pipeline.tracking.association``), which holds the gate: ``GreedyNN``, ``GlobalNN``, ``MultiNN``
  (Sec. II-B, V-A);
* initiation logic (``pipeline.tracking.initiation``), which says how a candidate starts too: ``CountInitiation``,
  ``BaseInitiation``, ``ExtendedInitiation`` (Sec. III-B, Alg. 1, V-B);
* deletion logic (``pipeline.tracking.deletion``): ``FixedDeletion``, ``YoungMatureDeletion`` (Sec. III-C, V-C);
* duplicate guards (``pipeline.tracking.duplicates``): ``DuplicateGuard``, SPENCER's, or none.

Each part declares its own parameters; in a scenario each is named by type (``motion: {type: cv, process_noise:
0.267}``), and the keys of the tracker before its parts were named still load (scenarios/format.py). The defaults
are the tracker as it was before these choices existed (CV, greedy, count initiation, fixed deletion, no guards):
Table II's "Greedy NN" row with the settings the parts' parameters explain.

One cycle (``NearestNeighbourTracker.update``), every step batched over all tracks (a struct of numpy arrays with the
tracks on the last axis, so that numpy's inner loops run over the tracks, not over 2 to 7 state components; packed
in two buffers, ``TrackColumns``):

1. predict   -- the filter's prediction by dt = stamp - previous stamp (with an IMM: mixing first).
2. gate      -- squared Mahalanobis distance of the (track, detection) pairs from the track's combined estimate
                (in a crowd only those that can lie within the gate: ``gated_mahalanobis``); pairs beyond
                the association's ``gate_chi2`` are not allowed.
3. associate -- confirmed tracks choose by the association; initiation candidates (tentative tracks)
                only get the detections left over (Alg. 1 works on the unmatched detections Z^u), by greedy NN and,
                with an initiation logic, only those that pass its velocity gate.
4. update    -- Kalman update of all matched tracks at once (each model's, with an IMM, and its mode probabilities).
5. delete    -- unmatched tracks coast on their prediction; the consecutive-miss counter grows; the deletion logic
                says when a track goes.
6. initiate  -- every detection left over starts a candidate at its position with zero velocity and the initiation
                logic's ``initial_velocity_variance``; the logic says when a candidate is confirmed; the duplicate
                guards, when given, drop tracks on one person and detections next to a track.

Choices:

* Track ids are handed out from a counter starting at 1 **when a track is confirmed**, so output ids are
  consecutive (1, 2, 3, ...) and do not depend on how many false-alarm candidates came and went. A track keeps its
  id until it is deleted; ids are never reused (``reset`` restarts the counter).
* ``age`` is the time since the track's first detection (its creation as a candidate), in seconds.
* Only confirmed tracks are output, sorted by track id, with the combined estimate (with an IMM, the
  mode-weighted mixture's mean and covariance). ``is_occluded`` is ``not is_matched``.
* Stamps must not decrease (ValueError); the first cycle (or one with equal stamp) does no prediction.
* Detections must be in the tracker's frame, with finite x/y and a positive-definite x/y covariance (ValueError).
* Ties in cost are broken by (track row, detection index), so results are deterministic; there is no randomness.
* Defaults q_L = 0.267 m^2/s^3 and gate 13.82 favour holding tracks through turns over smooth velocities; the
  reasons and measurements are in their declarations (``motion.PROCESS_NOISE``, ``association._Gated``). Known
  limit of greedy NN: two people whose detections coincide can swap tracks (about 1 % of 90-degree X crossings at
  1.3 m/s, 25 Hz, sigma 0.03-0.05 m).
* Speed (``bench_cycles``, ``crowdsim bench``): with 80 tracks the state is some 50 kB, so a cycle's cost is
  numpy's per call (a microsecond or two each, a few hundred calls a cycle), not its arithmetic; the steps are
  written to make few calls, and give bit for bit the numbers of their plainer forms.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from pipeline.types import DetectedPersons, TrackedPersons

from .association import ASSOCIATIONS, checked_detections, gated_mahalanobis
from .deletion import DELETIONS
from .duplicates import DUPLICATES
from .imm import MOTION, as_filter
from .initiation import INITIATIONS
from ..params import Slot, made

__all__ = ["TrackColumns", "NearestNeighbourTracker", "CycleRate", "bench_detections", "bench_cycles"]


class TrackColumns:
    """Per-track arrays, tracks last, packed as the rows of one float and one integer buffer [rows, tracks].

    Why: with clutter, candidates are born and dropped every cycle, and selecting or extending each of a dozen
    arrays took a large share of a cycle (numpy's cost per call, not the bytes: 80 tracks of a 4-state IMM are 50 kB).
    Packed, a death is one ``take`` and a birth one ``concatenate`` per buffer, and each field is a contiguous view
    of its rows, as fast to compute on as an array of its own.
    """

    def __init__(self, floats: dict[str, tuple[int, ...]], ints: tuple[str, ...]):
        """``floats``: name -> each track's shape of the float arrays; ``ints``: names of the int64 scalars."""
        self._at = {}  # name -> (buffer, its row or rows, each track's shape)
        size = [0, 0]
        for b, fields in enumerate((floats, dict.fromkeys(ints, ()))):
            for name, shape in fields.items():
                n_rows = int(np.prod(shape))
                self._at[name] = (b, slice(size[b], size[b] + n_rows) if shape else size[b], shape)
                size[b] += n_rows
        self._buf = [np.zeros((size[0], 0)), np.zeros((size[1], 0), np.int64)]
        self._view: dict[str, np.ndarray] | None = None

    @property
    def n(self) -> int:
        """Tracks held."""
        return self._buf[0].shape[1]

    def view(self) -> dict[str, np.ndarray]:
        """Each field of the tracks held, [*shape, n]: writable views, valid until the next ``keep`` or ``add``."""
        if self._view is None:  # (a scalar's row is a view as it is, and some 3 times quicker to make)
            self._view = {name: self._buf[b][rows].reshape(*shape, -1, copy=False) if shape else self._buf[b][rows]
                          for name, (b, rows, shape) in self._at.items()}
        return self._view

    def keep(self, index: np.ndarray) -> None:
        """Keep only the tracks at ``index`` (ascending)."""
        self._buf = [buf.take(index, 1) for buf in self._buf]
        self._view = None

    def add(self, k: int) -> slice:
        """k new tracks after the others, all zero; their columns."""
        n = self.n
        self._buf = [np.concatenate([buf, np.zeros((buf.shape[0], k), buf.dtype)], 1) for buf in self._buf]
        self._view = None
        return slice(n, n + k)


# ----------------------------------------------------------------------------------------------------------------
# The tracker
# ----------------------------------------------------------------------------------------------------------------


class NearestNeighbourTracker:
    """Nearest-neighbour Kalman tracker; all track state lives in parallel numpy arrays, the tracks on their last
    axis (a struct of arrays: the loops of every batched step run over the tracks)."""

    PARTS = {
        "motion": MOTION,
        "association": Slot(ASSOCIATIONS, "greedy", ("assign",),
                            "how confirmed tracks choose detections, within its gate: greedy NN, global NN "
                            "(Jonker-Volgenant) or NN with several tracks per detection (seed 000 Sec. II-B, V-A, "
                            "Table II)", "association"),
        "initiation": Slot(INITIATIONS, "none", (),
                           "which candidates become tracks, and how they start: none (after n_confirm detections), "
                           "base (speed from the latest detection in [v_min, v_max]) or extended (from every earlier "
                           "one), seed 000 Alg. 1, Sec. V-B", "initiation logic"),
        "deletion": Slot(DELETIONS, "fixed", ("limits",),
                         "when a track without detections goes: fixed (n_delete misses) or young_mature (seed 000 "
                         "Sec. III-C)", "deletion logic"),
        "duplicates": Slot(DUPLICATES, None, ("duplicates", "blocked"),
                           "guards against two tracks on one person (the SPENCER NNT's; seed 000 has none); left "
                           "out or null: none", "duplicate guard"),
    }
    """The parts it is given, each a slot: the built-in types by name and the default (``params.Slot``)."""

    def __init__(self, motion=None, association=None, initiation=None, deletion=None, duplicates=None,
                 frame: str = "odom"):
        """Each part an object (or its specification, a mapping of ``type`` and parameters, as a scenario gives it);
        left out, the slot's default with its own defaults (no duplicate guards)."""
        self.motion, self.association, self.initiation, self.deletion, self.duplicates = (
            made(part, self.PARTS[name]) for name, part in zip(self.PARTS, (motion, association, initiation,
                                                                             deletion, duplicates)))
        self.frame = frame
        self._filter = as_filter(self.motion)
        self.reset()

    # -- state --------------------------------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget all tracks and the last stamp; the id counter restarts at 1."""
        L, guard = self.initiation.history, self.duplicates
        floats = {**self._filter.shapes,  # the filter's: x, P (, mu)
                  "created": (),  # stamp of the first detection
                  **({"hist": (3, L)} if L else {}),  # a candidate's detections (x, y, stamp), for the velocity gate
                  # the predicted positions of the last cycles, latest last, for the duplicate deletion
                  **({"past": (guard.history, 2)} if guard is not None and guard.distance > 0.0 else {})}
        ints = ("id",  # track id, 0 while a candidate
                "hits",  # detections matched over the lifetime (creating one included)
                "misses",  # consecutive cycles without a detection
                "det",  # detection id matched this cycle, -1 for none
                "filled")  # how many of the past positions a track has
        self._tracks = TrackColumns(floats, ints)
        self._t = self._tracks.view()
        self._next_id = 1
        self._stamp: float | None = None

    @property
    def num_tracks(self) -> int:
        """Tracks held, candidates included."""
        return self._tracks.n

    # -- one cycle ----------------------------------------------------------------------------------------------

    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        """Run one tracking cycle with the detections at ``stamp``; returns the confirmed tracks."""
        z, R, det_ids = checked_detections(stamp, detections, self.frame, self._stamp)
        stamp = float(stamp)
        dt = 0.0 if self._stamp is None else stamp - self._stamp
        self._stamp = stamp
        t = self._t
        if dt > 0.0 and self._tracks.n:
            for key, v in self._filter.predict(t, dt).items():
                t[key][...] = v
        xy, Pxy = self._filter.estimate(t, 2)
        if "past" in t and self._tracks.n:  # the predicted positions of the last cycles, for the duplicate deletion
            t["past"][:-1] = t["past"][1:].copy()
            t["past"][-1] = xy
            t["filled"] += 1

        rows, cols = self._associate(stamp, z, R, xy, Pxy)
        self._update_matched(stamp, rows, cols, z, R, det_ids)
        self._delete()
        self._initiate(stamp, cols, z, R, det_ids)
        self._t = self._tracks.view()
        self._confirm()
        return self._output(stamp)

    def _associate(self, stamp: float, z: np.ndarray, R: np.ndarray, xy: np.ndarray,
                   Pxy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gate (the tracks' predicted positions xy [2, n] and covariances Pxy [2, 2, n]); confirmed tracks choose by
        the association, candidates after them by greedy NN on what is left (through the initiation logic's
        velocity gate, if it has one)."""
        t, gate = self._t, self.association.gate_chi2
        if self._tracks.n == 0 or z.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        d2 = gated_mahalanobis(xy.T, Pxy.transpose(2, 0, 1), z, R, gate)
        later = t["id"] == 0
        cand = np.flatnonzero(later)
        if cand.size == 0:
            return self.association.assign(d2)
        if self.initiation.history:  # the candidates' pairs within the gate must pass the velocity gate too
            r, c = np.nonzero(d2.take(cand, 0) <= gate)
            if r.size:
                r = cand.take(r)
                bad = ~self.initiation.velocity_ok(t["hist"].take(r, -1), t["hits"].take(r), z.take(c, 0), stamp)
                d2[r[bad], c[bad]] = np.inf
        return self.association.assign(d2, later)

    def _update_matched(self, stamp, rows, cols, z, R, det_ids) -> None:
        t = self._t
        t["misses"] += 1
        t["det"][:] = -1
        if rows.size:
            for key, v in self._filter.update({key: t[key].take(rows, -1) for key in self._filter.keys},
                                              z.take(cols, 0), R.take(cols, 0)).items():
                t[key][..., rows] = v
            t["misses"][rows] = 0
            if self.initiation.history:  # a candidate keeps its detections for the velocity gate
                cand = t["id"].take(rows) == 0
                if cand.any():
                    r = rows[cand]
                    k = t["hits"].take(r)
                    t["hist"][:2, k, r] = z.take(cols[cand], 0).T
                    t["hist"][2, k, r] = stamp
            t["hits"][rows] += 1
            t["det"][rows] = det_ids.take(cols)

    def _delete(self) -> None:
        t = self._t
        kept = t["misses"] < self.deletion.limits(t["id"] != 0, t["hits"])
        if "past" in t:
            kept &= ~self.duplicates.duplicates(t["past"], t["filled"], t["hits"])
        keep = np.flatnonzero(kept)
        if keep.size < self._tracks.n:
            self._tracks.keep(keep)

    def _initiate(self, stamp, used_cols, z, R, det_ids) -> None:
        """A new candidate for every detection no track took: position from it, velocity 0."""
        free = np.ones(z.shape[0], bool)
        free[used_cols] = False
        guard = self.duplicates
        if guard is not None and guard.clearance > 0.0 and self._tracks.n and free.any():
            t = self._tracks.view()  # (after the deletions)
            free[free] = ~guard.blocked(z[free], self._filter.estimate(t, 2)[0], t["misses"])
        k = int(np.count_nonzero(free))
        if k == 0:
            return
        zf = z[free]
        new = self._tracks.add(k)  # all zero: id 0 (a candidate), no misses
        t = self._tracks.view()
        self._filter.start(zf, R[free], self.initiation.initial_velocity_variance,
                           {key: t[key][..., new] for key in self._filter.keys})
        t["hits"][new] = 1
        t["created"][new] = stamp
        t["det"][new] = det_ids[free]
        if self.initiation.history:
            t["hist"][:2, 0, new] = zf.T
            t["hist"][2, 0, new] = stamp

    def _confirm(self) -> None:
        """Candidates with the detections the initiation logic needs are confirmed and get the next ids (in row
        order)."""
        t = self._t
        new = (t["id"] == 0) & (t["hits"] >= self.initiation.needed)
        k = int(np.count_nonzero(new))
        if k:
            t["id"][new] = np.arange(self._next_id, self._next_id + k)
            self._next_id += k

    def _output(self, stamp: float) -> TrackedPersons:
        t = self._t
        idx = np.flatnonzero(t["id"])  # the confirmed (a candidate's id is 0)
        ids = t["id"].take(idx)
        order = np.argsort(ids, kind="stable")
        idx, ids = idx.take(order), ids.take(order)
        x, P = self._filter.estimate({key: t[key].take(idx, -1) for key in self._filter.keys}, 4)
        matched = t["misses"].take(idx) == 0
        return TrackedPersons(
            stamp=stamp,
            frame=self.frame,
            track_id=ids,
            is_matched=matched,
            is_occluded=~matched,
            detection_id=t["det"].take(idx),
            position=x[:2].T.copy(),
            velocity=x[2:4].T.copy(),
            position_covariance=P[:2, :2].transpose(2, 0, 1).copy(),
            velocity_covariance=P[2:4, 2:4].transpose(2, 0, 1).copy(),
            age=stamp - t["created"].take(idx),
        )


class CycleRate(NamedTuple):
    """What ``bench_cycles`` measured."""

    cycles_per_s: float
    """Tracking cycles per second: the median of the timed blocks."""

    tracks: float
    """Confirmed tracks handed out per timed cycle, on average: the load the rate was measured at."""


def bench_detections(n_tracks: int, miss_rate: float = 0.0, false_alarms: int = 0, count: int = 250,
                     seed: int = 0) -> list[DetectedPersons]:
    """``count`` cycles of detections at 25 Hz of ``n_tracks`` people walking straight at 1.3 m/s from uniform
    starts in 30 x 30 m (uniform headings), detected with sigma 0.05 m (R = 0.1 m^2, seed 000 Sec. IV-C), each
    missed with probability ``miss_rate``, plus ``false_alarms`` detections uniform in the square per cycle (after
    the people's)."""
    rng = np.random.default_rng(seed)
    dt = 0.04
    start = rng.uniform(0, 30, (n_tracks, 2))
    heading = rng.uniform(-np.pi, np.pi, n_tracks)
    vel = 1.3 * np.stack([np.cos(heading), np.sin(heading)], 1)
    frames = []
    for k in range(count):
        xy = start + vel * k * dt + rng.normal(0, 0.05, (n_tracks, 2))
        xy = np.concatenate([xy[rng.random(n_tracks) >= miss_rate], rng.uniform(0, 30, (false_alarms, 2))])
        m = len(xy)
        cov = np.zeros((m, 3, 3))
        cov[:, 0, 0] = cov[:, 1, 1] = 0.1
        cov[:, 2, 2] = 1e6
        pos = np.concatenate([xy, np.zeros((m, 1))], 1)
        frames.append(DetectedPersons(k * dt, "odom", "laser2d", np.arange(m) + k * 1000, pos, cov, np.ones(m)))
    return frames


def bench_cycles(n_tracks: int, config: dict | None = None, miss_rate: float = 0.0, false_alarms: int = 0,
                 cycles: int = 200, blocks: int = 5, warm: int = 50) -> CycleRate:
    """Tracking cycles per second of the tracker ``config`` on ``bench_detections(n_tracks, miss_rate,
    false_alarms)``: the median of ``blocks`` timed blocks of ``cycles``, after ``warm`` untimed cycles that confirm
    the tracks. ``config``: a tracker spec as Table II's (``type`` nnt or mht and its parameters, in either of the
    scenario format's spellings; nnt when left out). The detections are made before the clock starts."""
    from pipeline.assemble import TRACKERS, build_part  # (they import this module)
    from scenarios.format import TRACKER
    from scenarios.schema import validate

    spec = validate({"type": "nnt", **(config or {})}, TRACKER, "<bench>", "tracker")
    tracker = build_part(spec, TRACKERS)
    frames = bench_detections(n_tracks, miss_rate, false_alarms, warm + cycles * blocks)
    for f in frames[:warm]:
        tracker.update(f.stamp, f)
    rates, held = [], 0
    for b in range(blocks):
        t0 = time.perf_counter()
        for f in frames[warm + b * cycles: warm + (b + 1) * cycles]:
            held += len(tracker.update(f.stamp, f))
        rates.append(cycles / (time.perf_counter() - t0))
    return CycleRate(float(np.median(rates)), held / (cycles * blocks))
