"""``crowdsim validate``: the crowd model against the RiMEA verification tests and Weidmann's fundamental diagram.

RiMEA (Richtlinie fuer Mikroskopische Entfluchtungsanalysen) lists tests a pedestrian model should pass; five of
its kind are run here on the social-force crowd of ``crowd.py``, each on a floor plan built in code:

1. RiMEA test 1: one adult walks 40 m of a 2 m wide corridor at 1.33 m/s; the time must lie in 26-34 s.
2. RiMEA test 4: the fundamental diagram. The simulator has no periodic boundary, so a ring corridor stands in for
   one: persons placed at the target density walk round it for ever, and their mean speed along the ring in the
   steady state is compared with Weidmann's (1993) v(rho) = 1.34 [1 - exp(-1.913 (1/rho - 1/5.4))].
3. RiMEA test 6: 20 persons walk round a left corner; none may cross a wall.
4. RiMEA test 7: the free walking speeds of each agent type must follow the configured distribution.
5. Bottleneck flow against the bottleneck's width: the flow must grow with the width, as in Seyfried et al. 2009.

Every run is watched at every step: the largest overlap of two bodies and the least clearance between a body and a
wall (a body whose centre is nearer a wall than its radius, or on the wrong side of one, is inside it).
``run_validation`` writes ``report.md``, ``validation.json`` and one PNG per test.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from scipy.stats import norm  # noqa: E402
from tqdm import tqdm  # noqa: E402

from scenarios import scenario_from_dict  # noqa: E402
from scenarios.geometry import inside_polygon, pair_vectors  # noqa: E402
from scenarios.typed import Scenario, plain  # noqa: E402

from .crowd import Crowd  # noqa: E402

DT = 0.04  # s, the project's simulation step
WALL_TOL = 1e-9  # m: a body may touch a wall, not enter it
LASERS = [{"name": "front_laser", "mount": [0.25, 0, 0]}, {"name": "rear_laser", "mount": [-0.25, 0, float(np.pi)]}]

# Weidmann 1993 (Transporttechnik der Fussgaenger, ETH Zuerich, Schriftenreihe IVT 90): free speed 1.34 m/s,
# gamma 1.913 persons/m^2, jam density 5.4 persons/m^2
WEIDMANN_V0, WEIDMANN_GAMMA, WEIDMANN_RHO_MAX = 1.34, 1.913, 5.4
WEIDMANN_TOLERANCE = 0.25  # relative; the criterion holds at the densities in WEIDMANN_CHECKED
WEIDMANN_CHECKED = (0.5, 1.0, 2.0, 3.0)
# Seyfried, Passon, Steffen, Boltes, Rupprecht, Klingsch 2009, "New insights into pedestrian flow through
# bottlenecks", Transportation Science 43(3) 395-406 (arXiv physics/0702004): the flow grows linearly with the
# width. The band of specific flows drawn and counted against, about 1.6-2.0 persons/(m s), is the range quoted for
# such experiments; it is reported, not a pass criterion (the criterion is that J grows with w)
SEYFRIED_SPECIFIC_FLOW = (1.6, 2.0)


def weidmann(rho) -> np.ndarray:
    """Weidmann's speed-density relation in m/s (0 at and beyond the jam density 5.4 persons/m^2)."""
    rho = np.asarray(rho, float)
    with np.errstate(divide="ignore"):
        v = WEIDMANN_V0 * (1.0 - np.exp(-WEIDMANN_GAMMA * (1.0 / rho - 1.0 / WEIDMANN_RHO_MAX)))
    return np.clip(v, 0.0, None)


# -- floor plans, placement, and the watch over every step ------------------------------------------------------


def _scenario(name: str, walls: list, waypoints: dict, routes: dict, params: dict | None = None,
              robot_at: list | None = None) -> Scenario:
    """A validation scenario: the model's defaults, but no random force (the checks measure the model itself). The
    crowd runs without the robot; the robot the format requires stands in the floor plan, at ``robot_at`` or else
    the first waypoint."""
    first = robot_at or next(iter(waypoints.values()), {"position": [0.0, 0.0]})["position"]
    return scenario_from_dict({
        "name": name,
        "crowd": {"random_force": 0.0, **(params or {})},
        "map": {"walls": [np.asarray(w, float).tolist() for w in walls]},
        "waypoints": waypoints,
        "routes": routes,
        "robot": {"start": [*first, 0.0]},
        "sensors": {"lasers": LASERS},
    }, source=f"<validation {name}>")


def _circle(radius: float, segments: int, centre=(0.0, 0.0)) -> np.ndarray:
    """A closed polyline (first point repeated last) with its vertices on the circle."""
    a = np.linspace(0.0, 2 * np.pi, segments + 1)
    a[-1] = 0.0
    return np.stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)], 1)


def _polygon_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


class Region:
    """The walkable floor: inside ``outer`` and outside every hole (polygons, even-odd rule)."""

    def __init__(self, outer: np.ndarray, holes: tuple = ()):
        self.outer = np.asarray(outer, float)
        self.holes = [np.asarray(h, float) for h in holes]

    def contains(self, points: np.ndarray) -> np.ndarray:
        inside = inside_polygon(points, self.outer)
        for h in self.holes:
            inside &= ~inside_polygon(points, h)
        return inside


class Watch:
    """Checks every step of a run: the largest agent-agent overlap, the least body-wall clearance, and how many
    bodies were ever inside a wall (clearance below -1e-9 m) or on the wrong side of one (outside the region)."""

    REPORT_RANGE = 0.5  # m: clearances up to this are measured exactly; a body farther from every wall is clear

    def __init__(self, walls: np.ndarray, region: Region | None):
        self.walls = walls
        self.region = region
        if len(walls):  # broad phase: a body within r of a segment lies within r + half its length of its middle
            self._mid = cKDTree(walls.mean(axis=1))
            self._half = float(np.linalg.norm(walls[:, 1] - walls[:, 0], axis=1).max()) / 2
        self.max_overlap = 0.0
        self.min_clearance = np.inf  # over bodies within REPORT_RANGE of a wall
        self.inside_wall = 0  # body-steps
        self.wrong_side = 0  # body-steps
        self.steps = 0

    def __call__(self, crowd: Crowd) -> None:
        pos, r = crowd.pos, crowd.radius
        self.steps += 1
        if len(pos) == 0:
            return
        if len(self.walls):
            near = cKDTree(pos).sparse_distance_matrix(self._mid, float(r.max()) + self._half + self.REPORT_RANGE,
                                                       output_type="ndarray")
            if len(near):
                k, s = near["i"], near["j"]
                clearance = pair_vectors(pos, self.walls, k, s)[1] - r[k]
                self.min_clearance = min(self.min_clearance, float(clearance.min()))
                self.inside_wall += len(np.unique(k[clearance < -WALL_TOL]))
        if self.region is not None:
            self.wrong_side += int((~self.region.contains(pos)).sum())
        if len(pos) > 1:
            pairs = cKDTree(pos).query_pairs(2 * float(r.max()), output_type="ndarray")
            if len(pairs):
                i, j = pairs.T
                overlap = r[i] + r[j] - np.linalg.norm(pos[i] - pos[j], axis=1)
                self.max_overlap = max(self.max_overlap, float(overlap.max()))

    @property
    def ok(self) -> bool:
        return self.inside_wall == 0 and self.wrong_side == 0

    def summary(self) -> dict:
        return {"max_overlap_m": self.max_overlap,
                "min_wall_clearance_m": None if not np.isfinite(self.min_clearance) else self.min_clearance,
                "body_steps_inside_wall": self.inside_wall, "body_steps_wrong_side": self.wrong_side,
                "steps_checked": self.steps}


def _merge_safety(watches: list[Watch]) -> dict:
    clear = [w.min_clearance for w in watches if np.isfinite(w.min_clearance)]
    return {"max_overlap_m": max((w.max_overlap for w in watches), default=0.0),
            "min_wall_clearance_m": min(clear) if clear else None,
            "body_steps_inside_wall": sum(w.inside_wall for w in watches),
            "body_steps_wrong_side": sum(w.wrong_side for w in watches),
            "steps_checked": sum(w.steps for w in watches), "walls_ok": all(w.ok for w in watches)}


def place_discs(rng: np.random.Generator, n: int, radius: float, sample, outside, gap: float = 5e-4,
                rounds: int = 4) -> np.ndarray | None:
    """``n`` non-overlapping discs of ``radius`` at random in an area, or None where they could not be fitted.

    ``sample(rng, n)`` draws centres uniformly in the area's centre region (the floor shrunk by the radius);
    ``outside(p)`` gives each centre's vector out of that region (zero inside). Overlaps are removed by minimising
    the harmonic overlap energy (L-BFGS); random starts unjam up to 4 persons/m^2 of 0.25 m discs (area fraction
    0.79) in the ring here, not at 4.2 (near random close packing), so such densities are reported as not set up.
    """
    d0 = 2 * radius + 2 * gap

    def energy(x):
        p = x.reshape(-1, 2)
        g = np.zeros_like(p)
        e = 0.0
        pairs = cKDTree(p).query_pairs(d0, output_type="ndarray") if n > 1 else np.zeros((0, 2), int)
        if len(pairs):
            i, j = pairs.T
            d = p[j] - p[i]
            dist = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
            ov = d0 - dist
            e += float((ov**2).sum())
            gj = (-2 * ov / dist)[:, None] * d
            g += np.stack([np.bincount(j, gj[:, 0], n) - np.bincount(i, gj[:, 0], n),
                           np.bincount(j, gj[:, 1], n) - np.bincount(i, gj[:, 1], n)], 1)
        out = outside(p)
        e += float((out**2).sum())
        g += 2 * out
        return e, g.ravel()

    p = sample(rng, n)
    for _ in range(rounds):
        p = minimize(energy, p.ravel(), jac=True, method="L-BFGS-B",
                     options={"maxiter": 5000, "ftol": 0.0, "gtol": 1e-12}).x.reshape(-1, 2)
        close = cKDTree(p).query_pairs(2 * radius, output_type="ndarray") if n > 1 else []
        if len(close) == 0 and np.abs(outside(p)).max(initial=0.0) <= gap:
            return p
        p = p + rng.normal(0.0, 0.01, p.shape)  # shake a jammed packing and try again
    return None


def _box(lo, hi):
    """``sample`` and ``outside`` for a rectangle of centres."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return (lambda rng, n: rng.uniform(lo, hi, (n, 2))), (lambda p: np.minimum(p - lo, 0) + np.maximum(p - hi, 0))


def _annulus(r_lo: float, r_hi: float):
    """``sample`` and ``outside`` for an annulus of centres about the origin."""

    def sample(rng, n):
        rho, a = np.sqrt(rng.uniform(r_lo**2, r_hi**2, n)), rng.uniform(0, 2 * np.pi, n)
        return np.stack([rho * np.cos(a), rho * np.sin(a)], 1)

    def outside(p):
        rho = np.maximum(np.linalg.norm(p, axis=1), 1e-12)
        return ((rho - np.clip(rho, r_lo, r_hi)) / rho)[:, None] * p

    return sample, outside


# -- RiMEA test 1: a straight corridor ---------------------------------------------------------------------------


def rimea1(quick: bool = False, plot_dir: Path | None = None, seed: int = 1, params: dict | None = None) -> dict:
    """One adult at 1.33 m/s from rest along 40 m of a 2 m corridor; the time to cover the 40 m."""
    length, width, speed, limit = 40.0, 2.0, 1.33, 60.0
    # the corridor runs on 2.5 m beyond both ends, out of the walls' 2 m reach, so no end wall pushes or brakes
    x0, x1 = -2.5, length + 2.5
    walls = [[[x0, 0], [x1, 0], [x1, width], [x0, width], [x0, 0]]]
    sc = _scenario("rimea1", walls, {"end": {"position": [length + 1.5, width / 2], "radius": 0.5}},
                   {"r": {"waypoints": ["end"], "sink": False}}, params)
    crowd = Crowd(sc, np.random.default_rng(seed))
    watch = Watch(crowd.walls, Region(np.array(walls[0][:-1], float)))
    crowd.add_walkers(np.array([[0.0, width / 2]]), "r", desired_speed=speed)
    t, x, v, arrival, lateral = [0.0], [0.0], [0.0], None, 0.0
    while crowd.t < limit and arrival is None:
        before = crowd.pos[0, 0]
        crowd.step(DT)
        watch(crowd)
        t.append(crowd.t)
        x.append(crowd.pos[0, 0])
        v.append(float(np.linalg.norm(crowd.vel[0])))
        lateral = max(lateral, abs(float(crowd.pos[0, 1]) - width / 2))
        if crowd.pos[0, 0] >= length:  # the crossing of the 40 m line, interpolated within the step
            arrival = crowd.t - DT * (crowd.pos[0, 0] - length) / max(crowd.pos[0, 0] - before, 1e-12)
    passed = arrival is not None and 26.0 <= arrival <= 34.0 and watch.ok
    result = {
        "name": "RiMEA 1", "title": "RiMEA test 1: straight corridor, 40 m x 2 m",
        "criterion": "time for 40 m at 1.33 m/s in 26-34 s",
        "measured": f"{arrival:.2f} s" if arrival is not None else f"not there after {limit:g} s",
        "passed": bool(passed),
        "values": {"walking_time_s": arrival, "ideal_time_s": length / speed,
                   "mean_speed_m_s": length / arrival if arrival else None, "desired_speed_m_s": speed,
                   "max_lateral_deviation_m": lateral},
        "safety": _merge_safety([watch]),
    }
    if plot_dir is not None:
        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(t, v, color="tab:blue", label="speed")
        ax.axhline(speed, color="0.4", ls="--", lw=1, label="desired speed 1.33 m/s")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("speed [m/s]")
        ax2 = ax.twinx()
        ax2.plot(t, x, color="tab:orange", label="distance")
        ax2.axhline(length, color="tab:orange", ls=":", lw=1)
        ax2.set_ylabel("distance walked [m]")
        ax.axvspan(26, 34, color="tab:green", alpha=0.12, label="RiMEA window 26-34 s")
        if arrival:
            ax.axvline(arrival, color="tab:green", lw=1.5)
        ax.set_title(f"RiMEA 1: 40 m in {result['measured']} ({'pass' if passed else 'FAIL'})")
        ax.legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        fig.savefig(plot_dir / "rimea1_corridor.png", dpi=100)
        plt.close(fig)
        result["plot"] = "rimea1_corridor.png"
    return result


# -- RiMEA test 4: the fundamental diagram on a ring -------------------------------------------------------------


def _ring_scenario(centre_radius: float, width: float, segments: int, lookahead: float, spacing: float = 0.5,
                   params: dict | None = None):
    """A ring corridor about the origin and K looped routes, route k starting at waypoint k.

    The waypoints lie on a circle of radius sqrt(R^2 + L^2) and are reached within L (the lookahead) of them, so a
    walker always heads for a point about L ahead: on the centre line (radius R) that point is on the tangent, so
    walkers follow the centre line without being drawn inwards, and one pushed off it is steered gently back.
    L exceeds the corridor's width, so nobody can pass a waypoint without reaching it (and turn back for it).
    """
    r_out, r_in = centre_radius + width / 2, centre_radius - width / 2
    r_wp = math.hypot(centre_radius, lookahead)
    count = int(round(2 * np.pi * r_wp / spacing))
    ang = 2 * np.pi * np.arange(count) / count
    wps = {f"w{k}": {"position": [float(r_wp * np.cos(a)), float(r_wp * np.sin(a))], "radius": lookahead}
           for k, a in enumerate(ang)}
    routes = {f"ring{k}": {"waypoints": [f"w{(k + i) % count}" for i in range(count)], "sink": False}
              for k in range(count)}
    outer, inner = _circle(r_out, segments), _circle(r_in, segments)
    # room for the densest ring (sizes the contact solver's spatial hash; sources are none here)
    most = int(2 * np.pi * centre_radius * width * 4.7) + 1
    sc = _scenario("rimea4_ring", [outer, inner], wps, routes, {"max_agents": most, **(params or {})})
    region = Region(outer[:-1], [inner[:-1]])
    area = _polygon_area(outer[:-1]) - _polygon_area(inner[:-1])
    # the polygon's chords lie inside the outer circle: centres keep the radius from them, and from the inner one
    centre_lo, centre_hi = r_in, r_out * np.cos(np.pi / segments)
    return sc, region, area, (centre_lo, centre_hi), r_wp, lookahead, count


def ring_run(density: float, quick: bool = False, seed: int = 0, params: dict | None = None) -> dict:
    """Persons at ``density`` (persons/m^2 of the ring's floor) walking round the ring; their mean speed along it."""
    if quick:
        R, W, segments, warmup, measure = 10.0, 4.0, 128, 10.0, 10.0
    else:
        R, W, segments, warmup, measure = 10.0, 4.0, 128, 20.0, 20.0
    sc, region, area, (lo, hi), r_wp, lookahead, count = _ring_scenario(R, W, segments, W + 0.5, params=params)
    radius = sc.crowd.agent_types["adult"].radius
    n = int(round(density * area))
    out = {"density_target": density, "ring_centre_radius_m": R, "ring_width_m": W, "area_m2": area, "agents": n,
           "warmup_s": warmup, "measure_s": measure}
    hex_limit = 1.0 / (2 * np.sqrt(3) * radius**2)
    if density >= hex_limit:
        out["set_up"] = False
        out["why"] = (f"{density:g} persons/m^2 of {radius:g} m discs exceeds the densest packing of discs "
                      f"({hex_limit:.2f} persons/m^2, hexagonal)")
        return out
    rng = np.random.default_rng(seed)
    pos = place_discs(rng, n, radius, *_annulus(lo + radius, hi - radius))
    if pos is None:
        out["set_up"] = False
        out["why"] = f"{n} discs of radius {radius:g} m could not be placed in the ring without overlaps"
        return out
    crowd = Crowd(sc, rng)
    # each walker starts on the route whose first waypoint lies about the lookahead ahead of it (counter-clockwise)
    theta = np.arctan2(pos[:, 1], pos[:, 0])
    first = np.ceil((theta + lookahead / r_wp) / (2 * np.pi / count)).astype(int) % count
    for k in np.unique(first):
        crowd.add_walkers(pos[first == k], f"ring{k}", agent_type="adult")
    watch = Watch(crowd.walls, region)
    steps_w, steps_m = int(round(warmup / DT)), int(round(measure / DT))
    series = np.zeros(steps_w + steps_m)
    per_agent = np.zeros(len(crowd.id))
    for s in range(steps_w + steps_m):
        crowd.step(DT)
        watch(crowd)
        a = np.arctan2(crowd.pos[:, 1], crowd.pos[:, 0])
        v_t = crowd.vel[:, 1] * np.cos(a) - crowd.vel[:, 0] * np.sin(a)  # along the ring, counter-clockwise
        series[s] = v_t.mean()
        if s >= steps_w:
            per_agent += v_t
    per_agent /= steps_m
    density_real = len(crowd.id) / area
    speed = float(per_agent.mean())
    out.update({"set_up": True, "agents": int(len(crowd.id)), "density": density_real, "speed_m_s": speed,
                "speed_std_agents_m_s": float(per_agent.std()),
                "speed_std_time_m_s": float(series[steps_w:].std()),
                "weidmann_m_s": float(weidmann(density_real)),
                "relative_error": float(speed / weidmann(density_real) - 1.0) if weidmann(density_real) > 0
                else None,
                "mean_desired_speed_m_s": float(crowd.v0.mean()),
                "series_t": (np.arange(1, len(series) + 1) * DT)[::5].tolist(), "series_v": series[::5].tolist(),
                "safety": watch.summary(), "walls_ok": watch.ok, "_watch": watch})
    return out


def fundamental_diagram(quick: bool = False, plot_dir: Path | None = None, seed: int = 0,
                        densities: tuple | None = None, params: dict | None = None) -> dict:
    if densities is None:
        densities = (0.5, 1.0, 2.0, 3.0) if quick else (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
    runs = [ring_run(d, quick, seed + k, params) for k, d in enumerate(densities)]
    watches = [r.pop("_watch") for r in runs if "_watch" in r]
    checked = [r for r in runs if r["density_target"] in WEIDMANN_CHECKED]
    good = [r for r in checked if r["set_up"] and abs(r["relative_error"]) <= WEIDMANN_TOLERANCE]
    missing = [r["density_target"] for r in runs if not r["set_up"]]
    safety = _merge_safety(watches)
    passed = len(good) == len(checked) and safety["walls_ok"]
    parts = [f"{r['density_target']:g}: {r['speed_m_s']:.2f} vs {r['weidmann_m_s']:.2f} m/s "
             f"({100 * r['relative_error']:+.0f}%)" for r in runs if r["set_up"]]
    measured = "; ".join(parts)
    if missing:
        measured += "; not set up: " + ", ".join(f"{d:g}" for d in missing) + " persons/m^2"
    result = {
        "name": "RiMEA 4 / Weidmann", "title": "RiMEA test 4: fundamental diagram (ring corridor) against Weidmann",
        "criterion": "mean speed within 25% of Weidmann's at "
                     + ", ".join(f"{d:g}" for d in WEIDMANN_CHECKED if d in densities) + " persons/m^2",
        "measured": measured, "passed": bool(passed),
        "values": {"runs": runs, "not_set_up": missing,
                   "checked_densities": [r["density_target"] for r in checked]},
        "safety": safety,
    }
    if plot_dir is not None:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
        rho = np.linspace(0.2, WEIDMANN_RHO_MAX, 300)
        v = weidmann(rho)
        ax.plot(rho, v, color="k", label="Weidmann 1993")
        ax.fill_between(rho, 0.75 * v, 1.25 * v, color="0.85", label="+-25%")
        ok = [r for r in runs if r["set_up"]]
        if ok:
            ax.errorbar([r["density"] for r in ok], [r["speed_m_s"] for r in ok],
                        yerr=[r["speed_std_agents_m_s"] for r in ok], fmt="o", color="tab:red", capsize=4,
                        label="crowdsim (mean, std over persons)")
        for d in missing:
            ax.axvline(d, color="tab:red", ls=":", lw=1)
            ax.text(d, 1.45, "not set up", rotation=90, va="top", ha="right", fontsize=7, color="tab:red")
        ax.set_xlim(0, 6.3)
        ax.set_ylim(0, 1.6)
        ax.set_xlabel("density [persons/m^2]")
        ax.set_ylabel("mean speed along the ring [m/s]")
        ax.set_title(f"Fundamental diagram ({'pass' if passed else 'FAIL'})")
        ax.legend(fontsize=8)
        for r in ok:
            ax2.plot(r["series_t"], r["series_v"], lw=1, label=f"{r['density_target']:g} p/m^2")
        if ok:
            ax2.axvline(ok[0]["warmup_s"], color="0.4", ls="--", lw=1)
        ax2.set_xlabel("t [s] (measured after the dashed line)")
        ax2.set_ylabel("crowd mean speed along the ring [m/s]")
        ax2.set_title("time series")
        ax2.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(plot_dir / "rimea4_fundamental_diagram.png", dpi=100)
        plt.close(fig)
        result["plot"] = "rimea4_fundamental_diagram.png"
    for r in runs:  # the time series are in the plot; the JSON keeps the numbers
        r.pop("series_t", None)
        r.pop("series_v", None)
    return result


# -- RiMEA test 6: round a corner --------------------------------------------------------------------------------


def rimea6(quick: bool = False, plot_dir: Path | None = None, seed: int = 6, params: dict | None = None) -> dict:
    """20 persons from the first 6 m of a 2 m corridor round a left corner; no one may cross a wall."""
    n, width, arm, limit = 20, 2.0, 12.0, 60.0
    outline = np.array([[0, 0], [arm, 0], [arm, arm], [arm - width, arm], [arm - width, width], [0, width]], float)
    walls = [np.vstack([outline, outline[:1]])]
    wps = {"corner": {"position": [arm - width / 2, width / 2], "radius": 1.0},
           "exit": {"position": [arm - width / 2, arm - 1.0], "radius": 0.8}}
    sc = _scenario("rimea6", walls, wps, {"r": {"waypoints": ["corner", "exit"], "sink": True}}, params)
    rng = np.random.default_rng(seed)
    crowd = Crowd(sc, rng)
    radius = crowd.types.radius[crowd.types.names.index("adult")]
    margin = radius + 0.02
    pos = place_discs(rng, n, radius, *_box([margin, margin], [6.0 - margin, width - margin]))
    crowd.add_walkers(pos, "r")
    watch = Watch(crowd.walls, Region(outline))
    tracks: dict[int, list] = {int(i): [p] for i, p in zip(crowd.id, pos)}
    arrived = 0
    while len(crowd.id) and crowd.t < limit:
        alive = crowd.id.copy()
        crowd.step(DT)
        watch(crowd)
        arrived += len(np.setdiff1d(alive, crowd.id))
        for i, p in zip(crowd.id.tolist(), crowd.pos):
            tracks[i].append(p.copy())
    safety = _merge_safety([watch])
    passed = safety["walls_ok"] and arrived == n
    result = {
        "name": "RiMEA 6", "title": "RiMEA test 6: 20 persons round a left corner",
        "criterion": "no body ever inside or across a wall (every step); all 20 round the corner",
        "measured": f"{arrived}/{n} round the corner in {crowd.t:.1f} s; least wall clearance "
                    f"{safety['min_wall_clearance_m']:.3f} m; inside/wrong side: "
                    f"{safety['body_steps_inside_wall']}/{safety['body_steps_wrong_side']} body-steps",
        "passed": bool(passed),
        "values": {"agents": n, "arrived": arrived, "time_s": crowd.t},
        "safety": safety,
    }
    if plot_dir is not None:
        fig, ax = plt.subplots(figsize=(6, 6))
        ax.plot(walls[0][:, 0], walls[0][:, 1], color="0.1", lw=2)
        cmap = plt.get_cmap("tab20")
        for k, xy in enumerate(tracks.values()):
            xy = np.asarray(xy)
            ax.plot(xy[:, 0], xy[:, 1], color=cmap(k % 20), lw=0.9)
            ax.plot(*xy[0], "o", color=cmap(k % 20), ms=3)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"RiMEA 6: {arrived}/{n} round the corner ({'pass' if passed else 'FAIL'})")
        fig.tight_layout()
        fig.savefig(plot_dir / "rimea6_corner.png", dpi=100)
        plt.close(fig)
        result["plot"] = "rimea6_corner.png"
    return result


# -- RiMEA test 7: demographic speed distributions ---------------------------------------------------------------


def free_speeds(agent_type: str, n: int, quick: bool = False, seed: int = 7,
                params: dict | None = None) -> tuple[np.ndarray, dict]:
    """Free walking speeds of ``n`` persons of ``agent_type``, each alone in its own lane.

    Lanes are 6 m apart (beyond the 5 m neighbour search) and 3 m from the walls (beyond their 2 m reach), so
    nothing acts on a walker but its desired force; the random force is off, since it is a perturbation of the
    walk, not part of the desired speed. A speed is the distance walked over a window that starts 5 s (10 relaxation
    times) after the start from rest, where the walker has reached its desired speed to 5e-5.
    """
    lane, length = 6.0, 60.0
    t0, t1 = (5.0, 10.0) if quick else (5.0, 15.0)
    ys = 3.0 + lane * np.arange(n)
    top = float(ys[-1] + 3.0)
    room = [[0, 0], [length, 0], [length, top], [0, top], [0, 0]]
    wps = {f"g{k}": {"position": [length - 3.0, float(y)], "radius": 0.3} for k, y in enumerate(ys)}
    routes = {f"lane{k}": {"waypoints": [f"g{k}"], "sink": False} for k in range(n)}
    sc = _scenario("rimea7", [room], wps, routes, params)
    crowd = Crowd(sc, np.random.default_rng(seed))
    for k, y in enumerate(ys):
        crowd.add_walkers(np.array([[3.0, y]]), f"lane{k}", agent_type=agent_type)
    watch = Watch(crowd.walls, Region(np.array(room[:-1], float)))
    start = None
    for s in range(int(round(t1 / DT))):
        crowd.step(DT)
        watch(crowd)
        if s + 1 == int(round(t0 / DT)):
            start = crowd.pos.copy()
    speeds = np.linalg.norm(crowd.pos - start, axis=1) / (t1 - t0)
    return speeds, {"desired": crowd.v0.copy(), "watch": watch, "params": sc.crowd.agent_types[agent_type]}


def _clipped_normal_moments(mean, std, lo, hi) -> tuple[float, float]:
    """Mean and std of clip(N(mean, std), lo, hi) (the draw ``Crowd`` makes)."""
    a, b = (lo - mean) / std, (hi - mean) / std
    pa, pb = norm.cdf(a), norm.cdf(b)
    # E[X; a<Z<b] = mean (pb - pa) + std (phi(a) - phi(b)); E[X^2; ...] from the truncated normal's moments
    m1 = mean * (pb - pa) + std * (norm.pdf(a) - norm.pdf(b))
    m2 = ((mean**2 + std**2) * (pb - pa) + 2 * mean * std * (norm.pdf(a) - norm.pdf(b))
          + std**2 * (a * norm.pdf(a) - b * norm.pdf(b)))
    e1 = lo * pa + m1 + hi * (1 - pb)
    e2 = lo**2 * pa + m2 + hi**2 * (1 - pb)
    return float(e1), float(np.sqrt(max(e2 - e1**2, 0.0)))


def rimea7(quick: bool = False, plot_dir: Path | None = None, seed: int = 7, n: int = 50,
           params: dict | None = None) -> dict:
    """Each agent type's measured free speeds: all within [speed_min, speed_max], the mean near speed_mean."""
    types = _scenario("rimea7_types", [], {}, {}, params).crowd.agent_types
    measured_tol = 1e-3  # m/s: the measurement's own error (the relaxation's tail, rounding) is far below this
    per_type, watches, passed, parts = {}, [], True, []
    for k, (name, p) in enumerate(types.items()):
        speeds, extra = free_speeds(name, n, quick, seed + k, params)
        watches.append(extra["watch"])
        in_range = (speeds >= p.speed_min - measured_tol) & (speeds <= p.speed_max + measured_tol)
        tolerance = 3 * p.speed_std / np.sqrt(n)  # 3 standard errors of the mean of n draws
        mean = float(speeds.mean())
        ok = bool(in_range.all() and abs(mean - p.speed_mean) <= tolerance)
        passed &= ok
        exp_mean, exp_std = _clipped_normal_moments(p.speed_mean, p.speed_std, p.speed_min, p.speed_max)
        per_type[name] = {"n": n, "configured": plain(p), "mean_m_s": mean, "std_m_s": float(speeds.std(ddof=1)),
                          "min_m_s": float(speeds.min()), "max_m_s": float(speeds.max()),
                          "out_of_range": int((~in_range).sum()), "mean_tolerance_m_s": float(tolerance),
                          "clipped_normal_mean_m_s": exp_mean, "clipped_normal_std_m_s": exp_std,
                          "max_abs_error_vs_desired_m_s": float(np.abs(speeds - extra["desired"]).max()),
                          "speeds_m_s": speeds.tolist(), "passed": ok}
        parts.append(f"{name}: mean {mean:.3f} (cfg {p['speed_mean']:g} +- {tolerance:.3f}), range "
                     f"{speeds.min():.2f}-{speeds.max():.2f} in [{p['speed_min']:g}, {p['speed_max']:g}]")
    safety = _merge_safety(watches)
    passed &= safety["walls_ok"]
    result = {
        "name": "RiMEA 7", "title": "RiMEA test 7: demographic walking speeds per agent type",
        "criterion": f"every free speed (alone, random force off) in [speed_min, speed_max] (+-{measured_tol:g} "
                     "m/s); mean within 3 std/sqrt(n) of speed_mean",
        "measured": "; ".join(parts), "passed": bool(passed), "values": per_type, "safety": safety,
    }
    if plot_dir is not None:
        fig, axes = plt.subplots(1, len(per_type), figsize=(4.2 * len(per_type), 3.8), squeeze=False)
        for ax, (name, r) in zip(axes[0], per_type.items()):
            p = r["configured"]
            ax.hist(r["speeds_m_s"], bins=np.linspace(p["speed_min"] - 0.1, p["speed_max"] + 0.1, 20), density=True,
                    color="tab:blue", alpha=0.6, label=f"measured (n={r['n']})")
            x = np.linspace(p["speed_min"], p["speed_max"], 200)
            ax.plot(x, norm.pdf(x, p["speed_mean"], p["speed_std"]), color="k", lw=1.2, label="configured N(m, s)")
            for b in (p["speed_min"], p["speed_max"]):
                ax.axvline(b, color="tab:red", ls="--", lw=1)
            ax.axvline(r["mean_m_s"], color="tab:blue", lw=1.5)
            ax.set_title(f"{name}: mean {r['mean_m_s']:.2f} m/s ({'pass' if r['passed'] else 'FAIL'})")
            ax.set_xlabel("free walking speed [m/s]")
            ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(plot_dir / "rimea7_speed_distributions.png", dpi=100)
        plt.close(fig)
        result["plot"] = "rimea7_speed_distributions.png"
    return result


# -- bottleneck flow against width -------------------------------------------------------------------------------


def bottleneck_run(width: float, n: int, seed: int = 0, limit: float = 200.0, params: dict | None = None) -> dict:
    """``n`` persons leave a 10 m x 10 m room through a 2 m long bottleneck of ``width``; the steady flow through it.

    The flow is taken between the 10% and the 90% quantiles of the crossing times of the line across the
    bottleneck's middle (the first and last persons do not see a steady state).
    """
    side, length = 10.0, 2.0
    y_lo, y_hi = side / 2 - width / 2, side / 2 + width / 2
    x_end = side + length
    walls = [[[side, y_hi], [side, side], [0, side], [0, 0], [side, 0], [side, y_lo], [x_end, y_lo]],
             [[side, y_hi], [x_end, y_hi]]]
    far = 40.0
    floor = np.array([[0, 0], [side, 0], [side, y_lo], [x_end, y_lo], [x_end, -far], [x_end + far, -far],
                      [x_end + far, side + far], [x_end, side + far], [x_end, y_hi], [side, y_hi], [side, side],
                      [0, side]], float)
    sc = _scenario("bottleneck", walls, {"out": {"position": [x_end + 3.0, side / 2], "radius": 1.5}},
                   {"r": {"waypoints": ["out"], "sink": True}}, params, robot_at=[side / 2, side / 2])
    rng = np.random.default_rng(seed)
    crowd = Crowd(sc, rng)
    radius = crowd.types.radius[crowd.types.names.index("adult")]
    margin = radius + 0.05
    pos = place_discs(rng, n, radius, *_box([margin, margin], [side - margin - 1.0, side - margin]))
    crowd.add_walkers(pos, "r")
    watch = Watch(crowd.walls, Region(floor))
    line = side + length / 2
    crossed = np.full(int(crowd.id.max()) + 1, np.nan)  # crossing time by id
    while len(crowd.id) and crowd.t < limit:
        crowd.step(DT)
        watch(crowd)
        new = crowd.id[(crowd.pos[:, 0] >= line) & np.isnan(crossed[crowd.id])]
        crossed[new] = crowd.t
    times = np.sort(crossed[np.isfinite(crossed)])
    k0, k1 = int(0.1 * len(times)), len(times) - 1 - int(0.1 * len(times))
    flow = (k1 - k0) / (times[k1] - times[k0]) if k1 > k0 and times[k1] > times[k0] else float("nan")
    return {"width_m": width, "agents": n, "crossed": int(len(times)), "flow_p_s": float(flow),
            "specific_flow_p_m_s": float(flow / width), "first_s": float(times[0]) if len(times) else None,
            "last_s": float(times[-1]) if len(times) else None, "steady_from_s": float(times[k0]) if k1 > k0 else None,
            "steady_to_s": float(times[k1]) if k1 > k0 else None, "crossing_times_s": times.tolist(),
            "safety": watch.summary(), "walls_ok": watch.ok, "_watch": watch}


def bottleneck(quick: bool = False, plot_dir: Path | None = None, seed: int = 0, widths: tuple | None = None,
               n: int | None = None, params: dict | None = None) -> dict:
    if widths is None:
        widths = (0.8, 1.6, 2.4) if quick else (0.8, 1.0, 1.2, 1.6, 2.0, 2.4)
    if n is None:
        n = 60 if quick else 100
    runs = [bottleneck_run(w, n, seed + k, params=params) for k, w in enumerate(widths)]
    watches = [r.pop("_watch") for r in runs]
    flows = np.array([r["flow_p_s"] for r in runs])
    w = np.array(widths, float)
    increasing = bool(np.all(np.isfinite(flows)) and np.all(np.diff(flows) > 0))
    all_out = all(r["crossed"] == n for r in runs)
    safety = _merge_safety(watches)
    slope, intercept = (np.polyfit(w, flows, 1) if np.all(np.isfinite(flows)) and len(w) > 1 else (np.nan, np.nan))
    specific = flows / w
    lo, hi = SEYFRIED_SPECIFIC_FLOW
    passed = increasing and all_out and safety["walls_ok"]
    measured = ", ".join(f"w {r['width_m']:g}: J {r['flow_p_s']:.2f}/s (J/w {r['specific_flow_p_m_s']:.2f})"
                         for r in runs)
    measured += f"; fit J = {intercept:.2f} + {slope:.2f} w; J/w in {lo:g}-{hi:g} at " \
                f"{int(((specific >= lo) & (specific <= hi)).sum())}/{len(w)} widths"
    stuck = [r for r in runs if r["crossed"] < n]
    if stuck:
        measured += "; NOT ALL THROUGH in 200 s: " + ", ".join(f"w {r['width_m']:g}: {r['crossed']}/{n}" for r in stuck)
    result = {
        "name": "Bottleneck", "title": "Bottleneck flow against width (room 10 m x 10 m, bottleneck 2 m long)",
        "criterion": "flow J grows with width w at every step (Seyfried et al. 2009: linear growth, J/w about "
                     f"{lo:g}-{hi:g} persons/(m s), reported); everyone leaves",
        "measured": measured, "passed": bool(passed),
        "values": {"runs": runs, "fit_slope_p_m_s": float(slope), "fit_intercept_p_s": float(intercept),
                   "increasing": increasing, "all_left": all_out,
                   "reference": "Seyfried, Passon, Steffen, Boltes, Rupprecht, Klingsch 2009, New insights into "
                                "pedestrian flow through bottlenecks, Transportation Science 43(3) 395-406"},
        "safety": safety,
    }
    if plot_dir is not None:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
        ww = np.linspace(0, max(2.6, w.max() + 0.2), 50)
        ax.fill_between(ww, lo * ww, hi * ww, color="0.85", label=f"J/w = {lo:g}-{hi:g} /(m s) (Seyfried 2009)")
        ax.plot(w, flows, "o-", color="tab:red", label="crowdsim (steady part)")
        if np.isfinite(slope):
            ax.plot(ww, intercept + slope * ww, color="tab:red", ls=":", lw=1,
                    label=f"fit J = {intercept:.2f} + {slope:.2f} w")
        ax.set_xlabel("bottleneck width w [m]")
        ax.set_ylabel("flow J [persons/s]")
        ax.set_title(f"Bottleneck flow ({'pass' if passed else 'FAIL'})")
        ax.legend(fontsize=8)
        for r in runs:
            t = np.asarray(r["crossing_times_s"])
            ax2.step(t, np.arange(1, len(t) + 1), where="post", label=f"w = {r['width_m']:g} m")
        ax2.set_xlabel("t [s]")
        ax2.set_ylabel("persons through the bottleneck")
        ax2.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(plot_dir / "bottleneck_flow.png", dpi=100)
        plt.close(fig)
        result["plot"] = "bottleneck_flow.png"
    return result


# -- the report --------------------------------------------------------------------------------------------------

CHECKS = (("RiMEA 1", rimea1), ("RiMEA 4 / Weidmann", fundamental_diagram), ("RiMEA 6", rimea6),
          ("RiMEA 7", rimea7), ("Bottleneck", bottleneck))


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x


def _metres(x: float | None) -> str:
    if x is None:
        return f"over {Watch.REPORT_RANGE:g} m"
    return f"{round(x, 4) + 0.0:.4f} m"  # + 0.0: no "-0.0000" for a body touching a wall


def _report(results: dict) -> str:
    checks = results["checks"]
    lines = ["# crowdsim validation", "",
             f"{'Quick' if results['quick'] else 'Full'} run, {results['seconds']:.0f} s; simulation step "
             f"{DT:g} s; crowd parameters: "
             + (", ".join(f"{k} = {v}" for k, v in results["crowd_params"].items()) or "the scenario format's defaults")
             + f"; {'all checks pass' if results['passed'] else 'SOME CHECKS FAIL'}.", "",
             "| test | criterion | measured | pass |", "|---|---|---|---|"]
    for c in checks:
        lines.append(f"| {c['name']} | {c['criterion']} | {c['measured']} | {'pass' if c['passed'] else '**FAIL**'} |")
    s = results["safety"]
    lines.append(f"| Walls (all runs) | no body inside or across a wall at any step | "
                 f"{s['body_steps_inside_wall']} inside, {s['body_steps_wrong_side']} on the wrong side in "
                 f"{s['steps_checked']} steps; least clearance {_metres(s['min_wall_clearance_m'])} | "
                 f"{'pass' if s['walls_ok'] else '**FAIL**'} |")
    lines.append(f"| Overlap (all runs) | largest agent-agent overlap, reported | "
                 f"{100 * s['max_overlap_m']:.1f} cm (" + ", ".join(
                     f"{c['name']} {100 * c['safety']['max_overlap_m']:.1f}" for c in checks) + " cm) | reported |")
    lines.append("")
    for c in checks:
        lines += [f"## {c['title']}", "", f"Criterion: {c['criterion']}.", "",
                  f"Measured: {c['measured']}.", "",
                  f"Result: **{'pass' if c['passed'] else 'FAIL'}** ({c['seconds']:.1f} s). Largest overlap "
                  f"{100 * c['safety']['max_overlap_m']:.1f} cm; least wall clearance "
                  + _metres(c["safety"]["min_wall_clearance_m"]) + ".", ""]
        if c["name"] == "RiMEA 4 / Weidmann":
            lines += ["| target density | agents | density | speed [m/s] | std over persons | Weidmann | error |",
                      "|---|---|---|---|---|---|---|"]
            for r in c["values"]["runs"]:
                if r["set_up"]:
                    lines.append(f"| {r['density_target']:g} | {r['agents']} | {r['density']:.2f} | "
                                 f"{r['speed_m_s']:.3f} | {r['speed_std_agents_m_s']:.3f} | {r['weidmann_m_s']:.3f} | "
                                 f"{100 * r['relative_error']:+.0f}% |")
                else:
                    lines.append(f"| {r['density_target']:g} | {r['agents']} | not set up: {r['why']} | | | | |")
            lines.append("")
        if c["name"] == "Bottleneck":
            lines += ["| width [m] | flow [1/s] | J/w [1/(m s)] | steady part [s] | through |", "|---|---|---|---|---|"]
            for r in c["values"]["runs"]:
                lines.append(f"| {r['width_m']:g} | {r['flow_p_s']:.2f} | {r['specific_flow_p_m_s']:.2f} | "
                             f"{r['steady_from_s']:.1f}-{r['steady_to_s']:.1f} | {r['crossed']}/{r['agents']} |")
            lines += ["", f"Reference: {c['values']['reference']}.", ""]
        if c.get("plot"):
            lines += [f"![{c['name']}]({c['plot']})", ""]
    return "\n".join(lines)


def run_validation(out_dir: Path, quick: bool = False, progress: bool = True, params: dict | None = None) -> dict:
    """Run every check, write ``report.md``, ``validation.json`` and the PNGs into ``out_dir``; return the results.

    ``quick`` runs each check at a smaller size (a smaller ring, fewer densities and widths, shorter runs);
    ``params`` overrides keys of the scenario format's ``crowd`` section (the defaults otherwise)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    checks = []
    bar = tqdm(CHECKS, desc="validate", unit="test", disable=not progress)
    for name, fn in bar:
        bar.set_postfix_str(name)
        t = time.perf_counter()
        result = fn(quick=quick, plot_dir=out_dir, params=params)
        result["seconds"] = time.perf_counter() - t
        checks.append(result)
    bar.close()
    safety = _merge_safety([])
    safety.update({
        "max_overlap_m": max(c["safety"]["max_overlap_m"] for c in checks),
        "min_wall_clearance_m": min(c["safety"]["min_wall_clearance_m"] for c in checks
                                    if c["safety"]["min_wall_clearance_m"] is not None),
        "body_steps_inside_wall": sum(c["safety"]["body_steps_inside_wall"] for c in checks),
        "body_steps_wrong_side": sum(c["safety"]["body_steps_wrong_side"] for c in checks),
        "steps_checked": sum(c["safety"]["steps_checked"] for c in checks),
        "walls_ok": all(c["safety"]["walls_ok"] for c in checks)})
    results = {"quick": quick, "dt_s": DT, "crowd_params": dict(params or {}), "seconds": time.perf_counter() - start,
               "passed": all(c["passed"] for c in checks) and safety["walls_ok"], "safety": safety,
               "checks": checks}
    results = _jsonable(results)
    (out_dir / "report.md").write_text(_report(results) + "\n", encoding="utf-8")
    with open(out_dir / "validation.json", "w", encoding="utf-8") as f:
        json.dump(results, f, indent=2)
        f.write("\n")
    return results
