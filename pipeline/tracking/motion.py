"""Motion models of the people tracker (seed 000 Sec. II-B Eq. 1-2 and Sec. III-A): nearly constant velocity (CV),
nearly constant acceleration (CA), nearly coordinated turn (CT, an extended Kalman filter) and Brownian motion.

Why a shared state: an IMM mixes the estimates of its models, which needs one state space for all of them. The
tracker's state is the union of what its models use, in the order ``COMPONENTS``: position and velocity always (the
tracker hands out both), the acceleration ``ax, ay`` when a CA model is among them, the turn rate ``w`` when a CT
model is. A component a model does not have is zero under that model, with zero variance: a CV person does not
accelerate or turn, a Brownian one does not walk. Every model predicts all tracks at once, held as a struct of
arrays with the tracks last (x [d, n], P [d, d, n]: numpy is fast on long inner loops, slow on loops of 2 to 7).

Process noise is white noise of density ``q`` (the seed's q_L) on the highest derivative each model has:
acceleration for CV and CT (m^2/s^3, Eq. 2), jerk for CA (m^2/s^5), velocity for Brownian motion (m^2/s); the CT
turn rate takes its own density ``turn_rate_noise`` (rad^2/s^3).

Each model is a part the tracker is given (``NearestNeighbourTracker(motion=ConstantVelocity(0.1))``, or several in
an ``imm.IMM``), its parameters declared on it; made on its own state layout unless given one (an IMM moves its
models onto their shared layout, ``on``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..params import param

__all__ = ["COMPONENTS", "MODELS", "INITIAL_VARIANCE", "state_layout", "layout_with", "ConstantVelocity",
           "ConstantAcceleration", "CoordinatedTurn", "Brownian"]

COMPONENTS = ("x", "y", "vx", "vy", "ax", "ay", "w")

INITIAL_VARIANCE = {"ax": 1.0, "ay": 1.0, "w": 1.0}
"""Variance of a new track's acceleration (m^2/s^4) and turn rate (rad^2/s^2), both started at 0. Seed 000 gives
none: walkers start, stop and turn with accelerations of the order of 1 m/s^2 and turn rates of the order of 1 rad/s
(a corner taken in 1.5 s), so 1.0 for both."""


def state_layout(kinds) -> tuple[str, ...]:
    """The state components the models ``kinds`` (names of ``MODELS``) need, in ``COMPONENTS`` order."""
    return layout_with({c for kind in kinds for c in MODELS[kind].EXTRA})


def layout_with(extra) -> tuple[str, ...]:
    """Position and velocity and the components ``extra``, in ``COMPONENTS`` order."""
    return tuple(c for c in COMPONENTS if c in ("x", "y", "vx", "vy") or c in extra)


def _pattern(layout: tuple[str, ...], blocks) -> np.ndarray:
    """A d x d 0/1 matrix on ``layout``: for each (rows, cols) of ``blocks``, 1 at the x-axis pair (rows[0], cols[0])
    and at the y-axis pair (rows[1], cols[1])."""
    M = np.zeros((len(layout), len(layout)))
    for rows, cols in blocks:
        for r, c in zip(rows, cols):
            M[layout.index(r), layout.index(c)] = 1.0
    return M


P_, V_, A_ = ("x", "y"), ("vx", "vy"), ("ax", "ay")


PROCESS_NOISE = (
    "q_L of seed 000 Eq. 2: spectral density of the white noise on the model's highest derivative (m^2/s^3 for cv "
    "and ct: the velocity variance grows by q_L per second of prediction; m^2/s^5 for ca, m^2/s for brownian). Seed "
    "000 Sec. V-D tuned an IMM of two CV models to 0.035 (smooth walking) and 0.267 (manoeuvres); a single CV model "
    "has to survive turns and stops on its own, so it takes the manoeuvre level. Check on a synthetic crowd (30 and 80 "
    "walkers at ~1.3 m/s in 30 x 30 m, heading random walk 0.5 rad/sqrt(s), smooth turns at the walls, 25 Hz, sigma "
    "0.05 m, 5 % misses, 1 false alarm per frame, 60 s; gate 13.82): q_L = 0.035 lost tracks at turns and gave 101 / "
    "268 ID switches (30 / 80 walkers), q_L = 0.1 gave 19 / 51, q_L = 0.267 gave 9 / 21; the velocity RMSE hardly "
    "changed (0.21-0.25 m/s per axis). Cost: on a walker at exactly constant velocity the velocity estimate is "
    "noisier than with a small q_L (at 25 Hz and sigma 0.02 m the filter's own per-axis velocity std is 0.17 m/s); "
    "use a smaller value (or an IMM) where smooth velocities matter more than holding tracks through turns")


@dataclass(eq=False)
class _Model:
    """A motion model predicts tracks held as a struct of arrays, components first and tracks last (``predict_soa``:
    the tracker's layout, where every numpy loop runs over the tracks); ``predict`` takes one row per track."""

    process_noise: float = param(0.267, PROCESS_NOISE, min=0.0)
    layout: tuple[str, ...] | None = dataclasses.field(default=None, kw_only=True)
    """The state components it works on (None: its own, ``state_layout``)."""

    EXTRA: ClassVar[tuple[str, ...]] = ()
    """The components it needs beyond position and velocity."""

    def __post_init__(self):
        if self.layout is None:
            self.layout = layout_with(self.EXTRA)

    def on(self, layout: tuple[str, ...]):
        """The same model on the state ``layout`` (which holds its components)."""
        return self if layout == self.layout else dataclasses.replace(self, layout=layout)

    def predict(self, x: np.ndarray, P: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Prediction of n tracks by dt: x [n, d], P [n, d, d] -> new arrays."""
        x1, P1 = self.predict_soa(x.T, P.transpose(1, 2, 0), dt)
        return np.ascontiguousarray(x1.T), np.ascontiguousarray(P1.transpose(2, 0, 1))


@dataclass(eq=False)
class _Linear(_Model):
    """x <- F x, P <- F P F^T + Q with F = sum dt^p / c F_k and Q = q sum dt^p / c Q_k over the model's ``F_TERMS``
    and ``Q_TERMS`` (p, c, blocks), each F_k, Q_k a 0/1 pattern of blocks (disjoint within F and within Q). F, Q
    and F (x) F are kept for up to ``CACHED`` values of dt: a sensor's cycles repeat a few (stamps k * 0.04 s differ
    by a dozen distinct dt in floating point, and keeping only the last dt recomputed them every other cycle)."""

    CACHED: ClassVar[int] = 16

    F_TERMS: ClassVar[tuple]
    Q_TERMS: ClassVar[tuple]

    def __post_init__(self):
        super().__post_init__()
        layout = self.layout
        # F and Q flattened = pattern matrix @ (dt^p / c for each term): one product each per new dt
        self._terms = [(np.array([p for p, _, _ in terms]), np.array([c for _, c, _ in terms]),
                        np.stack([_pattern(layout, blocks).ravel() for _, _, blocks in terms], 1))
                       for terms in (self.F_TERMS, self.Q_TERMS)]
        self._cache: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # dt -> F, F (x) F, Q as a column

    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(F, Q) for a step of dt."""
        d = len(self.layout)
        (pf, cf, F), (pq, cq, Q) = self._terms
        return (F @ (dt**pf / cf)).reshape(d, d), (Q @ (self.process_noise * dt**pq / cq)).reshape(d, d)

    def predict_soa(self, x: np.ndarray, P: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Prediction of n tracks by dt: x [d, n], P [d, d, n] -> new arrays. F P F^T is one product for all tracks,
        (F (x) F) vec(P)."""
        cached = self._cache.get(dt)
        if cached is None:
            if len(self._cache) >= self.CACHED:
                self._cache.clear()
            F, Q = self.matrices(dt)
            FF = (F[:, None, :, None] * F[None, :, None, :]).reshape(F.size, F.size)  # np.kron(F, F), sooner
            cached = self._cache[dt] = F, FF, Q.reshape(-1, 1)
        F, FF, Q = cached
        d, n = x.shape
        return F @ x, (FF @ P.reshape(d * d, n) + Q).reshape(d, d, n)


@dataclass(eq=False)
class ConstantVelocity(_Linear):
    """``cv``, seed 000 Eq. 1-2: position moves with the velocity; white-noise acceleration of density q (m^2/s^3)."""

    F_TERMS = ((0, 1.0, [(P_, P_), (V_, V_)]), (1, 1.0, [(P_, V_)]))
    Q_TERMS = ((3, 3.0, [(P_, P_)]), (2, 2.0, [(P_, V_), (V_, P_)]), (1, 1.0, [(V_, V_)]))


@dataclass(eq=False)
class ConstantAcceleration(_Linear):
    """``ca``, nearly constant acceleration (seed 000 Sec. III-A): white-noise jerk of density q (m^2/s^5), the
    Wiener-process acceleration model (Bar-Shalom, Li & Kirubarajan 2001, Sec. 6.2.3)."""

    EXTRA = ("ax", "ay")

    F_TERMS = ((0, 1.0, [(P_, P_), (V_, V_), (A_, A_)]), (1, 1.0, [(P_, V_), (V_, A_)]), (2, 2.0, [(P_, A_)]))
    Q_TERMS = ((5, 20.0, [(P_, P_)]), (4, 8.0, [(P_, V_), (V_, P_)]), (3, 6.0, [(P_, A_), (A_, P_)]),
               (3, 3.0, [(V_, V_)]), (2, 2.0, [(V_, A_), (A_, V_)]), (1, 1.0, [(A_, A_)]))


@dataclass(eq=False)
class Brownian(_Linear):
    """``brownian``, Brownian motion (a Wiener process on the position, seed 000 Sec. III-A): a person standing or
    milling about; velocity is zero under it. Position noise of density q (m^2/s)."""

    F_TERMS = ((0, 1.0, [(P_, P_)]),)
    Q_TERMS = ((1, 1.0, [(P_, P_)]),)


@dataclass(eq=False)
class CoordinatedTurn(_Model):
    """``ct``, nearly coordinated turn (seed 000 Sec. III-A): the velocity turns at the rate w, the position follows
    the arc exactly. Nonlinear in w, so the covariance goes through the Jacobian (an extended Kalman filter, as the
    seed's filters). White-noise acceleration of density q as CV (Eq. 2) plus turn-rate noise."""

    turn_rate_noise: float = param(1.0, "rad^2/s^3, density of the white noise on the turn rate. Seed 000 gives no "
                                        "value: a walker's turn rate changes by about 1 rad/s within about 1 s (a "
                                        "corner), so 1.0", min=0.0)

    EXTRA = ("w",)

    SMALL: ClassVar[float] = 1e-3
    """|w dt| under which sin(w dt) / w and (1 - cos(w dt)) / w are taken from their series (exact to 1e-14)."""

    def __post_init__(self):
        super().__post_init__()
        self._cv = ConstantVelocity(self.process_noise, layout=self.layout)

    def predict_soa(self, x: np.ndarray, P: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """EKF prediction of n tracks by dt: x [d, n], P [d, d, n] -> new arrays."""
        L = self.layout
        ix, iy, ivx, ivy, iw = (L.index(c) for c in ("x", "y", "vx", "vy", "w"))
        vx, vy, w = x[ivx], x[ivy], x[iw]
        u = w * dt
        small = np.abs(u) < self.SMALL
        ws = np.where(small, 1.0, w)
        s, c = np.sin(u), np.cos(u)
        A = np.where(small, dt * (1.0 - u * u / 6.0), s / ws)  # sin(w dt) / w
        B = np.where(small, dt * u / 2.0 * (1.0 - u * u / 12.0), (1.0 - c) / ws)  # (1 - cos(w dt)) / w
        dA = np.where(small, -w * dt**3 / 3.0, (dt * c - A) / ws)  # d/dw of A
        dB = np.where(small, dt * dt / 2.0 * (1.0 - u * u / 4.0), (dt * s - B) / ws)  # d/dw of B
        x_new = np.zeros(x.shape)
        x_new[ix] = x[ix] + A * vx - B * vy
        x_new[iy] = x[iy] + B * vx + A * vy
        x_new[ivx] = c * vx - s * vy
        x_new[ivy] = s * vx + c * vy
        x_new[iw] = w
        J = np.zeros((x.shape[1],) + P.shape[:2])  # one row per track: [n, d, d]
        J[:, ix, ix] = J[:, iy, iy] = J[:, iw, iw] = 1.0
        J[:, ix, ivx], J[:, ix, ivy], J[:, ix, iw] = A, -B, dA * vx - dB * vy
        J[:, iy, ivx], J[:, iy, ivy], J[:, iy, iw] = B, A, dB * vx + dA * vy
        J[:, ivx, ivx], J[:, ivx, ivy], J[:, ivx, iw] = c, -s, -dt * (s * vx + c * vy)
        J[:, ivy, ivx], J[:, ivy, ivy], J[:, ivy, iw] = s, c, dt * (c * vx - s * vy)
        Q = self._cv.matrices(dt)[1]
        Q[iw, iw] = self.turn_rate_noise * dt
        return x_new, (J @ P.transpose(2, 0, 1) @ J.transpose(0, 2, 1)).transpose(1, 2, 0) + Q[:, :, None]


MODELS = {"cv": ConstantVelocity, "ca": ConstantAcceleration, "ct": CoordinatedTurn, "brownian": Brownian}
