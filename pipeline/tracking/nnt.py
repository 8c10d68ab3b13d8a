"""Nearest-neighbour people tracker on the ground plane (the SPENCER NNT, seed 000 Sec. II-B, III, V, Table II).

Why: the testbed needs a fast, deterministic multi-person tracker that turns per-frame detections (already in the
locally fixed tracking frame, e.g. ``odom``) into persistent person tracks with ids, so that CLEAR-MOT can score the
perception pipeline. The seed paper's tracker is a Kalman filter per person with nearest-neighbour data association
on the Mahalanobis distance, made robust in crowds by a few cheap extensions (Sec. III); it runs at kHz (Table II).
Each part is chosen by the scenario (``TrackerParams``), so Table II's rows are configurations of this one tracker:

* motion model (``pipeline.tracking.motion``, ``.imm``): ``cv`` (Eq. 1-2), ``ca``, ``ct`` (an EKF), ``brownian``,
  or ``imm`` over a list of them (Sec. III-A, V-D);
* association (``pipeline.tracking.association``): ``greedy``, ``global``, ``multi`` (Sec. II-B, V-A);
* initiation logic (``pipeline.tracking.initiation``): ``none``, ``base``, ``extended`` (Sec. III-B, Alg. 1, V-B);
* deletion logic (``pipeline.tracking.deletion``): ``fixed``, ``young_mature`` (Sec. III-C, V-C).

The defaults are the tracker as it was before these choices existed (CV, greedy, ``none``, ``fixed``): Table II's
"Greedy NN" row with the settings ``TrackerParams`` explains. One cycle (``NearestNeighbourTracker.update``), every
step batched over all tracks (a struct of numpy arrays with the tracks on the last axis, so that numpy's inner loops
run over the tracks, not over 2 to 7 state components; packed in two buffers, ``TrackColumns``):

1. predict   -- the filter's prediction by dt = stamp - previous stamp (with an IMM: mixing first).
2. gate      -- squared Mahalanobis distance of the (track, detection) pairs from the track's combined estimate
                (in a crowd only those that can lie within the gate: ``gated_mahalanobis``); pairs beyond
                ``gate_chi2`` are not allowed.
3. associate -- confirmed tracks choose by the configured association; initiation candidates (tentative tracks)
                only get the detections left over (Alg. 1 works on the unmatched detections Z^u), by greedy NN and,
                with an initiation logic, only those that pass its velocity gate.
4. update    -- Kalman update of all matched tracks at once (each model's, with an IMM, and its mode probabilities).
5. delete    -- unmatched tracks coast on their prediction; the consecutive-miss counter grows; the deletion logic
                says when a track goes.
6. initiate  -- every detection left over starts a candidate at its position with zero velocity and variance
                ``initial_velocity_variance``; the initiation logic says when a candidate is confirmed.

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
  reasons and measurements are in ``TrackerParams``. Known limit of greedy NN: two people whose detections
  coincide can swap tracks (about 1 % of 90-degree X crossings at 1.3 m/s, 25 Hz, sigma 0.03-0.05 m).
* Speed (``bench_cycles``, ``crowdsim bench``): with 80 tracks the state is some 50 kB, so a cycle's cost is
  numpy's per call (a microsecond or two each, a few hundred calls a cycle), not its arithmetic; the steps are
  written to make few calls, and give bit for bit the numbers of their plainer forms.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from pipeline.types import DetectedPersons, TrackedPersons

from .association import ASSOCIATIONS, checked_detections, gated_mahalanobis
from .deletion import DELETIONS, DeletionLogic
from .duplicates import DuplicateGuard
from .imm import IMM
from .initiation import INITIATIONS, InitiationLogic
from .motion import MODELS, make_model, state_layout

__all__ = ["TrackerParams", "TrackColumns", "NearestNeighbourTracker", "CycleRate", "bench_detections",
           "bench_cycles"]

TURN_RATE_NOISE = 1.0  # rad^2/s^3, the CT model's default (TrackerParams.turn_rate_noise says why)


@dataclass
class TrackerParams:
    """Parameters of the nearest-neighbour tracker (units: metres, seconds)."""

    process_noise: float = 0.267
    """q_L of seed 000 Eq. 2 (m^2/s^3): spectral density of the white-noise acceleration per axis (the velocity
    variance grows by q_L per second of prediction). Seed 000 Sec. V-D tuned an IMM of two CV models to 0.035 (smooth
    walking) and 0.267 (manoeuvres); a single CV model has to survive turns and stops on its own, so it takes the
    manoeuvre level. Check on a synthetic crowd (30 and 80 walkers at ~1.3 m/s in 30 x 30 m, heading random walk
    0.5 rad/sqrt(s), smooth turns at the walls, 25 Hz, sigma 0.05 m, 5 % misses, 1 false alarm per frame, 60 s;
    gate 13.82): q_L = 0.035 lost tracks at turns and gave 101 / 268 ID switches (30 / 80 walkers), q_L = 0.1
    gave 19 / 51, q_L = 0.267 gave 9 / 21; the velocity RMSE hardly changed (0.21-0.25 m/s per axis).
    Cost: on a walker at exactly constant velocity the velocity estimate is noisier than with a small q_L (at
    25 Hz and sigma 0.02 m the filter's own per-axis velocity std is 0.17 m/s); use a smaller value (or an IMM)
    where smooth velocities matter more than holding tracks through turns. With another single ``motion`` model,
    the density of its own white noise (``pipeline.tracking.motion``: m^2/s^5 for ca, m^2/s for brownian)."""

    gate_chi2: float = 13.82
    """Mahalanobis gate on the 2D innovation: the chi-square 0.999 quantile for 2 degrees of freedom. The 0.99
    quantile (9.21) rejects 1 % of a track's own detections, about one every 4 s per person at 25 Hz; early in a
    track's life, with a velocity still uncertain, such a rejection often loses the track. On the synthetic crowd
    (see ``process_noise``) 13.82 cut the ID switches from 25 to 9 (30 walkers) and 65 to 21 (80 walkers) at
    q_L = 0.267; the gate only bounds which pairs may match, greedy NN still takes the nearest first."""

    n_confirm: int = 3
    """Detections (the creating one included) needed to confirm a tentative track."""

    n_delete: int = 5
    """Consecutive misses that delete a confirmed track (seed 000 Sec. V-C: n_del = 5 in the base NNT)."""

    n_delete_tentative: int = 2
    """Consecutive misses that delete a tentative track."""

    initial_velocity_variance: float = 1.0
    """Per-axis velocity variance (m^2/s^2) of a new track, whose velocity is unknown. A walker at ~1.3 m/s with a
    uniformly random heading has E[vx^2] = 1.3^2 / 2 = 0.845 m^2/s^2; rounded up to 1.0 to cover faster walkers."""

    association: str = "greedy"
    """How confirmed tracks choose detections (``pipeline.tracking.association``): ``greedy``, ``global`` or
    ``multi``. Greedy NN: the base NNT of seed 000 Table II, and within 0.1 % MOTA of the optimal global NN there
    (Sec. V-A)."""

    initiation: str = "none"
    """Track initiation logic (``pipeline.tracking.initiation``): ``none`` (confirmed after ``n_confirm``
    detections, no velocity gate: the base NNT), ``base`` or ``extended`` (seed 000 Alg. 1, Sec. V-B)."""

    n_min: int = 6
    """Detections that confirm a candidate under the ``base`` and ``extended`` logic (seed 000 Sec. V-B: 6)."""

    v_min: float = 0.2
    """m/s, slowest speed between a candidate's detections (seed 000 Sec. V-B: [v_min, v_max] = [0.2, 2])."""

    v_max: float = 2.0
    """m/s, fastest speed between a candidate's detections (seed 000 Sec. V-B: 2)."""

    position_slack: float = 0.1
    """m, detection noise allowed on top of v_max * dt by the velocity gate. Seed 000 gives no value. On
    airport_disembarkation (laser_segments, 20 s, 15,000 detections) the error of a person's detection changed from
    one cycle to the next by 1.6 cm (median), 4.9 cm (90 %) and 9.3 cm (99 %): 0.1 m lets 99 % of such steps through,
    where a walker at 1.3 m/s moves only 5.2 cm per 25 Hz cycle."""

    deletion: str = "fixed"
    """Track deletion logic (``pipeline.tracking.deletion``): ``fixed`` (after ``n_delete`` misses) or
    ``young_mature`` (seed 000 Sec. III-C)."""

    n_delete_young: int = 20
    """Consecutive misses that delete a young confirmed track under ``young_mature`` (seed 000 Sec. V-C: 20)."""

    n_delete_mature: int = 50
    """Consecutive misses that delete a mature track under ``young_mature`` (seed 000 Sec. V-C: 50)."""

    mature_after: int = 100
    """Detections over its life (the creating one included) that make a track mature (seed 000 Sec. V-C: 100)."""

    motion: str = "cv"
    """Motion model (``pipeline.tracking.motion``): ``cv`` (seed 000 Eq. 1-2), ``ca``, ``ct``, ``brownian``, each
    with ``process_noise`` (and ``turn_rate_noise`` for ``ct``), or ``imm`` over ``imm_models``."""

    turn_rate_noise: float = TURN_RATE_NOISE
    """rad^2/s^3, density of the white noise on the CT model's turn rate. Seed 000 gives no value: a walker's turn
    rate changes by about 1 rad/s within about 1 s (a corner), so 1.0."""

    imm_models: list = field(default_factory=lambda: [
        {"model": "cv", "process_noise": 0.035, "turn_rate_noise": TURN_RATE_NOISE},
        {"model": "cv", "process_noise": 0.267, "turn_rate_noise": TURN_RATE_NOISE}])
    """The IMM's models, each {model, process_noise, turn_rate_noise} as the single-model keys. Seed 000 Sec. V-D,
    Table II "+IMM (CV + CV)": two CV models with q_L = 0.035 (walking) and 0.267 (manoeuvres)."""

    imm_transition: list = field(default_factory=lambda: [0.95, 0.05, 0.05, 0.95])
    """The IMM's Markov matrix, row-major: entry (i, j) is the probability that a person moving by model i at one
    cycle moves by model j at the next; each row sums to 1. Seed 000 gives none: 0.95 to stay keeps a mode for 20
    cycles (0.8 s at 25 Hz) on average, about as long as a walker's turn or stop."""

    duplicate_distance: float = 0.0
    """m; 0 turns it off. Two tracks this close in 7 of their last 10 cycles are one person's, and the one matched
    fewer times goes (``pipeline.tracking.duplicates``: the SPENCER NNT's duplicate deletion, 0.15 m there). Off by
    default: the tracker as it was; Table II's rows and the airport turn it on."""

    new_track_clearance: float = 0.0
    """m; 0 turns it off. A detection no track took starts no candidate this close to a track or candidate matched in
    the last 5 cycles (the SPENCER NNT's check for a close-by track, 0.25 m there)."""

    def __post_init__(self) -> None:
        if not (self.process_noise >= 0.0 and np.isfinite(self.process_noise)):
            raise ValueError(f"process_noise must be finite and >= 0, got {self.process_noise}")
        if not self.gate_chi2 > 0.0:
            raise ValueError(f"gate_chi2 must be > 0, got {self.gate_chi2}")
        for name in ("n_confirm", "n_delete", "n_delete_tentative", "n_delete_young", "n_delete_mature",
                     "mature_after"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not (self.initial_velocity_variance > 0.0 and np.isfinite(self.initial_velocity_variance)):
            raise ValueError(f"initial_velocity_variance must be finite and > 0, got {self.initial_velocity_variance}")
        for name, allowed in (("association", tuple(ASSOCIATIONS)), ("initiation", INITIATIONS),
                              ("deletion", DELETIONS), ("motion", (*MODELS, "imm"))):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, got {getattr(self, name)!r}")
        if int(self.n_min) < 2:
            raise ValueError(f"n_min must be >= 2 (the velocity gate needs two detections), got {self.n_min}")
        if not (0.0 <= self.v_min < self.v_max and np.isfinite(self.v_max)):
            raise ValueError(f"need 0 <= v_min < v_max < inf, got v_min {self.v_min}, v_max {self.v_max}")
        if not (self.position_slack >= 0.0 and np.isfinite(self.position_slack)):
            raise ValueError(f"position_slack must be finite and >= 0, got {self.position_slack}")
        for name in ("duplicate_distance", "new_track_clearance"):
            if not (getattr(self, name) >= 0.0 and np.isfinite(getattr(self, name))):
                raise ValueError(f"{name} must be finite and >= 0, got {getattr(self, name)}")
        if not (self.turn_rate_noise >= 0.0 and np.isfinite(self.turn_rate_noise)):
            raise ValueError(f"turn_rate_noise must be finite and >= 0, got {self.turn_rate_noise}")
        self.imm_models = [{"turn_rate_noise": TURN_RATE_NOISE, **m} for m in self.imm_models]
        for i, m in enumerate(self.imm_models):
            if set(m) != {"model", "process_noise", "turn_rate_noise"} or m["model"] not in MODELS:
                raise ValueError(f"imm_models[{i}] must be {{model: one of {', '.join(MODELS)}, process_noise, "
                                 f"turn_rate_noise (optional)}}, got {m!r}")
            if not (m["process_noise"] >= 0.0 and m["turn_rate_noise"] >= 0.0):
                raise ValueError(f"imm_models[{i}]: process_noise and turn_rate_noise must be >= 0, got {m!r}")
        k = len(self.imm_models)
        T = np.asarray(self.imm_transition, float)
        if (k < 1 or T.shape != (k * k,) or not (T >= 0.0).all() or not np.allclose(T.reshape(k, k).sum(1), 1.0)
                or not (T.reshape(k, k).sum(0) > 0.0).all()):
            raise ValueError(f"imm_transition must be the {k} x {k} Markov matrix of the {k} imm_models, row-major "
                             f"({k * k} numbers >= 0, each row of {k} summing to 1, each model reachable: a "
                             f"positive entry in each column), got {self.imm_transition!r}")


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

    def __init__(self, frame: str = "odom", **params):
        """``params``: the keywords of ``TrackerParams`` (its defaults for those left out)."""
        self.params = p = TrackerParams(**params)
        self.frame = frame
        single = {"model": p.motion, "process_noise": p.process_noise, "turn_rate_noise": p.turn_rate_noise}
        specs = p.imm_models if p.motion == "imm" else [single]
        layout = state_layout([s["model"] for s in specs])
        models = [make_model(s["model"], layout, s["process_noise"], s["turn_rate_noise"]) for s in specs]
        k = len(models)
        self._filter = IMM(models, np.reshape(p.imm_transition, (k, k)) if p.motion == "imm" else None)
        self._assign = ASSOCIATIONS[p.association]
        self._initiation = InitiationLogic(p.initiation, p.n_confirm, p.n_min, p.v_min, p.v_max, p.position_slack)
        self._deletion = DeletionLogic(p.deletion, p.n_delete, p.n_delete_tentative, p.n_delete_young,
                                       p.n_delete_mature, p.mature_after)
        self._guard = DuplicateGuard(distance=p.duplicate_distance, clearance=p.new_track_clearance)
        self.reset()

    # -- state --------------------------------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget all tracks and the last stamp; the id counter restarts at 1."""
        L = self._initiation.history
        floats = {**self._filter.shapes,  # the filter's: x, P (, mu)
                  "created": (),  # stamp of the first detection
                  **({"hist": (3, L)} if L else {}),  # a candidate's detections (x, y, stamp), for the velocity gate
                  # the predicted positions of the last cycles, latest last, for the duplicate deletion
                  **({"past": (self._guard.history, 2)} if self._guard.distance > 0.0 else {})}
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
        the configured association, candidates after them by greedy NN on what is left (through the initiation
        logic's velocity gate, if it has one)."""
        t, gate = self._t, self.params.gate_chi2
        if self._tracks.n == 0 or z.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        d2 = gated_mahalanobis(xy.T, Pxy.transpose(2, 0, 1), z, R, gate)
        later = t["id"] == 0
        cand = np.flatnonzero(later)
        if cand.size == 0:
            return self._assign(d2, gate)
        if self._initiation.history:  # the candidates' pairs within the gate must pass the velocity gate too
            r, c = np.nonzero(d2.take(cand, 0) <= gate)
            if r.size:
                r = cand.take(r)
                bad = ~self._initiation.velocity_ok(t["hist"].take(r, -1), t["hits"].take(r), z.take(c, 0), stamp)
                d2[r[bad], c[bad]] = np.inf
        return self._assign(d2, gate, later)

    def _update_matched(self, stamp, rows, cols, z, R, det_ids) -> None:
        t = self._t
        t["misses"] += 1
        t["det"][:] = -1
        if rows.size:
            for key, v in self._filter.update({key: t[key].take(rows, -1) for key in self._filter.keys},
                                              z.take(cols, 0), R.take(cols, 0)).items():
                t[key][..., rows] = v
            t["misses"][rows] = 0
            if self._initiation.history:  # a candidate keeps its detections for the velocity gate
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
        kept = t["misses"] < self._deletion.limits(t["id"] != 0, t["hits"])
        if "past" in t:
            kept &= ~self._guard.duplicates(t["past"], t["filled"], t["hits"])
        keep = np.flatnonzero(kept)
        if keep.size < self._tracks.n:
            self._tracks.keep(keep)

    def _initiate(self, stamp, used_cols, z, R, det_ids) -> None:
        """A new candidate for every detection no track took: position from it, velocity 0."""
        free = np.ones(z.shape[0], bool)
        free[used_cols] = False
        if self._guard.clearance > 0.0 and self._tracks.n and free.any():
            t = self._tracks.view()  # (after the deletions)
            free[free] = ~self._guard.blocked(z[free], self._filter.estimate(t, 2)[0], t["misses"])
        k = int(np.count_nonzero(free))
        if k == 0:
            return
        zf = z[free]
        new = self._tracks.add(k)  # all zero: id 0 (a candidate), no misses
        t = self._tracks.view()
        self._filter.start(zf, R[free], self.params.initial_velocity_variance,
                           {key: t[key][..., new] for key in self._filter.keys})
        t["hits"][new] = 1
        t["created"][new] = stamp
        t["det"][new] = det_ids[free]
        if self._initiation.history:
            t["hist"][:2, 0, new] = zf.T
            t["hist"][2, 0, new] = stamp

    def _confirm(self) -> None:
        """Candidates with the detections the initiation logic needs are confirmed and get the next ids (in row
        order)."""
        t = self._t
        new = (t["id"] == 0) & (t["hits"] >= self._initiation.needed)
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
    the tracks. ``config``: a tracker spec as Table II's (``type`` nnt or mht and its parameters; nnt when left out).
    The detections are made before the clock starts."""
    from pipeline.assemble import TRACKERS, build_part  # (it imports this module)

    tracker = build_part({"type": "nnt", **(config or {})}, TRACKERS)
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
