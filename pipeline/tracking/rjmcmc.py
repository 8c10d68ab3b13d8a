"""Seed 001's RJMCMC particle filter (Mekonnen, Lerasle & Herbulot, Sec. 5, Alg. 1, Eq. 1-6): passers-by on the floor
from the pooled detections of a laser and fixed wall cameras, with each person's colour in each camera.

A state is a set of targets (id, x, y). Each cycle runs one Markov chain of ``burn_in + samples`` steps (Table 1: 40 +
150) from a state of the last cycle; every step proposes one move (Table 1's q_m: add 0.15, update 0.8, remove 0.02,
swap 0.03) and accepts it by Metropolis-Hastings (Eq. 1); the steps after the burn-in are the particles, and the
estimate is the configuration they hold most often (Alg. 1 line 16).

* **Sources.** The fused detections' ``originals`` keys (``laser/legs``, ``laser/blobs``, ``camera_1/fseg``,
  ``camera_1/hog``, ...) say where each came from; ``weights`` holds seed 001's k_d per source (Table 1: laser 0.16,
  per camera 0.22 foreground and 0.2 HOG). Births are proposed at the ``proposal_sources`` (the leg detector's
  persons and the cameras', Eq. 2); the likelihood weighs the ``likelihood_sources`` (the laser's raw blobs l_b in
  place of its persons, Eq. 5).
* **Add** (Eq. 2): a detection j is drawn with weight k_d / N_d (1 - T(z_j)), T the mean kernel of the last
  estimate's targets at it (Eq. 2's mask, taken at the detection), and the new target is placed at z_j + N(0, Sigma),
  so that the reverse of a removal is a proposal of positive density. The target takes the id of the last cycle's
  target missing from the state whose predictive is highest there (within two sd), so that a person removed and added
  back within a cycle keeps their id; else a newcomer's. **Remove** (Eq. 3): target p is drawn with probability
  1/(2M) + r_p / (2 sum r), r_p = (1 - D(x_p)) T(x_p) (Eq. 3, clipped at 0), mixed half and half with a uniform
  choice: with Eq. 3 alone a newcomer (T = 0) could never be removed, and so, by Eq. 1's reverse-move term, never
  added. Where no detection is near, the birth density is floored at ``birth_floor`` (kernel units), so that a target
  whose person has gone can still be removed. **Update** (Alg. 1 lines 7-10): target p moves to its position in a
  random particle of the last cycle that holds it, plus N(0, Sigma) (a random walk around its current position when
  it was born this cycle); the ratio is the likelihood's, the interaction's and the colour's: the proposal is the
  target's predictive, which is its prior. **Swap** (line 11): a random target and its nearest exchange ids; the
  ratio is the colour's (Alg. 1 line 12) and the two ids' predictives' (which the paper leaves out: without it a swap
  of two far-apart targets of like colour is accepted half the time, and the estimate's mean positions blur the two).
  Swaps are not proposed without a camera.
* **Interaction** (Eq. 4): Psi = prod over unordered pairs of 1 - exp(-(d / sigma)^2), sigma 0.75 m (Table 1).
* **Likelihood.** Kernels are g(x; z) = exp(-|x - z|^2 / (2 * 0.09)) (Table 1's Sigma, peak 1: Eq. 2 and 3 take 1
  minus them, which a normalised density, peaking at 1.77 m^-2, would make negative). ``likelihood``:

  - ``"pooled"`` (ours, the default): each source's detections as a Poisson process of clutter (``clutter``, per m^2
    and cycle, per source) and of targets (each seen with ``p_detect``, at N(x, Sigma)), the sources pooled
    log-linearly with the weights k_d: log pi_D = sum_d w_d [sum_j log(1 + gain_d sum_i g(z_dj; x_i)) - p_detect
    sum_i v_d(x_i)], gain_d = p_detect N(0; Sigma) / clutter_d, v_d(x) = 1 where source d can see a target at x (a
    camera: the whole box of an average person in its image; the laser: everywhere), w_d = ``looks`` k_d (the
    weights of a mode sum to 1 and share out the evidence of ``looks`` independent sources: 2, chosen on training
    sequences; seed 001's five kinds of detection are far from independent). A second target on a detection gains
    little and pays the miss cost and Eq. 4, so duplicates do not pay.
    With it, each target has a prior against its absence (``_prior``): ``newcomer`` (odds per kernel area) for a
    target not tracked in the last cycle; r s / (1 - r s) times its predictive for one that the share r of the last
    cycle's particles held (s: ``survival``).
  - ``"mean"``: Eq. 5 as written, the mean over the targets of sum_d k_d (1 / N_d) sum_j g(x_i; z_dj), with no prior.
    A mean does not grow with the number of targets it explains: in a reversible sampler a person seen by every
    sensor is then tracked no more often than not (the README's seed 001 section gives the measurements). The
    paper's chain, whose Add and Remove densities (Eq. 2-3) are not each other's reverse, must have made up for it;
    literally, its Q_remove at a newcomer is 0, so no one would ever be added.

  The colour term pi_B = prod_i prod_c exp(-lambda B_ic^2) (Eq. 5) enters update and swap moves, with B the
  Bhattacharyya distance between the target's model in camera c and the histogram of an average person's box (0.5 x
  1.7 m) standing at the proposed point, in the cameras that see the whole box; lambda = 20 (Perez et al. 2002, seed
  001's [45]; the paper gives none).
* **Colour models** (Sec. 5.2.5): per id and camera, started from the estimate's histogram and moved by Eq. 6
  (alpha 0.9) when B < beta_t = 0.24; kept after the person goes. A new id in the estimate whose histograms are
  within beta_o = 0.1 of a gone person's model in every camera that sees both takes that person's id.
* **Estimate**: the id set held by most particles; each id's position is its mean over them, its covariance their
  spread; the velocity is the change of the estimate since the last cycle.

Cameras reach the filter through ``see`` (the loop calls it with the wall cameras' frames before ``update``); the
images are binned at half resolution (``views``). Randomness comes from ``seed``: one run is one draw of the filter,
and seed 001 reports eight.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from pipeline.appearance import bhattacharyya, bin_image, blend, histogram
from pipeline.params import param
from pipeline.types import DetectedPersons, TrackedPersons

# seed 001 Table 1 (crowdsim/experiments/seed001.py's "all sensors")
TABLE1_WEIGHTS = {"laser/legs": 0.16, "laser/blobs": 0.16, "camera_1/fseg": 0.22, "camera_1/hog": 0.2,
                  "camera_2/fseg": 0.22, "camera_2/hog": 0.2}
PERSON = (0.5, 1.7)  # m, width and height of the average person whose box gives a target's colour
CELL = 0.05  # m, floor cells over which a box histogram is reused within a cycle
EMPTY_MEAN = 1e-3  # Eq. 5's value for a state without targets (``likelihood: mean``)


@dataclass
class State:
    """A state of the chain: its targets (ids, positions) and, per target, its kernels at the likelihood's detections,
    its cost (the sources that should see it) and its removal weight (Eq. 3); with the state's log pi_D."""

    ids: list
    xs: list
    ys: list
    kernels: list
    costs: list
    removal: list
    log_pi: float


@dataclass
class View:
    """A wall camera's latest image for the colour term: bin indices at half resolution, its camera matrix scaled
    to them, and the optical frame's pose in the tracking frame."""

    name: str
    bins: np.ndarray
    camera_matrix: np.ndarray
    pose: np.ndarray


def views(frames) -> list[View]:
    """The colour views of calibrated wall-camera frames (CameraFrame with rgb, camera_matrix, pose)."""
    scale = np.diag([0.5, 0.5, 1.0])
    return [View(f.frame, bin_image(f.rgb[::2, ::2]), scale @ f.camera_matrix, f.pose) for f in frames
            if f.rgb is not None and f.camera_matrix is not None and f.pose is not None]


def person_box(view: View, x: float, y: float) -> tuple[int, int, int, int] | None:
    """The box (u0, v0, u1, v1) of an average person standing at (x, y) in the view, None unless all of it is in
    the image (plain floats: it runs for every proposal of the chain)."""
    rot, origin, k = view.pose[:3, :3].tolist(), view.pose[:3, 3].tolist(), view.camera_matrix.tolist()
    ends = []
    for z in (0.0, PERSON[1]):
        d = (x - origin[0], y - origin[1], z - origin[2])
        cx, cy, cz = (rot[0][i] * d[0] + rot[1][i] * d[1] + rot[2][i] * d[2] for i in range(3))  # rot^T d
        if cz <= 0.1:
            return None
        ends.append(((k[0][0] * cx + k[0][1] * cy) / cz + k[0][2], k[1][1] * cy / cz + k[1][2]))
    (u_foot, v_foot), (u_head, v_head) = ends
    height = v_foot - v_head
    width = height * PERSON[0] / PERSON[1]
    centre = (u_foot + u_head) / 2
    box = (int(round(centre - width / 2)), int(round(v_head)), int(round(centre + width / 2)), int(round(v_foot)))
    h, w = view.bins.shape
    if height < 8 or box[0] < 0 or box[1] < 0 or box[2] > w or box[3] > h:
        return None
    return box


def _sources(p: dict):
    w = p["weights"]
    for key in ("proposal_sources", "likelihood_sources"):
        if not any(w.get(s, 0.0) > 0 for s in p[key]):
            return key, f"{p[key]}; expected at least one source with a positive weight under weights"
    missing = [s for s in p["likelihood_sources"] if w.get(s, 0.0) > 0 and s not in p["clutter"]]
    if p["likelihood"] == "pooled" and missing:
        return "clutter", f"has no rate for {', '.join(missing)}; expected one for each likelihood source"


def _move_probabilities(p: dict):
    q = p["move_probabilities"]
    if len(q) != 4 or abs(sum(q) - 1.0) > 1e-9:
        return "move_probabilities", f"{q}; expected 4 values (add, update, remove, swap) summing to 1"


@dataclass(eq=False)
class RjmcmcTracker:
    """The ``rjmcmc`` tracker: seed 001's filter (module docstring). The defaults are its Table 1 where it has them;
    the pooled likelihood's own (p_detect, clutter, looks, newcomer, survival) were measured or chosen on training
    sequences of its room (``crowdsim experiment seed001 --tune``)."""

    weights: dict = param(TABLE1_WEIGHTS, "k_d per detection source (`sensor/batch`, as the detectors name their "
                                          "batches; Table 1)", item=dict(min=0.0))
    proposal_sources: list = param(["laser/legs", "camera_1/fseg", "camera_1/hog", "camera_2/fseg", "camera_2/hog"],
                                   "the sources where targets are born (Eq. 2: the leg detector's persons and the "
                                   "cameras')")
    likelihood_sources: list = param(["laser/blobs", "camera_1/fseg", "camera_1/hog", "camera_2/fseg",
                                      "camera_2/hog"], "the sources the likelihood weighs (Eq. 5: the laser's raw "
                                                       "blobs l_b and the cameras')")
    move_probabilities: list = param([0.15, 0.8, 0.02, 0.03], "q_m of add, update, remove, swap (Table 1)",
                                     item=dict(min=0.0, max=1.0), min_items=4)
    step_variance: float = param(0.09, "m^2, Sigma of the random walk and of every Gaussian kernel (Table 1)",
                                 min=0.0, exclusive_min=True)
    interaction_sd: float = param(0.75, "m, sigma of the MRF (Eq. 4, Table 1)", min=0.0, exclusive_min=True)
    samples: int = param(150, "N, particles kept per cycle (Table 1)", min=1)
    burn_in: int = param(40, "N_B, burn-in steps per cycle (Table 1)", min=0)
    likelihood: str = param("pooled", "pooled: each source's detections a Poisson process of clutter and of the "
                                      "targets, the sources pooled with the weights k_d, each target with a prior "
                                      "(ours); mean: Eq. 5 as written", choices=("pooled", "mean"))
    p_detect: float = param(0.7, "pooled: chance that a source sees a person in its view", min=0.0,
                            exclusive_min=True, max=1.0)
    # measured on training sequences (seed001_room_3 at seed 4000 and _2 at 4001, which the experiment does not use):
    # detections farther than 0.5 m from everyone, over the room's 82 m^2
    clutter: dict = param({"laser/blobs": 0.08, "camera_1/fseg": 0.003, "camera_1/hog": 0.006,
                           "camera_2/fseg": 0.003, "camera_2/hog": 0.006},
                          "pooled: false detections per m^2 and cycle of each likelihood source (measured on "
                          "training sequences of seed 001's room)", item=dict(min=0.0, exclusive_min=True))
    looks: float = param(2.0, "pooled: the independent sources whose evidence the weights k_d (summing to 1) share "
                              "out", min=0.0, exclusive_min=True)
    newcomer: float = param(0.0003, "pooled: prior odds of a person not tracked before, per kernel area (2 pi Sigma "
                                    "= 0.57 m^2)", min=0.0, exclusive_min=True)
    survival: float = param(0.6, "pooled: chance that a tracked person is still there a cycle later", min=0.0,
                            exclusive_min=True, max=0.999)
    birth_floor: float = param(0.01, "least birth density (kernel units): where no detection is, a target can still "
                                     "be removed", min=0.0, exclusive_min=True)
    colour_lambda: float = param(20.0, "lambda of exp(-lambda B^2) (Perez et al. 2002; seed 001: none)", min=0.0)
    alpha: float = param(0.9, "colour model update weight (Eq. 6, Table 1)", min=0.0, max=1.0)
    update_threshold: float = param(0.24, "beta_t: the model follows only closer histograms", min=0.0, max=1.0)
    reid_threshold: float = param(0.1, "beta_o: a new id this close to a gone person's model takes their id",
                                  min=0.0, max=1.0)
    seed: int = param(0, "the filter's random stream (one run = one draw; seed 001 reports eight)")

    CHECKS = (_sources, _move_probabilities)

    def __post_init__(self) -> None:
        """What the chain uses, made from the parameters (which the scenario format has checked)."""
        self._proposal = [s for s in self.proposal_sources if self.weights.get(s, 0.0) > 0]
        self._likelihood = [s for s in self.likelihood_sources if self.weights.get(s, 0.0) > 0]
        self.q = np.asarray(self.move_probabilities, float)
        self.inv_2var = 1.0 / (2.0 * self.step_variance)
        self.step_sd = math.sqrt(self.step_variance)
        # per source, a detection's density from a target at its kernel's peak over the clutter's: p_D N(0; Sigma) /
        # kappa_d (``pooled`` only: ``mean`` has no clutter)
        pooled = self.likelihood == "pooled"
        self.gain = {s: self.p_detect / (2 * math.pi * self.step_variance * self.clutter[s]) if pooled else 0.0
                     for s in self._likelihood}
        # a target's prior odds against no target, in kernel units (per kernel area 2 pi Sigma): ``newcomer`` for one
        # not tracked before; r s / (1 - r s) times its predictive for one that the share r of the last cycle's
        # particles held, s = ``survival``
        self.log_newcomer = math.log(self.newcomer)
        self.reset()

    def reset(self) -> None:
        """A new run: no targets, no colour models, ids from 1, the random stream from ``seed``."""
        self.rng = np.random.default_rng(self.seed)
        self._next_id = 1
        self._views: dict[str, View] = {}
        self._models: dict[int, dict[str, np.ndarray]] = {}  # id -> camera -> colour model
        self._estimate: dict[int, np.ndarray] = {}  # id -> position of the last estimate
        self._born: dict[int, float] = {}
        self._particles: list[tuple[tuple[int, ...], tuple[tuple[float, float], ...]]] = []
        self._stamp: float | None = None
        self._by_id: dict[int, np.ndarray] = {}  # id -> its positions in the last cycle's particles
        self._share: dict[int, float] = {}  # id -> the share of the last cycle's particles holding it

    # -- cameras ---------------------------------------------------------------------------------------------------
    def see(self, frames) -> None:
        """The cameras' latest frames with their calibration (wall cameras; a robot's colour depth camera too), for the
        colour term."""
        self.look(views(frames))

    def look(self, camera_views: list[View]) -> None:
        for view in camera_views:
            self._views[view.name] = view

    # -- one cycle -------------------------------------------------------------------------------------------------
    def update(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        if self._stamp is not None and stamp < self._stamp:
            raise ValueError(f"stamp {stamp} is before the last cycle's {self._stamp}")
        self._prepare(detections)
        self._chain()
        tracks = self._estimate_tracks(stamp, detections)
        self._stamp = stamp
        return tracks

    def _prepare(self, detections: DetectedPersons) -> None:
        """The cycle's detections by source, the birth proposal (Eq. 2) and the last estimate's mask T."""
        xy = detections.position[:, :2]
        originals = detections.originals or {}

        def rows(source):
            ids = originals.get(source)
            return np.zeros(0, np.int64) if ids is None else np.flatnonzero(ids >= 0)

        self._est_xy = np.array(list(self._estimate.values())).reshape(-1, 2)
        self._est_points = self._est_xy.tolist()
        prop = [(rows(s), self.weights[s]) for s in self._proposal]
        prop = [(r, k / len(r)) for r, k in prop if len(r)]
        self._prop_rows = np.concatenate([r for r, _ in prop]) if prop else np.zeros(0, np.int64)
        self._prop_xy = xy[self._prop_rows]
        self._prop_k = np.concatenate([np.full(len(r), w) for r, w in prop]) if prop else np.zeros(0)
        birth = self._prop_k * (1.0 - self._mask(self._prop_xy))
        total = birth.sum()
        self._birth_p = birth / total if total > 0 else birth  # Q_add's mixture weights
        self._birth_cdf = np.cumsum(self._birth_p)
        self._births: list[tuple[float, float, int]] = []  # this cycle's births: where, which id
        like = [(rows(s), s) for s in self._likelihood]
        self._like_xy = np.concatenate([xy[r] for r, _ in like])
        # k_d, summing to 1 over a mode's sources, share out the evidence of ``looks`` independent sources
        self._like_w = np.concatenate([np.full(len(r), self.weights[s] * self.looks) for r, s in like])
        self._like_w_n = np.concatenate([np.full(len(r), self.weights[s] / max(len(r), 1)) for r, s in like])
        self._like_k = np.array([self.weights[s] * self.looks for _, s in like])
        self._like_gain = np.concatenate([np.full(len(r), self.gain[s]) for r, s in like])
        self._like_camera = [s.split("/")[0] if s.split("/")[0] in self._views else None for _, s in like]
        self._histograms: dict[tuple[str, int, int], np.ndarray | None] = {}
        self._boxes: dict[tuple[str, int, int], tuple | None] = {}

    def _mask(self, points: np.ndarray) -> np.ndarray:
        """T(x): the mean kernel of the last estimate's targets at the points (0 with none)."""
        if not len(self._est_xy) or not len(points):
            return np.zeros(len(points))
        d2 = ((points[:, None, :] - self._est_xy[None]) ** 2).sum(axis=2)
        return np.exp(-d2 * self.inv_2var).mean(axis=1)

    def _target(self, x: float, y: float) -> tuple[np.ndarray, float, float]:
        """What a target at (x, y) brings: its kernels at the likelihood's detections, the weighted share of the
        sources that should see it (those cameras whose view holds its whole box, and the laser), and its removal
        weight r (Eq. 3)."""
        g = np.exp(-((self._like_xy[:, 0] - x) ** 2 + (self._like_xy[:, 1] - y) ** 2) * self.inv_2var)
        cost = sum(k for k, camera in zip(self._like_k, self._like_camera)
                   if camera is None or self._box(camera, x, y) is not None)
        if len(self._prop_xy):
            d = float(self._prop_k @ np.exp(-((self._prop_xy[:, 0] - x) ** 2 + (self._prop_xy[:, 1] - y) ** 2)
                                            * self.inv_2var))
        else:
            d = 0.0
        mask = (sum(math.exp(-((x - ex) ** 2 + (y - ey) ** 2) * self.inv_2var) for ex, ey in self._est_points)
                / len(self._est_points) if self._est_points else 0.0)
        return g, cost, max(0.0, 1.0 - d) * mask

    def _log_likelihood(self, kernels: list, cost: float) -> float:
        """log pi_D of a state from its targets' kernels at the detections (a list of [L] arrays) and their summed
        ``cost`` (module docstring)."""
        if not kernels:
            return 0.0 if self.likelihood == "pooled" else math.log(EMPTY_MEAN)
        g = np.array(kernels)
        if self.likelihood == "mean":
            return math.log(float((g @ self._like_w_n).mean()) + EMPTY_MEAN)
        return float(self._like_w @ np.log1p(self._like_gain * g.sum(axis=0))) - self.p_detect * cost

    def _birth_density(self, x: float, y: float) -> float:
        """Q_add at (x, y) in kernel units (the chance of proposing a target there, per kernel area), floored."""
        if not len(self._prop_xy):
            return self.birth_floor
        g = np.exp(-((self._prop_xy[:, 0] - x) ** 2 + (self._prop_xy[:, 1] - y) ** 2) * self.inv_2var)
        return max(float(self._birth_p @ g), self.birth_floor)

    def _phi(self, ax: float, ay: float, bx: float, by: float) -> float:
        """Eq. 4's pair potential."""
        d2 = ((ax - bx) ** 2 + (ay - by) ** 2) / self.interaction_sd ** 2
        return max(1.0 - math.exp(-d2), 1e-300)

    def _log_interaction(self, x: float, y: float, xs: list, ys: list, skip: int = -1) -> float:
        """log prod of phi between (x, y) and the targets (but ``skip``)."""
        return sum(math.log(self._phi(x, y, xs[j], ys[j])) for j in range(len(xs)) if j != skip)

    def _colour(self, target_id: int, x: float, y: float) -> float:
        """-lambda sum_c B_c^2 of the target's models against the box at (x, y) (0 with no model or view)."""
        models = self._models.get(target_id)
        if not models:
            return 0.0
        total = 0.0
        for name, model in models.items():
            h = self._histogram(name, x, y)
            if h is not None:
                total += float(bhattacharyya(h, model)) ** 2
        return -self.colour_lambda * total

    def _box(self, name: str, x: float, y: float) -> tuple | None:
        """``person_box`` in camera ``name`` for the floor cell of (x, y), once per cycle."""
        key = (name, int(math.floor(x / CELL)), int(math.floor(y / CELL)))
        if key not in self._boxes:
            self._boxes[key] = person_box(self._views[name], (key[1] + 0.5) * CELL, (key[2] + 0.5) * CELL)
        return self._boxes[key]

    def _histogram(self, name: str, x: float, y: float) -> np.ndarray | None:
        """The colour histogram of an average person at (x, y) in camera ``name`` (None: not all in view), once per
        floor cell and cycle."""
        key = (name, int(math.floor(x / CELL)), int(math.floor(y / CELL)))
        if key not in self._histograms:
            box = self._box(name, x, y) if name in self._views else None
            self._histograms[key] = None if box is None else histogram(self._views[name].bins, box)
        return self._histograms[key]

    def _chain(self) -> None:
        """Alg. 1: the chain of this cycle; its particles are kept for the estimate and the next cycle."""
        rng = self.rng
        self._by_id = self._last_positions()
        self._share = {i: len(points) / len(self._particles) for i, points in self._by_id.items()}
        state = self.state(*self._initial_state())
        steps = self.samples + self.burn_in
        moves = rng.choice(4, size=steps, p=self.q)
        accept, pick, which = rng.random(steps), rng.random(steps), rng.random(steps)
        noise = rng.standard_normal((steps, 2)) * self.step_sd
        swaps = bool(self._views) and bool(self._models)
        births = len(self._prop_xy) and self._birth_cdf[-1] > 0
        kept = []
        for n in range(steps):
            move, m = moves[n], len(state.ids)
            proposal = None
            if move == 0 and births:
                j = min(int(np.searchsorted(self._birth_cdf, pick[n] * self._birth_cdf[-1])), len(self._prop_xy) - 1)
                proposal = self.propose_add(state, self._prop_xy[j, 0] + noise[n, 0], self._prop_xy[j, 1] + noise[n, 1])
            elif move == 1 and m:
                p = min(int(pick[n] * m), m - 1)
                last = self._by_id.get(state.ids[p])
                cx, cy = (last[min(int(which[n] * len(last)), len(last) - 1)] if last is not None
                          else (state.xs[p], state.ys[p]))
                proposal = self.propose_update(state, p, cx + noise[n, 0], cy + noise[n, 1])
            elif move == 2 and m:
                proposal = self.propose_remove(state, _choose_removal(state.removal, pick[n]))
            elif move == 3 and swaps and m >= 2:
                a = min(int(pick[n] * m), m - 1)
                b = min((k for k in range(m) if k != a),
                        key=lambda k: (state.xs[k] - state.xs[a]) ** 2 + (state.ys[k] - state.ys[a]) ** 2)
                proposal = self.propose_swap(state, a, b)
            if proposal is not None and (proposal[0] >= 0 or accept[n] < math.exp(proposal[0])):
                state = proposal[1]
            if n >= self.burn_in:
                kept.append((tuple(state.ids), tuple(zip(state.xs, state.ys))))
        self._particles = kept

    # -- the moves: each gives log beta (Eq. 1) and the proposed state ---------------------------------------------
    def state(self, ids: list, xs: list, ys: list) -> State:
        """The chain's state of targets ``ids`` at (``xs``, ``ys``) with what the moves need of each."""
        info = [self._target(x, y) for x, y in zip(xs, ys)]
        kernels, costs, removal = [g for g, _, _ in info], [c for _, c, _ in info], [r for _, _, r in info]
        return State(list(ids), list(xs), list(ys), kernels, costs, removal, self._log_likelihood(kernels, sum(costs)))

    def propose_add(self, state: State, x: float, y: float) -> tuple[float, State]:
        """A target at (x, y) (a newcomer, or one of the last cycle's back: ``_birth_id``): likelihood and interaction
        ratios, its prior, and Q_remove q_remove / (Q_add q_add)."""
        g, cost, r = self._target(x, y)
        target = self._birth_id(x, y, state.ids)
        new = State(state.ids + [target], state.xs + [x], state.ys + [y], state.kernels + [g], state.costs + [cost],
                    state.removal + [r], self._log_likelihood(state.kernels + [g], sum(state.costs) + cost))
        log_beta = (new.log_pi - state.log_pi + self._log_interaction(x, y, state.xs, state.ys)
                    + self._prior(target, x, y)
                    + math.log(self.q[2] * _removal_probability(new.removal, len(state.ids)))
                    - math.log(self.q[0] * self._birth_density(x, y)))
        return log_beta, new

    def propose_remove(self, state: State, p: int) -> tuple[float, State]:
        """Target p gone: the reverse of ``propose_add``."""
        keep = [k for k in range(len(state.ids)) if k != p]
        new = State(*([column[k] for k in keep] for column in (state.ids, state.xs, state.ys, state.kernels,
                                                              state.costs, state.removal)),
                    log_pi=0.0)
        new.log_pi = self._log_likelihood(new.kernels, sum(new.costs))
        x, y = state.xs[p], state.ys[p]
        log_beta = (new.log_pi - state.log_pi - self._log_interaction(x, y, state.xs, state.ys, skip=p)
                    - self._prior(state.ids[p], x, y) + math.log(self.q[0] * self._birth_density(x, y))
                    - math.log(self.q[2] * _removal_probability(state.removal, p)))
        return log_beta, new

    def propose_update(self, state: State, p: int, x: float, y: float) -> tuple[float, State]:
        """Target p moved to (x, y): the likelihood's, the interaction's and the colour's ratios (Alg. 1 line 10)."""
        g, cost, r = self._target(x, y)
        new = State(list(state.ids), state.xs[:p] + [x] + state.xs[p + 1:], state.ys[:p] + [y] + state.ys[p + 1:],
                    state.kernels[:p] + [g] + state.kernels[p + 1:], state.costs[:p] + [cost] + state.costs[p + 1:],
                    state.removal[:p] + [r] + state.removal[p + 1:], 0.0)
        new.log_pi = self._log_likelihood(new.kernels, sum(new.costs))
        target = state.ids[p]
        log_beta = (new.log_pi - state.log_pi
                    + self._log_interaction(x, y, state.xs, state.ys, skip=p)
                    - self._log_interaction(state.xs[p], state.ys[p], state.xs, state.ys, skip=p)
                    + self._colour(target, x, y) - self._colour(target, state.xs[p], state.ys[p]))
        return log_beta, new

    def propose_swap(self, state: State, a: int, b: int) -> tuple[float, State]:
        """Targets a and b exchange ids: the colour's ratio (Alg. 1 line 12) and the ids' predictive's, since each
        id's last positions are its prior (the Update move's)."""
        ia, ib = state.ids[a], state.ids[b]
        (xa, ya), (xb, yb) = (state.xs[a], state.ys[a]), (state.xs[b], state.ys[b])
        log_beta = (self._colour(ib, xa, ya) + self._colour(ia, xb, yb) - self._colour(ia, xa, ya)
                    - self._colour(ib, xb, yb)
                    + self._log_predictive(ia, xb, yb) + self._log_predictive(ib, xa, ya)
                    - self._log_predictive(ia, xa, ya) - self._log_predictive(ib, xb, yb))
        ids = list(state.ids)
        ids[a], ids[b] = ib, ia
        return log_beta, State(ids, list(state.xs), list(state.ys), list(state.kernels), list(state.costs),
                               list(state.removal), state.log_pi)

    def _log_predictive(self, target_id: int, x: float, y: float) -> float:
        """log of the id's predictive at (x, y) in kernel units: the mean kernel of its positions in the last cycle's
        particles (0 for an id born this cycle, which has no position prior but the newcomer's)."""
        last = self._by_id.get(target_id)
        if last is None:
            return 0.0
        g = np.exp(-((last[:, 0] - x) ** 2 + (last[:, 1] - y) ** 2) * self.inv_2var).mean()
        return math.log(max(float(g), 1e-300))

    def _prior(self, target_id: int, x: float, y: float) -> float:
        """A target's log prior against its absence (``pooled``; Eq. 5's ``mean`` has none): for an id that the share
        r of the last cycle's particles held, the odds r s / (1 - r s) (s: ``survival``) times its predictive at
        (x, y); for a newcomer, ``newcomer``."""
        if self.likelihood == "mean":
            return 0.0
        share = self._share.get(target_id)
        if share is None:
            return self.log_newcomer
        alive = share * self.survival
        return math.log(alive / (1.0 - alive)) + self._log_predictive(target_id, x, y)

    def _initial_state(self) -> tuple[list, list, list]:
        """Alg. 1 line 1: a random particle of the last cycle holding the estimate's ids, each target moved by
        N(0, Sigma); none before the first estimate."""
        wanted = frozenset(self._estimate)
        pool = [p for p in self._particles if frozenset(p[0]) == wanted] if wanted else []
        if not pool:
            return [], [], []
        ids, points = pool[min(int(self.rng.random() * len(pool)), len(pool) - 1)]
        moved = np.asarray(points, float) + self.rng.standard_normal((len(points), 2)) * self.step_sd
        return list(ids), moved[:, 0].tolist(), moved[:, 1].tolist()

    def _last_positions(self) -> dict[int, np.ndarray]:
        """Each id's positions [k, 2] in the last cycle's particles (the Update move's predictive)."""
        out: dict[int, list] = {}
        for ids, points in self._particles:
            for i, point in zip(ids, points):
                out.setdefault(i, []).append(point)
        return {i: np.asarray(points) for i, points in out.items()}

    def _birth_id(self, x: float, y: float, ids: list) -> int:
        """The id of a target added at (x, y): of the last cycle's targets missing from the state, the one whose
        predictive is highest there, if within two sd (a target removed and added back keeps its id); else that of
        the nearest earlier birth of this cycle within two sd not in the state (so the particles agree on one
        newcomer's id, whichever detection bore it); else a new one."""
        best, best_log = None, -(2 * self.step_sd) ** 2 * self.inv_2var  # the log kernel two sd away
        for i in self._by_id:
            if i not in ids and (value := self._log_predictive(i, x, y)) >= best_log:
                best, best_log = i, value
        if best is not None:
            return best
        best_d2 = (2 * self.step_sd) ** 2
        for bx, by, i in self._births:
            d2 = (bx - x) ** 2 + (by - y) ** 2
            if d2 <= best_d2 and i not in ids:
                best, best_d2 = i, d2
        if best is None:
            best = self._next_id
            self._next_id += 1
            self._births.append((x, y, best))
        return best

    def _estimate_tracks(self, stamp: float, detections: DetectedPersons) -> TrackedPersons:
        """Alg. 1 line 16 and Sec. 5.2.5: the id set most particles hold with each id's mean position; new ids
        re-identified against gone persons' colour models; the models updated by Eq. 6."""
        sets = Counter(frozenset(ids) for ids, _ in self._particles)
        best = sets.most_common(1)[0][0] if sets else frozenset()
        points: dict[int, list] = {i: [] for i in best}
        for ids, pts in self._particles:
            if frozenset(ids) == best:
                for i, point in zip(ids, pts):
                    points[i].append(point)
        estimate = {i: np.mean(points[i], axis=0) for i in sorted(best)}
        spread = {i: np.cov(np.asarray(points[i]).T) if len(points[i]) > 1 else np.eye(2) * 0.09 for i in best}
        rename = self._reidentify(estimate)
        if rename:
            estimate = {rename.get(i, i): p for i, p in estimate.items()}
            spread = {rename.get(i, i): c for i, c in spread.items()}
            self._particles = [(ids if set(rename.values()) & set(ids) else tuple(rename.get(i, i) for i in ids), pts)
                               for ids, pts in self._particles]
        for i, position in estimate.items():
            self._update_model(i, position)
        dt = 0.0 if self._stamp is None else stamp - self._stamp
        order = sorted(estimate)
        n = len(order)
        position = np.array([estimate[i] for i in order]).reshape(n, 2)
        velocity = np.array([(estimate[i] - self._estimate[i]) / dt if i in self._estimate and dt > 0
                             else np.zeros(2) for i in order]).reshape(n, 2)
        self._born = {i: self._born.get(i, stamp) for i in order}  # only the tracked: memory stays flat
        near = np.zeros(n, bool)
        detection_id = np.full(n, -1, np.int64)
        if n and len(self._prop_xy):
            d = np.hypot(*(position[:, None, :] - self._prop_xy[None]).transpose(2, 0, 1))
            nearest = d.argmin(axis=1)
            near = d[np.arange(n), nearest] <= 2 * self.step_sd
            detection_id = np.where(near, detections.detection_id[self._prop_rows[nearest]], -1)
        self._estimate = {i: estimate[i] for i in order}
        return TrackedPersons(stamp, detections.frame, np.array(order, np.int64), near, ~near, detection_id,
                              position, velocity, np.array([spread[i] for i in order]).reshape(n, 2, 2),
                              np.repeat(np.eye(2)[None], n, axis=0),
                              np.array([stamp - self._born[i] for i in order], float))

    def _reidentify(self, estimate: dict) -> dict[int, int]:
        """New ids whose colour matches a gone person's model within beta_o in every camera that sees both: new id
        -> the gone person's id (the closest match)."""
        gone = [i for i in self._models if i not in estimate]
        rename: dict[int, int] = {}
        for i, (x, y) in estimate.items():
            if i in self._estimate or i in self._models or not gone:
                continue
            best, best_b = None, self.reid_threshold
            for g in gone:
                if g in rename.values():
                    continue
                distances = [float(bhattacharyya(h, model)) for name, model in self._models[g].items()
                             if (h := self._histogram(name, x, y)) is not None]
                if distances and max(distances) < best_b:
                    best, best_b = g, max(distances)
            if best is not None:
                rename[i] = best
        return rename

    def _update_model(self, target_id: int, position: np.ndarray) -> None:
        """Eq. 6 in each camera that sees the target whole: the model starts at the histogram there and follows it
        (alpha) while within beta_t of it."""
        for name in self._views:
            h = self._histogram(name, float(position[0]), float(position[1]))
            if h is None:
                continue
            models = self._models.setdefault(target_id, {})
            if name not in models:
                models[name] = h
            elif float(bhattacharyya(h, models[name])) < self.update_threshold:
                models[name] = blend(models[name], h, self.alpha)


def _removal_probability(removal: list, p: int) -> float:
    """The chance that Remove picks target p: half uniform, half by Eq. 3's weights r (all uniform when r are 0)."""
    total = sum(removal)
    if total <= 0:
        return 1.0 / len(removal)
    return 0.5 / len(removal) + 0.5 * removal[p] / total


def _choose_removal(removal: list, u: float) -> int:
    """The target Remove picks for a uniform draw u, with the chances of ``_removal_probability``."""
    m, total = len(removal), sum(removal)
    if total <= 0 or u < 0.5:
        return min(int((u * 2 if total > 0 else u) * m), m - 1)
    target, acc = (u - 0.5) * 2 * total, 0.0
    for p, r in enumerate(removal):
        acc += r
        if target < acc:
            return p
    return m - 1
