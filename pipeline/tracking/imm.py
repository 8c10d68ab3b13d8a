"""The tracker's filter: one motion model (a Kalman filter, extended for CT) or an IMM over several (seed 000 Sec.
III-A and V-D; Blom & Bar-Shalom 1988, "The interacting multiple model algorithm for systems with Markovian switching
coefficients").

Why an IMM: one process-noise level is a compromise between smooth estimates of walkers and holding tracks through
turns and stops (seed 000 Sec. III-A); the IMM runs one filter per model and weighs them by how well each predicted
the detections, switching between them with a Markov chain. Table II's IMM is two CV models, q = 0.035 and 0.267.

All tracks at once, as a struct of arrays with the components first and the tracks last (numpy is fast on long inner
loops, slow on loops of 2 to 7): x [d, M, n] (each track's estimate under each of the M models), P [d, d, M, n], mode
probabilities mu [M, n]. With M = 1 there is no mixing and no mode probability: the plain (extended) Kalman filter.
The measurement is the position: H = [I 0], z = H x + v, v ~ N(0, R).

``IMM`` is the tracker's filter, given to it as its motion part (``imm`` in a scenario); a single model given in its
place is an IMM of one (``as_filter``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .motion import INITIAL_VARIANCE, MODELS, layout_with
from ..compiled import kernel
from ..params import Slot, made, param

__all__ = ["IMM", "MOTIONS", "MOTION", "as_filter", "kalman_update", "kalman_update_soa"]


def kalman_update_soa(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray,
                      log_likelihood: bool = False) -> tuple[np.ndarray, ...]:
    """Kalman update with one position measurement each, components first: x [d, n], P [d, d, n], z [2, n],
    R [2, 2, n], or an IMM's x [d, M, n], P [d, d, M, n] with z [2, 1 or M, n], R [2, 2, 1 or M, n].

    nu = z - H x, S = H P H^T + R, K = P H^T S^-1, x+ = x + K nu, P+ = P - K H P (symmetrized), all written out for
    H = [I 0] and the 2 x 2 S (``_kalman``, one compiled pass: numpy's 30 calls on a few tracks cost their overhead).
    Returns new (x+, P+), and with ``log_likelihood`` also log N(nu; 0, S) + log(2 pi), from which the IMM weighs its
    models.
    """
    models = x.ndim == 3  # x [d, M, n] (an IMM's), else [d, n]
    x4, P4 = (x, P) if models else (x[:, None], P[:, :, None])
    z4, R4 = (z, R) if z.ndim == 3 else (z[:, None], R[:, :, None])
    d, m, n = x4.shape
    x_new, P_new, quad, det = np.empty((d, m, n)), np.empty((d, d, m, n)), np.empty((m, n)), np.empty((m, n))
    _kalman(x4, P4, z4, R4, x_new, P_new, quad, det)
    if not models:
        x_new, P_new = x_new[:, 0], P_new[:, :, 0]
    if not log_likelihood:
        return x_new, P_new
    ll = -0.5 * (quad + np.log(det))
    return x_new, P_new, ll if models else ll[0]


@kernel
def _kalman(x, P, z, R, x_new, P_new, quad, det):
    """``kalman_update_soa`` of x [d, M, n], P [d, d, M, n] with z [2, 1 or M, n], R [2, 2, 1 or M, n] into x_new,
    P_new, and the innovation's nu^T S^-1 nu (``quad``) and det S [M, n], each summed in numpy's version's order."""
    d = x.shape[0]
    k0, k1, p_raw = np.empty(d), np.empty(d), np.empty((d, d))
    for m in range(x.shape[1]):
        mz, mr = min(m, z.shape[1] - 1), min(m, R.shape[2] - 1)
        for c in range(x.shape[2]):
            nu0, nu1 = z[0, mz, c] - x[0, m, c], z[1, mz, c] - x[1, m, c]
            s00, s01 = P[0, 0, m, c] + R[0, 0, mr, c], P[0, 1, m, c] + R[0, 1, mr, c]
            s10, s11 = P[1, 0, m, c] + R[1, 0, mr, c], P[1, 1, m, c] + R[1, 1, mr, c]
            dt = s00 * s11 - s01 * s10
            a, b = (s11 * nu0 - s01 * nu1) / dt, (s00 * nu1 - s10 * nu0) / dt  # S^-1 nu
            for i in range(d):  # P H^T's columns are P[:, 0] and P[:, 1]
                x_new[i, m, c] = x[i, m, c] + P[i, 0, m, c] * a + P[i, 1, m, c] * b
                k0[i] = (P[i, 0, m, c] * s11 - P[i, 1, m, c] * s10) / dt  # the columns of K
                k1[i] = (P[i, 1, m, c] * s00 - P[i, 0, m, c] * s01) / dt
            for i in range(d):
                for j in range(d):
                    p_raw[i, j] = P[i, j, m, c] - k0[i] * P[0, j, m, c] - k1[i] * P[1, j, m, c]
            for i in range(d):
                for j in range(d):
                    P_new[i, j, m, c] = 0.5 * (p_raw[i, j] + p_raw[j, i])
            quad[m, c], det[m, c] = nu0 * a + nu1 * b, dt


def kalman_update(x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray,
                  log_likelihood: bool = False) -> tuple[np.ndarray, ...]:
    """``kalman_update_soa`` on one row per track: x [..., d], P [..., d, d], z [..., 2], R [..., 2, 2]."""
    out = kalman_update_soa(np.moveaxis(x, -1, 0), np.moveaxis(P, (-2, -1), (0, 1)), np.moveaxis(z, -1, 0),
                            np.moveaxis(R, (-2, -1), (0, 1)), log_likelihood)
    rows = (np.moveaxis(out[0], 0, -1), np.moveaxis(out[1], (0, 1), (-2, -1))) + out[2:]
    return tuple(np.ascontiguousarray(v) for v in rows)


MODEL = Slot(MODELS, "cv", ("predict_soa", "on"), "a motion model (pipeline/tracking/motion.py)", "motion model")


def _markov(p: dict):
    k, T = len(p["models"]), p["transition"]
    rows = [T[i * k:(i + 1) * k] for i in range(k)]
    if (len(T) != k * k or any(abs(sum(r) - 1.0) > 1e-9 for r in rows)
            or any(all(r[j] == 0 for r in rows) for j in range(k))):
        return "transition", (f"{T}; expected the {k} x {k} Markov matrix of the {k} models, row-major: {k * k} "
                              f"numbers, each row summing to 1, each model reachable")


@dataclass(eq=False)
class IMM:
    """The filter of M motion models (``pipeline.tracking.motion``, or their specifications) on one state layout,
    the union of theirs; ``transition`` is the Markov matrix p_ij = P(model j at this cycle | model i at the last),
    M x M or row-major, rows summing to 1 (unused when M = 1).

    The tracks' filter state is a dict of arrays, tracks last, the names ``keys``: x [d, M, n], P [d, d, M, n] and,
    with M > 1, the mode probabilities mu [M, n]. Every method returns new arrays (``start`` fills given ones if
    asked).
    """

    models: list = param([{"type": "cv", "process_noise": 0.035}, {"type": "cv", "process_noise": 0.267}],
                         "the IMM's models (seed 000 Sec. V-D, Table II \"+IMM (CV + CV)\": two CV models with q_L = "
                         "0.035, walking, and 0.267, manoeuvres)", parts=MODEL, min_items=1)
    transition: list = param([0.95, 0.05, 0.05, 0.95],
                             "the Markov matrix, row-major, one row per model, rows summing to 1: entry (i, j) is the "
                             "chance that a person moving by model i at one cycle moves by model j at the next (seed "
                             "000 gives none: 0.95 to stay keeps a mode for 20 cycles, 0.8 s at 25 Hz, about as long "
                             "as a walker's turn or stop)", item=dict(min=0.0, max=1.0), min_items=1)

    CHECKS = (_markov,)

    def __post_init__(self):
        models = [made(m, MODEL) for m in self.models]
        self.layout = layout_with({c for m in models for c in m.layout[4:]})
        self.models = [m.on(self.layout) for m in models]
        self.M, self.d = len(self.models), len(self.layout)
        self._T = None if self.M == 1 else np.reshape(np.asarray(self.transition, float), (self.M, self.M))
        self.keys = ("x", "P", "mu") if self.M > 1 else ("x", "P")
        self.shapes = dict(zip(self.keys, ((self.d, self.M), (self.d, self.d, self.M), (self.M,))))  # per track

    def start(self, z: np.ndarray, R: np.ndarray, velocity_variance: float, out: dict | None = None) -> dict:
        """k new tracks at the positions z [k, 2] (covariances R [k, 2, 2]), everything else 0 with its initial
        variance; every model starts from the same estimate, the mode probabilities uniform. Written into ``out``
        when given (the new tracks' arrays, all zero: the tracker's own columns, so that a birth copies nothing),
        else into new arrays."""
        s = out if out is not None else {key: np.zeros((*shape, z.shape[0])) for key, shape in self.shapes.items()}
        x, P = s["x"], s["P"]
        x[:2] = z.T[:, None]
        P[:2, :2] = R.transpose(1, 2, 0)[:, :, None]
        P[2, 2] = P[3, 3] = velocity_variance
        for i, c in enumerate(self.layout[4:], start=4):
            P[i, i] = INITIAL_VARIANCE[c]
        if self.M > 1:
            s["mu"][...] = 1.0 / self.M
        return s

    def predict(self, s: dict, dt: float) -> dict:
        """One cycle ahead by dt > 0: the IMM's interaction (mixing) step, then each model's own prediction from
        its mixed estimate; mu becomes the predicted mode probabilities c_j = sum_i mu_i p_ij."""
        if self.M == 1:
            x, P = self.models[0].predict_soa(s["x"][:, 0], s["P"][:, :, 0], dt)
            return {"x": x[:, None], "P": P[:, :, None]}
        mu, T = s["mu"], self._T
        c = T.T @ mu
        w = T[:, :, None] * mu[:, None] / c[None]  # [i, j, n]: P(model i before | model j now)
        x0, P0 = _mix(w.transpose(1, 0, 2), s["x"], s["P"])
        x, P = np.empty_like(x0), np.empty_like(P0)
        for j, m in enumerate(self.models):
            x[:, j], P[:, :, j] = m.predict_soa(x0[:, j], P0[:, :, j], dt)
        return {"x": x, "P": P, "mu": c}

    def estimate(self, s: dict, k: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The combined estimate handed out (and gated on) of the first k state components (all by default): the
        mode-weighted mean and covariance, [k, n], [k, k, n]."""
        if self.M == 1:
            return s["x"][:k, 0], s["P"][:k, :k, 0]
        xc, Pc = _mix(s["mu"][None], s["x"][:k], s["P"][:k, :k])
        return xc[:, 0], Pc[:, :, 0]

    def update(self, s: dict, z: np.ndarray, R: np.ndarray) -> dict:
        """Each model's Kalman update of the tracks with their detections z [n, 2], R [n, 2, 2]; the mode
        probabilities become mu_j ~ c_j N(nu_j; 0, S_j)."""
        z, R = np.ascontiguousarray(z.T), np.ascontiguousarray(R.transpose(1, 2, 0))  # tracks last, as the state
        if self.M == 1:
            x, P = kalman_update_soa(s["x"][:, 0], s["P"][:, :, 0], z, R)
            return {"x": x[:, None], "P": P[:, :, None]}
        x, P, log_l = kalman_update_soa(s["x"], s["P"], z[:, None], R[:, :, None], log_likelihood=True)
        # relative to the best model, and floored, so that no probability underflows to 0 (nor the sum to 0)
        post = s["mu"] * np.exp(np.maximum(log_l - log_l.max(axis=0), -700.0))
        return {"x": x, "P": P, "mu": post / post.sum(axis=0)}


MOTIONS = {**MODELS, "imm": IMM}
MOTION = Slot(MOTIONS, "cv", ("predict_soa", "on"),
              "the motion model (seed 000 Eq. 1-2, Sec. III-A, V-D): constant velocity, constant acceleration, "
              "coordinated turn (EKF), Brownian, or an IMM of several", "motion model")


def as_filter(motion) -> IMM:
    """The tracker's filter from its motion part: an IMM as it is, a single model as an IMM of one."""
    return motion if isinstance(motion, IMM) else IMM([motion])


def _mix(weights: np.ndarray, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian mixtures reduced to their moments: for each output j, sum_i weights[j, i] of the components
    (x[:, i], P[:, :, i]), spread of the means included. weights [J, M, n], x [d, M, n], P [d, d, M, n] -> [d, J, n],
    [d, d, J, n]."""
    xm = np.einsum("jmn,dmn->djn", weights, x)
    dx = x[:, None] - xm[:, :, None]  # [d, J, M, n]
    return xm, np.einsum("jmn,abmn->abjn", weights, P) + np.einsum("ajmn,bjmn->abjn", weights * dx, dx)
