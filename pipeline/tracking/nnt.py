"""Nearest-neighbour people tracker on the ground plane (the SPENCER base NNT, seed 000 Sec. II-B, III-B/C, Table II).

Why: the testbed needs a fast, deterministic multi-person tracker that turns per-frame detections (already in the
locally fixed tracking frame, e.g. ``odom``) into persistent person tracks with ids, so that CLEAR-MOT can score the
perception pipeline. The seed paper's base tracker is a Kalman filter per person with a nearly-constant-velocity
model and greedy nearest-neighbour data association on the Mahalanobis distance; it runs at kHz rates (Table II).

Model (seed 000 Eq. 1-2), state ``[x, y, vx, vy]`` (the seed orders it ``[x, vx, y, vy]``; the model is the same):

    x_k = F x_{k-1} + w,  F = [[I, t I], [0, I]],  w ~ N(0, Q),
    Q = q_L [[t^3/3 I, t^2/2 I], [t^2/2 I, t I]]       (white-noise acceleration, q_L in m^2/s^3)
    z_k = H x_k + v,      H = [I 0],                    v ~ N(0, R)  (R: the detection's x/y covariance)

One cycle (``NearestNeighbourTracker.update``), every step batched over all tracks (struct of numpy arrays):

1. predict   -- ``predict``: x <- F x, P <- F P F^T + Q with dt = stamp - previous stamp.
2. gate      -- ``mahalanobis``: d^2 = nu^T S^-1 nu for every (track, detection) pair, S = H P H^T + R;
                pairs with d^2 > gate_chi2 are not allowed.
3. associate -- ``greedy_assign``: greedy NN (seed 000 Table II "Greedy NN"): take the globally smallest gated cost,
                assign, remove its row and column, repeat. Confirmed tracks choose first; tentative tracks
                (initiation candidates) only get the detections left over, as in the seed's initiation logic
                (Alg. 1 works on the unmatched detections Z^u). Implemented as one stable sort of the gated pairs by
                (tentative, cost) and a single walk.
4. update    -- ``kalman_update``: standard Kalman update of all matched tracks at once.
5. misses    -- unmatched tracks coast on their prediction; the consecutive-miss counter grows. A confirmed track
                is deleted after ``n_delete`` consecutive misses (seed 000 Sec. V-C: n_del = 5 in the base NNT), a
                tentative one after ``n_delete_tentative``.
6. initiate  -- every unmatched detection starts a tentative track at its position with zero velocity and
                variance ``initial_velocity_variance``; a tentative track is confirmed once it has been matched by
                ``n_confirm`` detections in all (the creating detection counts as the first; the seed's base
                initiation logic, Sec. III-B, without its velocity gate).

Choices:

* Track ids are handed out from a counter starting at 1 **when a track is confirmed**, so output ids are
  consecutive (1, 2, 3, ...) and do not depend on how many false-alarm candidates came and went. A track keeps its
  id until it is deleted; ids are never reused (``reset`` restarts the counter).
* ``age`` is the time since the track's first detection (its creation as a tentative track), in seconds.
* Only confirmed tracks are output, sorted by track id. ``is_occluded`` is ``not is_matched``.
* Stamps must not decrease (ValueError); the first cycle (or one with equal stamp) does no prediction.
* Detections must be in the tracker's frame, with finite x/y and a positive-definite x/y covariance (ValueError).
* Ties in cost are broken by (track row, detection index), so results are deterministic; there is no randomness.
* Defaults q_L = 0.267 m^2/s^3 and gate 13.82 favour holding tracks through turns over smooth velocities; the
  reasons and measurements are in ``TrackerParams``. Known limit of greedy NN: two people whose detections
  coincide can swap tracks (about 1 % of 90-degree X crossings at 1.3 m/s, 25 Hz, sigma 0.03-0.05 m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.types import DetectedPersons, TrackedPersons

__all__ = [
    "TrackerParams",
    "NearestNeighbourTracker",
    "transition_matrix",
    "process_noise",
    "predict",
    "mahalanobis",
    "greedy_assign",
    "kalman_update",
]


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
    where smooth velocities matter more than holding tracks through turns."""

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

    def __post_init__(self) -> None:
        if not (self.process_noise >= 0.0 and np.isfinite(self.process_noise)):
            raise ValueError(f"process_noise must be finite and >= 0, got {self.process_noise}")
        if not self.gate_chi2 > 0.0:
            raise ValueError(f"gate_chi2 must be > 0, got {self.gate_chi2}")
        for name in ("n_confirm", "n_delete", "n_delete_tentative"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not (self.initial_velocity_variance > 0.0 and np.isfinite(self.initial_velocity_variance)):
            raise ValueError(f"initial_velocity_variance must be finite and > 0, got {self.initial_velocity_variance}")


# ----------------------------------------------------------------------------------------------------------------
# Small parts (pure functions, batched over tracks)
# ----------------------------------------------------------------------------------------------------------------


def transition_matrix(dt: float) -> np.ndarray:
    """F of seed 000 Eq. 1 for the state [x, y, vx, vy] (4x4)."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    return F


def process_noise(dt: float, q: float) -> np.ndarray:
    """Q of seed 000 Eq. 2 for the state [x, y, vx, vy] (4x4), white-noise acceleration of density q."""
    a, b, c = q * dt**3 / 3.0, q * dt**2 / 2.0, q * dt
    return np.array([[a, 0.0, b, 0.0], [0.0, a, 0.0, b], [b, 0.0, c, 0.0], [0.0, b, 0.0, c]])


def predict(x: np.ndarray, P: np.ndarray, dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """Constant-velocity prediction of n tracks: x [n, 4], P [n, 4, 4] -> (F x, F P F^T + Q), new arrays."""
    F = transition_matrix(dt)
    x_pred = x @ F.T
    P_pred = F @ P @ F.T + process_noise(dt, q)
    return x_pred, P_pred


def mahalanobis(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distance d^2[i, j] = nu^T S^-1 nu of every track i against every detection j.

    x [n, 4], P [n, 4, 4] (predicted tracks), z [m, 2] positions, R [m, 2, 2] their covariances; returns [n, m].
    nu = z_j - H x_i, S = H P_i H^T + R_j; the 2x2 inverse is written out in closed form.
    """
    nu0 = np.subtract.outer(x[:, 0], z[:, 0])  # sign of nu does not matter for d^2
    nu1 = np.subtract.outer(x[:, 1], z[:, 1])
    s00 = np.add.outer(P[:, 0, 0], R[:, 0, 0])
    s11 = np.add.outer(P[:, 1, 1], R[:, 1, 1])
    s01 = np.add.outer(P[:, 0, 1], 0.5 * (R[:, 0, 1] + R[:, 1, 0]))
    d2 = s11 * nu0 * nu0
    d2 -= 2.0 * s01 * nu0 * nu1
    d2 += s00 * nu1 * nu1
    det = s00 * s11
    det -= s01 * s01
    d2 /= det
    return d2


def greedy_assign(cost: np.ndarray, gate: float, priority: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy nearest-neighbour assignment on cost [n, m]: returns (rows, cols) of the pairs, in the order taken.

    Only pairs with cost <= gate are allowed. Pairs are taken in increasing cost, each row and column at most once
    (seed 000 Table II "Greedy NN"). With ``priority`` [n] (smaller first), all gated pairs of priority-0 rows are
    taken before any of priority-1 rows and so on. Ties go to the smaller (row, column).
    """
    n, m = cost.shape
    if n == 0 or m == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rows, cols = np.nonzero(cost <= gate)  # row-major, so a stable sort breaks ties by (row, col)
    c = cost[rows, cols]
    order = np.argsort(c, kind="stable") if priority is None else np.lexsort((c, priority[rows]))
    rows_l, cols_l = rows[order].tolist(), cols[order].tolist()
    row_free = [True] * n
    col_free = [True] * m
    out_r: list[int] = []
    out_c: list[int] = []
    left = min(n, m)
    for r, k in zip(rows_l, cols_l):
        if row_free[r] and col_free[k]:
            row_free[r] = False
            col_free[k] = False
            out_r.append(r)
            out_c.append(k)
            left -= 1
            if left == 0:
                break
    return np.asarray(out_r, np.int64), np.asarray(out_c, np.int64)


def kalman_update(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Kalman update of k tracks with one position measurement each: x [k, 4], P [k, 4, 4], z [k, 2], R [k, 2, 2].

    nu = z - H x, S = H P H^T + R, K = P H^T S^-1, x+ = x + K nu, P+ = P - K S K^T (symmetrized). Returns new arrays.
    """
    nu = z - x[:, :2]
    PHt = P[:, :, :2]  # [k, 4, 2]
    S = P[:, :2, :2] + R
    s00, s01, s10, s11 = S[:, 0, 0], S[:, 0, 1], S[:, 1, 0], S[:, 1, 1]
    det = s00 * s11 - s01 * s10
    Sinv = np.empty_like(S)
    Sinv[:, 0, 0] = s11 / det
    Sinv[:, 1, 1] = s00 / det
    Sinv[:, 0, 1] = -s01 / det
    Sinv[:, 1, 0] = -s10 / det
    K = PHt @ Sinv  # [k, 4, 2]
    x_new = x + (K @ nu[:, :, None])[:, :, 0]
    P_new = P - K @ PHt.transpose(0, 2, 1)  # K S K^T = K H P = P H^T S^-1 H P
    P_new = 0.5 * (P_new + P_new.transpose(0, 2, 1))
    return x_new, P_new


# ----------------------------------------------------------------------------------------------------------------
# The tracker
# ----------------------------------------------------------------------------------------------------------------


class NearestNeighbourTracker:
    """Greedy nearest-neighbour Kalman tracker; all track state lives in parallel numpy arrays (one row per track)."""

    def __init__(self, frame: str = "odom", **params):
        """``params``: the keywords of ``TrackerParams`` (its defaults for those left out)."""
        self.params = TrackerParams(**params)
        self.frame = frame
        self.reset()

    # -- state --------------------------------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget all tracks and the last stamp; the id counter restarts at 1."""
        self._x = np.zeros((0, 4))  # [n, 4] state x, y, vx, vy
        self._P = np.zeros((0, 4, 4))  # [n, 4, 4] covariance
        self._id = np.zeros(0, np.int64)  # [n] track id, 0 while tentative
        self._confirmed = np.zeros(0, bool)  # [n]
        self._hits = np.zeros(0, np.int64)  # [n] detections matched over the lifetime (creating one included)
        self._misses = np.zeros(0, np.int64)  # [n] consecutive cycles without a detection
        self._created = np.zeros(0)  # [n] stamp of the first detection
        self._det = np.zeros(0, np.int64)  # [n] detection id matched this cycle, -1 for none
        self._next_id = 1
        self._stamp: float | None = None

    @property
    def num_tracks(self) -> int:
        """Tracks held, tentative ones included."""
        return int(self._id.size)

    # -- one cycle ----------------------------------------------------------------------------------------------

    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        """Run one tracking cycle with the detections at ``stamp``; returns the confirmed tracks."""
        z, R, det_ids = self._check(stamp, detections)
        stamp = float(stamp)
        dt = 0.0 if self._stamp is None else stamp - self._stamp
        self._stamp = stamp
        if dt > 0.0 and self._id.size:
            self._x, self._P = predict(self._x, self._P, dt, self.params.process_noise)

        rows, cols = self._associate(z, R)
        self._update_matched(rows, cols, z, R, det_ids)
        self._delete()
        self._initiate(stamp, cols, z, R, det_ids)
        self._confirm()
        return self._output(stamp)

    def _check(self, stamp: float, det: DetectedPersons) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if det.frame != self.frame:
            raise ValueError(f"detections are in frame '{det.frame}' but the tracker tracks in frame '{self.frame}'")
        if not np.isfinite(stamp):
            raise ValueError(f"stamp must be finite, got {stamp}")
        if self._stamp is not None and stamp < self._stamp:
            raise ValueError(f"stamp {stamp} is earlier than the previous cycle's {self._stamp}")
        n = len(det)
        pos = np.asarray(det.position, float)
        cov = np.asarray(det.covariance, float)
        if pos.shape != (n, 3) or cov.shape != (n, 3, 3):
            raise ValueError(f"detections: position {pos.shape} / covariance {cov.shape} do not match {n} ids")
        z = pos[:, :2]
        R = cov[:, :2, :2]
        if n:
            if not np.isfinite(z).all() or not np.isfinite(R).all():
                raise ValueError("detections: x/y position and covariance must be finite")
            if not ((R[:, 0, 0] > 0.0) & (R[:, 0, 0] * R[:, 1, 1] - R[:, 0, 1] * R[:, 1, 0] > 0.0)).all():
                raise ValueError("detections: x/y covariance must be positive definite")
        return z, R, np.asarray(det.detection_id, np.int64)

    def _associate(self, z: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gate and greedily assign; confirmed tracks first, tentative tracks on the detections left over."""
        if self._id.size == 0 or z.shape[0] == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        d2 = mahalanobis(self._x, self._P, z, R)
        return greedy_assign(d2, self.params.gate_chi2, priority=(~self._confirmed).view(np.int8))

    def _update_matched(self, rows, cols, z, R, det_ids) -> None:
        self._misses += 1
        self._det = np.full(self._id.size, -1, np.int64)
        if rows.size:
            self._x[rows], self._P[rows] = kalman_update(self._x[rows], self._P[rows], z[cols], R[cols])
            self._misses[rows] = 0
            self._hits[rows] += 1
            self._det[rows] = det_ids[cols]

    def _delete(self) -> None:
        p = self.params
        limit = np.where(self._confirmed, p.n_delete, p.n_delete_tentative)
        keep = self._misses < limit
        if not keep.all():
            self._select(keep)

    def _select(self, keep: np.ndarray) -> None:
        self._x, self._P, self._id = self._x[keep], self._P[keep], self._id[keep]
        self._confirmed, self._hits, self._misses = self._confirmed[keep], self._hits[keep], self._misses[keep]
        self._created, self._det = self._created[keep], self._det[keep]

    def _initiate(self, stamp, used_cols, z, R, det_ids) -> None:
        """A new tentative track for every detection no track took: position from it, velocity 0."""
        m = z.shape[0]
        free = np.ones(m, bool)
        free[used_cols] = False
        k = int(np.count_nonzero(free))
        if k == 0:
            return
        x = np.zeros((k, 4))
        x[:, :2] = z[free]
        P = np.zeros((k, 4, 4))
        P[:, :2, :2] = R[free]
        P[:, 2, 2] = P[:, 3, 3] = self.params.initial_velocity_variance
        self._x = np.concatenate([self._x, x])
        self._P = np.concatenate([self._P, P])
        self._id = np.concatenate([self._id, np.zeros(k, np.int64)])
        self._confirmed = np.concatenate([self._confirmed, np.zeros(k, bool)])
        self._hits = np.concatenate([self._hits, np.ones(k, np.int64)])
        self._misses = np.concatenate([self._misses, np.zeros(k, np.int64)])
        self._created = np.concatenate([self._created, np.full(k, stamp)])
        self._det = np.concatenate([self._det, det_ids[free]])

    def _confirm(self) -> None:
        """Tentative tracks with n_confirm detections become confirmed and get the next ids (in row order)."""
        new = ~self._confirmed & (self._hits >= self.params.n_confirm)
        k = int(np.count_nonzero(new))
        if k:
            self._id[new] = np.arange(self._next_id, self._next_id + k)
            self._next_id += k
            self._confirmed |= new

    def _output(self, stamp: float) -> TrackedPersons:
        idx = np.flatnonzero(self._confirmed)
        idx = idx[np.argsort(self._id[idx], kind="stable")]
        x, P = self._x[idx], self._P[idx]
        matched = self._misses[idx] == 0
        return TrackedPersons(
            stamp=stamp,
            frame=self.frame,
            track_id=self._id[idx].copy(),
            is_matched=matched,
            is_occluded=~matched,
            detection_id=self._det[idx].copy(),
            position=x[:, :2].copy(),
            velocity=x[:, 2:].copy(),
            position_covariance=P[:, :2, :2].copy(),
            velocity_covariance=P[:, 2:, 2:].copy(),
            age=stamp - self._created[idx],
        )
