"""Seed 003's tracker (Munaro & Menegatti 2014, "Fast RGB-D people tracking for service robots", Sec. 3.2): a
constant-velocity Kalman filter per person on the floor, global nearest-neighbour association on a three-term joint
cost (motion, colour, detector), and a per-track online-boosted colour classifier.

* **Motion.** State (x, y, vx, vy), constant velocity, white acceleration (Q = q G G^T, G = (dt^2 / 2, dt) per axis,
  as the authors' OpenPTrack). The paper runs an unscented Kalman filter; with this linear model and a linear
  (position) measurement the unscented transform is exact, so the UKF *is* this Kalman filter.
* **Motion term** (Eq. 3-4): the squared Mahalanobis distance D_M over position and velocity (4 dof), the measured
  velocity being the one the track would have if the detection were its own: (z_j - p_ref) / (t - t_ref), p_ref the
  track's filtered position at its reference time, about ``velocity_lag`` s back (between one and two lags once the
  track is that old, as OpenPTrack; its first position before). Its noise follows from z_j's and p_ref's, with the
  cross-covariance R_j / L between measured position and velocity (L the lag). ``use_velocity: false`` gates on
  position only (2 dof), the switch of the paper's RGB-D People test (L680). The filter itself is corrected with the
  position only: the velocity "measurement" reuses the track's own past and would count it twice.
* **Gate**: D_M above the chi-square quantile of ``gate_probability`` (4 or 2 dof) forbids a pair.
* **Joint cost** (Eq. 6, signs so that confident pairs cost less; OpenPTrack's ``detector_weight: -1`` reads Eq. 6
  the same way): cost_ij = gamma D_M - alpha c_online_ij - beta c_HOG_j. One Munkres assignment (scipy) per cycle
  takes the most allowed pairs, then the least total cost among them (the forbidden pairs cost more than any set of
  allowed ones), as OpenPTrack's gated Munkres.
* **Colour** (Sec. 3.2.1): every track has an ``OnlineColourClassifier``. A track learns its detection's histogram
  as a positive, the frame's other detections' and ``random_windows`` random windows of the latest camera image
  (``see``) as negatives (Fig. 8b): when it starts, then (with ``learn``) again each ``learn_interval`` s, one track
  a cycle, the one waiting longest. How often the paper's tracks learn is not given; learning every track every cycle
  (``learn_interval: 0``) costs n (m + windows) classifier updates of about 0.5 ms each, some 35 ms a cycle for five
  people, where one track's learning (some 7 ms) every sixth cycle keeps five people at about 2 ms a cycle on
  average. ``learn: false`` keeps every classifier as its first learning left it (the fixed-classifier ablation,
  L582).
* **Tracks**: an unassociated detection with c_HOG >= ``init_confidence`` starts one; it is reported once
  ``confirm`` of its detections reached that confidence, and dropped if that takes longer than ``confirm_time`` s
  (OpenPTrack's validation: ``detections_to_validate`` 3, ``sec_before_fake`` 2.4 s, tracker.yaml). A track without
  a detection for ``max_missed_time`` s is deleted (OpenPTrack's ``sec_before_old``, 8 s in tracker.yaml): until
  then its growing covariance lets a returning person take it up again. A track is reported while its latest
  detection is at most ``report_time`` s old: KTP labels only the people an image shows, so a track kept for a person
  who left or is hidden would be a false positive there (seed 003 reports about 1% of them). No track starts within
  ``clearance`` of a track that took a detection this cycle: two people's heads are never nearer than 0.3 m (Table
  7's sub-clustering distance), so such a detection is a piece of a person sub-clustering split off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import gammaincinv

from pipeline.lsap import linear_sum_assignment
from pipeline.params import param
from pipeline.tracking.association import checked_detections, mahalanobis
from pipeline.tracking.online_boost import (BINS, POOL, SELECTORS, OnlineColourClassifier, colour_histogram,
                                           rgb_to_hsv)
from pipeline.types import DetectedPersons, TrackedPersons

MIN_WINDOW = 10  # px, the smallest random negative window (the authors' AdaBoost demo)
WINDOW_SAMPLES = 32  # a random window's histogram is taken on at most this many pixels a side, evenly strided
# the least HOG score that starts a track: the shipped robot-camera model's, passed by 90% of its validation people
# (`crowdsim experiment train-hog --camera robot` prints it; Table 7's [-1, -0.5] is the same role on the paper's scale)
INIT_CONFIDENCE = 0.325
HEIGHT_GAIN = 0.1  # a track's height follows its detections' by this exponential gain (a running mean before)


def predict(x: np.ndarray, P: np.ndarray, dt: float, acceleration_variance: float) -> tuple[np.ndarray, np.ndarray]:
    """Constant-velocity prediction of states x [n, 4] (x, y, vx, vy) and covariances P [n, 4, 4] over dt."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    G = np.array([dt * dt / 2, dt * dt / 2, dt, dt])
    Q = acceleration_variance * np.outer(G, G) * np.kron(np.ones((2, 2)), np.eye(2))  # x and y independent
    return x @ F.T, F @ P @ F.T + Q


def correct(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Kalman correction of x [n, 4], P [n, 4, 4] with positions z [n, 2] of covariances R [n, 2, 2]."""
    S = P[:, :2, :2] + R
    K = P[:, :, :2] @ np.linalg.inv(S)  # [n, 4, 2]
    x = x + (K @ (z - x[:, :2])[:, :, None])[:, :, 0]
    P = P - K @ S @ K.transpose(0, 2, 1)
    return x, 0.5 * (P + P.transpose(0, 2, 1))


def motion_distance(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray, ref: np.ndarray, ref_P: np.ndarray,
                    lag: np.ndarray) -> np.ndarray:
    """D_M [n, m] over position and velocity (Eq. 3-4) of predicted tracks x [n, 4], P [n, 4, 4] against detections
    z [m, 2], R [m, 2, 2]: the measured velocity is (z_j - ref_i) / lag_i, ref_i [n, 2] (covariance ref_P [n, 2, 2])
    the track's position lag_i [n] s ago (> 0). Measurement noise [[R, R / L], [R / L, (R + ref_P) / L^2]]."""
    n, m = x.shape[0], z.shape[0]
    inv_lag = (1.0 / lag)[:, None, None, None]
    nu = np.empty((n, m, 4))
    nu[..., :2] = z[None] - x[:, None, :2]
    nu[..., 2:] = (z[None] - ref[:, None]) * inv_lag[..., 0] - x[:, None, 2:]
    S = np.broadcast_to(P[:, None], (n, m, 4, 4)).copy()
    S[..., :2, :2] += R[None]
    S[..., :2, 2:] += R[None] * inv_lag
    S[..., 2:, :2] += R[None] * inv_lag
    S[..., 2:, 2:] += (R[None] + ref_P[:, None]) * inv_lag ** 2
    return np.einsum("nmi,nmi->nm", nu, np.linalg.solve(S, nu[..., None])[..., 0])


def joint_cost(distance: np.ndarray, colour: np.ndarray, detector: np.ndarray, motion_weight: float,
               appearance_weight: float, detector_weight: float) -> np.ndarray:
    """Eq. 6's cost [n, m]: gamma D_M - alpha c_online - beta c_HOG (the confidences lower the cost)."""
    return motion_weight * distance - appearance_weight * colour - detector_weight * detector[None]


def assign(cost: np.ndarray, allowed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Munkres on cost [n, m]: the most allowed pairs, and the cheapest such set (forbidden pairs cost more than the
    spread of any set of allowed ones, and are dropped from the answer)."""
    if not allowed.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    spread = np.abs(cost[allowed]).max()
    forbidden = 2.0 * min(cost.shape) * spread + 1.0
    rows, cols = linear_sum_assignment(np.where(allowed, cost, forbidden))
    keep = allowed[rows, cols]
    return rows[keep].astype(np.int64), cols[keep].astype(np.int64)


@dataclass(eq=False)
class RgbdTracker:
    """The ``rgbd`` tracker: seed 003's (module docstring). Defaults: the paper's Table 7 where it has one (gamma 0.5,
    alpha 30, beta 1, 50 selectors of 250, 16 bins; init_confidence its [-1, -0.5] on our HOG scale), else
    OpenPTrack's (tracker.yaml: gate 0.999, acceleration variance 100, validation 3 in 2.4 s, deletion 8 s; its code:
    initial velocity variance 100, velocity over 1-2 s) and the AdaBoost demo (10 random windows)."""

    frame: str = param("odom", "the tracks' frame (the detections')")
    motion_weight: float = param(0.5, "gamma of the Mahalanobis distance in the joint cost (Table 7)", min=0.0)
    # c_online is a normalised vote in [-1, 1] and gamma D_M <= 0.5 * 18.5 within the gate: at Table 7's alpha
    # (30-100) a confidence difference of 0.3 outweighs any motion difference, so colour decides between
    # unlike-dressed candidates and motion between like-dressed ones. 30, the range's lower end, leaves motion the most
    # say.
    appearance_weight: float = param(30.0, "alpha of the colour classifier's confidence (Table 7: 30-100; 0: no colour "
                                           "term)", min=0.0)
    detector_weight: float = param(1.0, "beta of the HOG score (Table 7)", min=0.0)
    acceleration_variance: float = param(100.0, "m^2/s^4, white acceleration of the constant-velocity model "
                                                "(OpenPTrack)", min=0.0, exclusive_min=True)
    initial_velocity_variance: float = param(100.0, "m^2/s^2, a new track's velocity variance (OpenPTrack)", min=0.0,
                                             exclusive_min=True)
    use_velocity: bool = param(True, "the Mahalanobis distance over position and velocity (false: position only, "
                                     "seed 003's RGB-D People test)")
    velocity_lag: float = param(1.0, "s, a detection's velocity is measured from the track's position 1-2 lags back "
                                     "(OpenPTrack)", min=0.0, exclusive_min=True)
    gate_probability: float = param(0.999, "chi-square gate on the Mahalanobis distance (OpenPTrack)", min=0.0,
                                    exclusive_min=True, max=0.999999)
    init_confidence: float = param(INIT_CONFIDENCE, "least HOG score of a detection that starts or validates a track: "
                                                    "the shipped robot-camera model's, passed by 90% of its validation "
                                                    "people (Table 7's [-1, -0.5] on the paper's scale)")
    confirm: int = param(3, "detections at init_confidence that confirm a new track (OpenPTrack)", min=1)
    confirm_time: float = param(2.4, "s, an unconfirmed track is dropped after this (OpenPTrack)", min=0.0)
    max_missed_time: float = param(8.0, "s without a detection before a track is deleted (OpenPTrack)", min=0.0)
    report_time: float = param(0.1, "s since its latest detection that a track is still reported (kept, unreported, "
                                    "to max_missed_time for a person who comes back; chosen on training seed 100 of "
                                    "the KTP room: 0 s, 0.1, 0.2, 0.5 gave MOTA 96.2, 94.8, 93.5, 88.6% with 59, 10, "
                                    "7, 9 ID switches)", min=0.0)
    clearance: float = param(0.3, "m: no track starts this near a track that took a detection in the cycle (Table 7: "
                                  "heads are at least 0.3 m apart)", min=0.0)
    learn: bool = param(True, "the colour classifiers keep learning (false: frozen after their first cycle, seed 003's "
                              "ablation)")
    learn_interval: float = param(1.0, "s between a track's learning cycles, one track a cycle (0: every track every "
                                       "cycle; an update costs about 0.5 ms here)", min=0.0)
    random_windows: int = param(10, "random image windows learnt as negatives (the authors' demo)", min=0)
    # that of the random windows' histograms: the detector makes the detections' in the same one (``rgb_to_hsv``)
    colour_space: str = param("rgb", "of the histograms; the detector's must be the same", choices=("rgb", "hsv"))
    bins: int = param(BINS, "histogram bins a channel (seed 003 Sec. 3.2.1)", min=2)
    pool: int = param(POOL, "weak classifiers (Table 7)", min=1)
    selectors: int = param(SELECTORS, "selectors of the strong classifier (Table 7)", min=1)
    seed: int = param(0, "the classifiers' and windows' random stream")

    def __post_init__(self) -> None:
        """What the cycle uses, made from the parameters (which the scenario format has checked)."""
        # the chi-square quantile, as scipy.stats' chi2.ppf works it out (without importing scipy.stats: 0.5 s)
        self.gate = {dof: float(2 * gammaincinv(dof / 2, self.gate_probability)) for dof in (2, 4)}
        self.reset()

    def reset(self) -> None:
        """A new run: no tracks, ids from 1, no image, the random stream (classifiers, windows) from ``seed``."""
        self.rng = np.random.default_rng(self.seed)
        self._image: np.ndarray | None = None
        self._stamp: float | None = None
        self._next_id = 1
        self._classifiers: list[OnlineColourClassifier] = []
        self._t = {
            "x": np.zeros((0, 4)), "P": np.zeros((0, 4, 4)),
            # the velocity reference (position, covariance, stamp) and the next one, taken a lag after it
            "ref": np.zeros((0, 2)), "ref_P": np.zeros((0, 2, 2)), "ref_t": np.zeros(0),
            "next": np.zeros((0, 2)), "next_P": np.zeros((0, 2, 2)), "next_t": np.zeros(0),
            "id": np.zeros(0, np.int64),  # 0 until confirmed
            "created": np.zeros(0), "seen": np.zeros(0),  # stamps of the first and the latest detection
            "validations": np.zeros(0, np.int64),  # detections at init_confidence or above
            "det": np.zeros(0, np.int64),  # this cycle's detection id, -1 for none
            "height": np.zeros(0), "heights": np.zeros(0, np.int64),  # smoothed height, heights seen
            "learned": np.zeros(0),  # stamp of the classifier's latest learning, -inf before its first
        }

    @property
    def num_tracks(self) -> int:
        """Tracks held, unconfirmed ones included."""
        return int(self._t["id"].size)

    def see(self, frames) -> None:
        """Keep the latest colour image among the cameras' frames, for the random negative windows."""
        for f in frames:
            if getattr(f, "rgb", None) is not None:
                self._image = f.rgb

    # -- one cycle ------------------------------------------------------------------------------------------------

    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        """One tracking cycle with the detections at ``stamp``; returns the confirmed tracks."""
        z, R, det_ids = checked_detections(stamp, detections, self.frame, self._stamp)
        stamp = float(stamp)
        t = self._t
        if self._stamp is not None and stamp > self._stamp and self.num_tracks:
            t["x"], t["P"] = predict(t["x"], t["P"], stamp - self._stamp, self.acceleration_variance)
        self._stamp = stamp
        hog = np.asarray(detections.confidence, float)
        hist = None if detections.appearance is None else np.asarray(detections.appearance, float)
        rows, cols = self._associate(stamp, z, R, hog, hist)
        self._correct(stamp, rows, cols, z, R, det_ids, hog, detections.height)
        self._delete(stamp)
        self._initiate(stamp, cols, z, R, det_ids, hog, detections.height)
        if hist is not None and self.appearance_weight != 0.0:
            self._learn(stamp, hist, det_ids)
        self._confirm()
        return self._output(stamp, detections.height is not None)

    def _associate(self, stamp, z, R, hog, hist) -> tuple[np.ndarray, np.ndarray]:
        if self.num_tracks == 0 or z.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return assign(*self._cost(stamp, z, R, hog, hist))

    def _cost(self, stamp, z, R, hog, hist) -> tuple[np.ndarray, np.ndarray]:
        """Eq. 6's cost [n, m] and the pairs within the gate; the classifiers are asked about those only."""
        t = self._t
        n, m = self.num_tracks, z.shape[0]
        distance = mahalanobis(t["x"], t["P"], z, R)
        gate = np.full(n, self.gate[2])
        if self.use_velocity:
            lag = stamp - t["ref_t"]
            moved = np.flatnonzero(lag > 0.0)  # a track started this very stamp has no velocity to measure yet
            if moved.size:
                distance[moved] = motion_distance(t["x"][moved], t["P"][moved], z, R, t["ref"][moved],
                                                  t["ref_P"][moved], lag[moved])
                gate[moved] = self.gate[4]
        allowed = distance <= gate[:, None]
        colour = np.zeros((n, m))
        if hist is not None and self.appearance_weight != 0.0:
            for i, j in zip(*np.nonzero(allowed)):
                colour[i, j] = self._classifiers[i].confidence(hist[j])
        return joint_cost(distance, colour, hog, self.motion_weight, self.appearance_weight,
                          self.detector_weight), allowed

    def _correct(self, stamp, rows, cols, z, R, det_ids, hog, heights) -> None:
        t = self._t
        t["det"][:] = -1
        if rows.size == 0:
            return
        x, P = correct(t["x"][rows], t["P"][rows], z[cols], R[cols])
        t["x"][rows], t["P"][rows] = x, P
        t["det"][rows] = det_ids[cols]
        t["seen"][rows] = stamp
        t["validations"][rows] += hog[cols] >= self.init_confidence
        shift = rows[stamp - t["next_t"][rows] >= self.velocity_lag]  # the next reference is a lag old: take it
        for key in ("", "_P", "_t"):
            t["ref" + key][shift] = t["next" + key][shift]
        t["next"][shift], t["next_P"][shift], t["next_t"][shift] = t["x"][shift, :2], t["P"][shift, :2, :2], stamp
        if heights is not None:
            self._smooth_heights(rows, np.asarray(heights, float)[cols])

    def _smooth_heights(self, rows: np.ndarray, heights: np.ndarray) -> None:
        t = self._t
        t["heights"][rows] += 1
        gain = np.maximum(1.0 / t["heights"][rows], HEIGHT_GAIN)
        t["height"][rows] = np.where(t["heights"][rows] == 1, heights,
                                     t["height"][rows] + gain * (heights - t["height"][rows]))

    def _delete(self, stamp: float) -> None:
        t = self._t
        keep = (stamp - t["seen"] <= self.max_missed_time) & (
            (t["id"] != 0) | (stamp - t["created"] <= self.confirm_time))
        if not keep.all():
            self._keep(np.flatnonzero(keep))

    def _keep(self, idx: np.ndarray) -> None:
        for key, v in self._t.items():
            self._t[key] = v[idx]
        self._classifiers = [self._classifiers[i] for i in idx]

    def _initiate(self, stamp, used, z, R, det_ids, hog, heights) -> None:
        """A track for every detection no track took with c_HOG >= init_confidence, unless it lies within
        ``clearance`` of a track that took one (a person split in two by sub-clustering): at it, velocity 0."""
        free = hog >= self.init_confidence
        free[used] = False
        taken = self._t["x"][self._t["det"] >= 0, :2]
        if len(taken) and free.any():
            free &= np.hypot(*(z[:, None] - taken[None]).transpose(2, 0, 1)).min(axis=1) >= self.clearance
        new = np.flatnonzero(free)
        k = new.size
        if k == 0:
            return
        P = np.zeros((k, 4, 4))
        P[:, :2, :2] = R[new]
        P[:, 2, 2] = P[:, 3, 3] = self.initial_velocity_variance
        xy = z[new]
        add = {"x": np.concatenate([xy, np.zeros((k, 2))], 1), "P": P,
               "ref": xy, "ref_P": R[new], "ref_t": np.full(k, stamp),
               "next": xy, "next_P": R[new], "next_t": np.full(k, stamp),
               "id": np.zeros(k, np.int64), "created": np.full(k, stamp), "seen": np.full(k, stamp),
               "validations": np.ones(k, np.int64), "det": det_ids[new],
               "height": np.full(k, np.nan), "heights": np.zeros(k, np.int64), "learned": np.full(k, -np.inf)}
        n = self.num_tracks
        for key, v in add.items():
            self._t[key] = np.concatenate([self._t[key], v])
        if heights is not None:
            self._smooth_heights(np.arange(n, n + k), np.asarray(heights, float)[new])
        self._classifiers += [OnlineColourClassifier(self.rng, self.bins, self.pool, self.selectors)
                              for _ in range(k)]

    def _learn(self, stamp: float, hist: np.ndarray, det_ids: np.ndarray) -> None:
        """Tracks with a detection this cycle learn it as a positive and the other detections and random windows as
        negatives: a new classifier at once, the others (with ``learn``) in turn (``learn_interval``)."""
        t = self._t
        has, trained = t["det"] >= 0, np.isfinite(t["learned"])
        first = has & ~trained
        due = has & trained & self.learn & (stamp - t["learned"] >= self.learn_interval)
        if self.learn_interval > 0.0 and due.any():  # one a cycle: the longest waiting
            waiting = np.flatnonzero(due)
            due[:] = False
            due[waiting[np.argmin(t["learned"][waiting])]] = True
        learners = np.flatnonzero(first | due)
        if learners.size == 0:
            return
        column = {d: j for j, d in enumerate(det_ids.tolist())}
        windows = self._windows()
        for i in learners.tolist():
            own = column[int(t["det"][i])]
            classifier = self._classifiers[i]
            classifier.update(hist[own], True)
            for j in range(hist.shape[0]):
                if j != own:
                    classifier.update(hist[j], False)
            for w in windows:
                classifier.update(w, False)
        t["learned"][learners] = stamp

    def _windows(self) -> list[np.ndarray]:
        """Histograms of ``random_windows`` random windows (at least MIN_WINDOW px a side, at most half the image's)
        of the latest image, each on an even grid of at most WINDOW_SAMPLES^2 of its pixels."""
        if self._image is None or self.random_windows <= 0:
            return []
        h, w = self._image.shape[:2]
        if min(h, w) < MIN_WINDOW:
            return []
        sizes = self.rng.integers(MIN_WINDOW, np.maximum([h // 2, w // 2], MIN_WINDOW) + 1, (self.random_windows, 2))
        corners = (self.rng.random((self.random_windows, 2)) * ([h + 1, w + 1] - sizes)).astype(np.int64)
        out = []
        for (dh, dw), (v0, u0) in zip(sizes.tolist(), corners.tolist()):
            sv, su = -(-dh // WINDOW_SAMPLES), -(-dw // WINDOW_SAMPLES)
            pixels = self._image[v0:v0 + dh:sv, u0:u0 + dw:su].reshape(-1, 3)
            out.append(colour_histogram(rgb_to_hsv(pixels) if self.colour_space == "hsv" else pixels,
                                        self.bins))
        return out

    def _confirm(self) -> None:
        """Tracks with ``confirm`` validating detections get the next ids (in row order)."""
        t = self._t
        new = (t["id"] == 0) & (t["validations"] >= self.confirm)
        k = int(np.count_nonzero(new))
        if k:
            t["id"][new] = np.arange(self._next_id, self._next_id + k)
            self._next_id += k

    def _output(self, stamp: float, with_height: bool) -> TrackedPersons:
        t = self._t
        idx = np.flatnonzero((t["id"] > 0) & (stamp - t["seen"] <= self.report_time))
        idx = idx[np.argsort(t["id"][idx], kind="stable")]
        x, P = t["x"][idx], t["P"][idx]
        matched = t["det"][idx] >= 0
        return TrackedPersons(
            stamp=stamp,
            frame=self.frame,
            track_id=t["id"][idx],
            is_matched=matched,
            is_occluded=~matched,
            detection_id=t["det"][idx],
            position=x[:, :2].copy(),
            velocity=x[:, 2:].copy(),
            position_covariance=P[:, :2, :2].copy(),
            velocity_covariance=P[:, 2:, 2:].copy(),
            age=stamp - t["created"][idx],
            height=t["height"][idx] if with_height else None,
        )
