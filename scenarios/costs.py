"""What a scenario costs, checked before it runs: steps, laser beams, camera pixels, the map filter's grid, people at
once, the RJMCMC filter's chain, and what one step can move the robot.

``check_costs(scenario, source)`` takes the validated scenario (defaults filled in) and raises one ``ScenarioError``
naming the key, its value, the limit and what is expected. Two kinds of limit:

- **cost limits** (``MAX_*`` below): what a scenario may ask of time and memory before it must say that it means it.
  Each is set well above what the bundled scenarios and real sensors need, and far below what makes a run hang or
  run out of memory; ``allow_large=True`` (the CLI's ``--allow-large``) passes them on purpose.
- **validity limits**: more persons at the start than ``crowd.max_agents``, a robot that moves past its own radius or
  turns more than a quarter turn in one step (``STEP_*`` below; a laser of fewer than two beams is the format's own
  check, scenarios/format.py). These are no costs: the run would fail, or its results would be wrong, however long
  one waited, so ``allow_large`` does not pass them.

The figures behind each limit were measured on the project's 2-core machine (MuJoCo 4.0, EGL rendering); they say
how long or how much memory one unit costs here. ``scenario_costs`` gives the same figures for a scenario.
"""

from __future__ import annotations

import math
import re

import numpy as np

from sensors.laser import beam_count

from .geometry import wall_segments
from .schema import ScenarioError

# -- cost limits (passed with allow_large) ------------------------------------------------------------------------

# steps: (warmup + duration) / dt. A step costs 0.7-1.8 ms here in the warm-up (the crowd alone: passers_by,
# airport_disembarkation) and 8-10 ms recording (crowd, two lasers, the pipeline, scoring: passers_by, the airport),
# so 1e6 steps are 15-30 min of warm-up or 2-3 h of an airport run: 11 h of simulated time at the default dt of
# 0.04 s, 1000 s at dt 1 ms. The longest bundled scenario takes 4,500 steps (the airport: 60 s + 120 s at 0.04 s);
# the experiments' 600 s airport runs take 16,500.
MAX_STEPS = 1_000_000

# beams a scan, each laser (what sensors/laser.py casts: fov / resolution, plus one unless a full circle). A beam
# costs about 200 bytes while a scan is made and read (1,000,001 beams: +195 MB) and 3-4 us of ray cast, noise,
# detector and scoring; 1e5 beams are 20 MB and about 0.4 s a scan. Real 2D lasers give at most a few thousand
# (SICK LMS5xx at 1/24 deg over 190 deg: 4,561; Hokuyo UTM-30LX: 1,081); the bundled ones give 361-450.
MAX_BEAMS_PER_SCAN = 100_000

# beams a second, all lasers together (beams a scan x rate). At 3.3 us a beam (the airport's two lasers at 0.01 deg
# instead of 0.5: 138.7 ms a step instead of 16.6) 1e6 beams/s cost about 3.3 s of this machine per simulated second.
# The airport's two SICK LMS500 give 19,050 beams/s; a 16-ring 3D lidar emulated by 16 lasers at 0.2 deg and 10 Hz,
# 288,000.
MAX_BEAMS_PER_SECOND = 1_000_000

# camera pixels a second, every depth and wall camera together (width x height x rate; a colour image is a second
# rendering pass of the same pixels). A depth camera's pixel costs 1.2 us here with the RGB-D detector and tracker
# (ktp_group's camera at 640 x 480 instead of 160 x 120, 30 Hz: 11.1 s instead of 1.1 s per simulated second), so
# 1e8 pixels/s are about 2 minutes of this machine per simulated second. A Kinect at 640 x 480 and 30 Hz gives 9.2
# million pixels/s, a 1080p camera at 30 Hz 62 million; the bundled scenarios give at most 3.1 million (seed 001's
# room: two 640 x 480 wall cameras at 5 Hz).
MAX_PIXELS_PER_SECOND = 100_000_000

# m, the map's extent: the larger side of the bounding box of its walls and obstacles. OpenGL renders in 32-bit
# floats, whose spacing is 1 mm at 10 km and 1 cm at 100 km: beyond this the cameras' people (legs 5 cm wide) lose
# their shape, and nothing indoors is this large (the longest airport terminals are 1-2 km; the airport here is 37 m).
MAX_MAP_EXTENT = 10_000.0

# wall and obstacle segments of the map. Every step costs about 28 us a segment here (seed 001's room with its two
# wall cameras and tiny obstacles added: 77 ms a step with 3,000 segments, 339 ms with 12,000; the crowd's wall
# forces, the scenes and the renders all go over every segment), so 10,000 segments are about 0.3 s a step, 7 s of
# this machine per simulated second. The bundled maps have 6-40 segments; the largest PedSim file, 96.
MAX_WALL_SEGMENTS = 10_000

# cells of the map filter's occupancy grid (pipeline/map_filter.py: the map's bounding box plus a margin, at
# map_filter.resolution). A cell costs about 50 bytes while the grid is made (the grid, its float copy and the FFT
# convolution) and 260 ns (the airport at 0.01 m: 13.2 million cells, +657 MB, 3.6 s), so 2e7 cells are about 1 GB
# and 6 s. That is a 220 m x 220 m map at the default 0.05 m; the airport at 0.05 m (inflation 0.3 m) has 539,825
# cells.
MAX_GRID_CELLS = 20_000_000

# persons at once: crowd.max_agents, and the persons present at the start. The crowd's memory and the MuJoCo scenes
# grow with the persons actually present (sensors/scene.py, crowdsim/crowd/contacts.py), but a scene slot costs
# about 37 KB and MuJoCo's compiler takes time that grows faster than the slots (2.8 s for 2,048, 13 s for 4,096,
# 57 s for 8,192 here), and the scenes are rebuilt as the crowd doubles: 10,000 persons at once is a scene that
# takes minutes to make. The bundled scenarios allow 400-600 (and have 0-34 at the start); the benchmarks run 5,000.
MAX_AGENTS = 10_000

# steps of the RJMCMC filter's Markov chain each tracking cycle (samples + burn_in; seed 001 Table 1: 150 + 40). A
# step costs 60-150 us here (seed001_room_1: 11.8 ms a cycle at 190 steps, 451 ms at 3,040), so 20,000 steps are
# 1-3 s a cycle, 5-15 s per simulated second at the room's 5 Hz; the chain's arrays and kept particles are a few
# hundred bytes a step.
MAX_CHAIN_STEPS = 20_000

# -- validity limits (not passed with allow_large) ----------------------------------------------------------------

# robot radii the robot may move in one step (robot.max_speed x dt). The collision test (crowdsim/loop.py) and the
# crowd's contacts (pymunk, no continuous collision detection) look at the robot's disc once a step: moving farther
# than its radius, the disc can pass a wall or a person between two steps without ever overlapping them (N04: 1e4
# m/s leaves the building through its walls). The bundled robots move 0.005-0.04 m a step, radius 0.26-0.425 m.
STEP_MOVE_RADII = 1.0

# rad the robot may turn in one step (robot.max_angular_speed x dt). The planners steer with omega =
# max_angular_speed x heading error / (pi / 2) (pipeline/navigation/nd.py): within a quarter turn a step the robot
# never turns past the heading it aims for; beyond, it overshoots, and beyond a half turn the steering diverges (and
# a turn reads as one the other way round). The bundled robots turn at most 0.04 rad a step.
STEP_TURN = math.pi / 2

ALLOW = "; --allow-large runs it on purpose"
NOT_A_COST = "; this is no cost limit: --allow-large does not pass it"


def _n(x: float) -> str:
    """A count as people read it: 1,000,000 (and 2.5e+10 beyond what digits help)."""
    return f"{x:,.0f}" if x < 1e13 else f"{x:.3g}"


# -- the figures ----------------------------------------------------------------------------------------------------

def laser_beams(laser: dict) -> float:
    """The beams of one scan, as the laser counts them (sensors.laser.beam_count; a float: huge counts stay finite
    or inf)."""
    return float(beam_count(laser["fov_deg"], laser["resolution_deg"]))


def _grid_ends(map_: dict, map_filter: dict) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest corner of what the map filter rasterises: the walls, and the obstacles unless it
    leaves them out."""
    obstacles = map_["obstacles"] if map_filter.get("obstacles", True) else []
    segments = wall_segments({"map": {"walls": map_["walls"], "obstacles": obstacles}})
    ends = segments.reshape(-1, 2) if len(segments) else np.zeros((1, 2))
    return ends.min(axis=0), ends.max(axis=0)


def _grid_size(lo: np.ndarray, hi: np.ndarray, res: float, inflation: float) -> tuple[float, float]:
    margin = inflation + res
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        origin = lo - (np.ceil(margin / res) + 0.5) * res
        size = np.ceil((hi + margin - origin) / res)
    cols, rows = (float(v) if np.isfinite(v) else math.inf for v in size)
    return cols, rows


def grid_shape(map_: dict, map_filter: dict) -> tuple[float, float]:
    """(columns, rows) of the map filter's occupancy grid, as pipeline/map_filter.py's occupancy_grid makes it (as
    floats: nothing is allocated)."""
    return _grid_size(*_grid_ends(map_, map_filter), float(map_filter["resolution"]), map_filter["inflation"])


def map_extent(map_: dict) -> tuple[float, float]:
    """Width and height (m) of the bounding box of the map's walls and obstacles (0 without any)."""
    points = wall_segments({"map": map_}).reshape(-1, 2)
    if not len(points):
        return 0.0, 0.0
    w, h = points.max(axis=0) - points.min(axis=0)
    return float(w), float(h)


def persons_at_start(scenario: dict) -> list[tuple[str, int]]:
    """(key, persons) of everything that places persons before any source emits: standing groups, clusters and the
    follow driver's target (who joins when recording starts, whatever the sources have done)."""
    out = [(f"standing[{i}].count", g["count"]) for i, g in enumerate(scenario["standing"])]
    out += [(f"clusters[{i}].count", c["count"]) for i, c in enumerate(scenario["clusters"])]
    follow = scenario["robot"]["follow"]
    if scenario["robot"]["driver"] == "follow" and follow is not None and follow.get("target") is not None:
        out.append(("robot.follow.target", 1))
    return out


def scenario_costs(scenario: dict) -> dict:
    """The figures check_costs weighs, for a validated scenario: steps, beams per scan of each laser and per second
    of all, camera pixels per second, the map's extent and the map filter's grid cells, persons at the start and at
    most, and the RJMCMC chain's steps a cycle (None without that tracker)."""
    dt = scenario["dt"]
    sensors = scenario["sensors"]
    beams = [laser_beams(laser) for laser in sensors["lasers"]]
    cameras = [c for kind in ("depth_cameras", "wall_cameras") for c in sensors[kind]]
    mf = scenario["pipeline"]["map_filter"]
    cols, rows = grid_shape(scenario["map"], mf) if mf is not None else (0.0, 0.0)
    tracker = scenario["pipeline"]["tracker"]
    return {
        "steps": scenario["warmup"] / dt + scenario["duration"] / dt,
        "beams_per_scan": beams,
        "beams_per_second": sum(b * laser["rate"] for b, laser in zip(beams, sensors["lasers"])),
        "pixels_per_second": float(sum(c["width"] * c["height"] * c["rate"] for c in cameras)),
        "map_extent": max(map_extent(scenario["map"])),
        "grid_cells": cols * rows,
        "persons_at_start": sum(n for _, n in persons_at_start(scenario)),
        "max_agents": scenario["crowd"]["max_agents"],
        "chain_steps": (tracker["samples"] + tracker["burn_in"]) if tracker["type"] == "rjmcmc" else None,
    }


# -- the checks -----------------------------------------------------------------------------------------------------

def check_costs(scenario: dict, source: str, allow_large: bool = False) -> None:
    """Refuse a validated scenario that cannot run as written (the validity limits, first) or that costs more than
    the ``MAX_*`` limits (unless ``allow_large``), with one ScenarioError naming the key, its value and the limit."""
    _check_people_at_start(scenario, source)
    _check_robot(scenario, source)
    _check_walkers(scenario, source)
    if allow_large:
        return
    _check_steps(scenario, source)
    _check_lasers(scenario, source)
    _check_cameras(scenario, source)
    _check_people(scenario, source)
    _check_map(scenario, source)
    _check_chain(scenario, source)


def _check_steps(scenario: dict, source: str) -> None:
    warmup, duration, dt = scenario["warmup"], scenario["duration"], scenario["dt"]
    steps = warmup / dt + duration / dt
    if steps <= MAX_STEPS:
        return
    default_dt = 0.04  # the format's (scenarios/format.py SCENARIO.dt)
    if dt < default_dt and (warmup + duration) / default_dt <= MAX_STEPS:
        key, fix = "dt", f"a dt of at least {(warmup + duration) / MAX_STEPS:.3g} s"
    else:
        key, other = ("warmup", duration) if warmup >= duration else ("duration", warmup)
        room = MAX_STEPS * dt - other
        fix = (f"a {'warm-up' if key == 'warmup' else 'duration'} of at most {room:.6g} s" if room > 0 else
               f"a warm-up and duration of at most {MAX_STEPS * dt:.6g} s together")
    raise ScenarioError(source, key, f"{scenario[key]:g} s: {warmup:g} s of warm-up and {duration:g} s recorded at a "
                                     f"step of {dt:g} s are {_n(steps)} steps; expected at most {_n(MAX_STEPS)} "
                                     f"steps (scenarios/costs.py MAX_STEPS: a step takes 1-10 ms here, so hours), "
                                     f"{fix}{ALLOW}")


def _check_lasers(scenario: dict, source: str) -> None:
    lasers = scenario["sensors"]["lasers"]
    beams = [laser_beams(laser) for laser in lasers]
    for i, (laser, n) in enumerate(zip(lasers, beams)):
        fov, res = laser["fov_deg"], laser["resolution_deg"]
        if n > MAX_BEAMS_PER_SCAN:
            raise ScenarioError(source, f"sensors.lasers[{i}].resolution_deg",
                                f"{res:g} deg over a fov_deg of {fov:g} gives {_n(n)} beams a scan; expected at most "
                                f"{_n(MAX_BEAMS_PER_SCAN)} (scenarios/costs.py MAX_BEAMS_PER_SCAN: about 200 bytes "
                                f"and 4 us a beam), a resolution_deg of at least {fov / MAX_BEAMS_PER_SCAN:.3g} deg"
                                f"{ALLOW}")
    per_second = [n * laser["rate"] for n, laser in zip(beams, lasers)]
    total = sum(per_second)
    if total > MAX_BEAMS_PER_SECOND:
        k = int(np.argmax(per_second))
        laser = lasers[k]
        others = f" and all {len(lasers)} lasers {_n(total)}" if len(lasers) > 1 else ""
        raise ScenarioError(source, f"sensors.lasers[{k}]",
                            f"{_n(beams[k])} beams a scan at {laser['rate']:g} Hz are {_n(per_second[k])} beams/s"
                            f"{others}; expected at most {_n(MAX_BEAMS_PER_SECOND)} beams/s from all lasers together "
                            f"(scenarios/costs.py MAX_BEAMS_PER_SECOND: about 3.3 us a beam, seconds of this machine "
                            f"per simulated second), a coarser resolution_deg or a lower rate{ALLOW}")


def _check_cameras(scenario: dict, source: str) -> None:
    sensors = scenario["sensors"]
    cameras = [(f"sensors.{kind}[{i}]", c) for kind in ("depth_cameras", "wall_cameras")
               for i, c in enumerate(sensors[kind])]
    per_second = [c["width"] * c["height"] * c["rate"] for _, c in cameras]
    total = sum(per_second)
    if total <= MAX_PIXELS_PER_SECOND:
        return
    k = int(np.argmax(per_second))
    key, c = cameras[k]
    others = f" and all {len(cameras)} cameras {_n(total)}" if len(cameras) > 1 else ""
    raise ScenarioError(source, key, f"{c['width']} x {c['height']} pixels at {c['rate']:g} Hz are "
                                     f"{_n(per_second[k])} pixels/s{others}; expected at most "
                                     f"{_n(MAX_PIXELS_PER_SECOND)} pixels/s from all cameras together "
                                     f"(scenarios/costs.py MAX_PIXELS_PER_SECOND: about 1.2 us a pixel with the "
                                     f"RGB-D detector, minutes of this machine per simulated second), a smaller width "
                                     f"and height or a lower rate{ALLOW}")


def _pedsim_element(scenario: dict, key: str, source: str) -> str:
    """' (the PedSim <agent> on line L)' for a cluster a PedSim file's element made (scenarios/pedsim.py names its
    route after the element's line), else ''."""
    m = re.match(r"clusters\[(\d+)\]", key)
    if not m or not source.lower().endswith(".xml"):
        return ""
    route = scenario["clusters"][int(m.group(1))]["route"]
    found = re.fullmatch(r"(agent|source)_line(\d+)", route)
    return f" (the PedSim <{found.group(1)}> on line {found.group(2)})" if found else ""


def _check_people_at_start(scenario: dict, source: str) -> None:
    placed = persons_at_start(scenario)
    at_start = sum(n for _, n in placed)
    most = scenario["crowd"]["max_agents"]
    if at_start > most:
        largest = sorted(placed, key=lambda kn: -kn[1])[:3]
        parts = ", ".join(f"{key} {_n(n)}{_pedsim_element(scenario, key, source)}" for key, n in largest)
        more = f" and {len(placed) - 3} more" if len(placed) > 3 else ""
        raise ScenarioError(source, "crowd.max_agents",
                            f"{_n(most)} persons at most at once, but {_n(at_start)} are present at the start "
                            f"({parts}{more}); expected a crowd.max_agents of at least {_n(at_start)}, or fewer "
                            f"persons at the start" + NOT_A_COST)


def _check_people(scenario: dict, source: str) -> None:
    placed = persons_at_start(scenario)
    at_start = sum(n for _, n in placed)
    if at_start > MAX_AGENTS:
        key, n = max(placed, key=lambda kn: kn[1])
        raise ScenarioError(source, key, f"{_n(n)} persons{_pedsim_element(scenario, key, source)}, "
                                         f"{_n(at_start)} present at the start in all; expected at most "
                                         f"{_n(MAX_AGENTS)} persons at once (scenarios/costs.py MAX_AGENTS: the "
                                         f"MuJoCo scene of that many takes minutes to make){ALLOW}")
    most = scenario["crowd"]["max_agents"]
    if most > MAX_AGENTS:
        raise ScenarioError(source, "crowd.max_agents",
                            f"{_n(most)} persons at once; expected at most {_n(MAX_AGENTS)} (scenarios/costs.py "
                            f"MAX_AGENTS: the MuJoCo scene of that many takes minutes to make; the scenes grow with "
                            f"the persons actually present, so a bound well above them costs nothing more){ALLOW}")


def _check_robot(scenario: dict, source: str) -> None:
    robot, dt = scenario["robot"], scenario["dt"]
    radius = robot["radius"]
    if robot["max_speed"] * dt > STEP_MOVE_RADII * radius:
        fastest = STEP_MOVE_RADII * radius / dt
        raise ScenarioError(source, "robot.max_speed",
                            f"{robot['max_speed']:g} m/s moves the robot {robot['max_speed'] * dt:.3g} m in one step "
                            f"of {dt:g} s, more than its radius ({radius:g} m): the collision test and the crowd's "
                            f"contacts look at its disc once a step, so it would pass walls and people unseen; "
                            f"expected at most {fastest:.3g} m/s (robot.radius / dt), or a smaller dt" + NOT_A_COST)
    if robot["max_angular_speed"] * dt > STEP_TURN:
        fastest = STEP_TURN / dt
        turn = robot["max_angular_speed"] * dt
        raise ScenarioError(source, "robot.max_angular_speed",
                            f"{robot['max_angular_speed']:g} rad/s turns the robot {turn:.3g} rad in one step of "
                            f"{dt:g} s, more than a quarter turn: its planners' steering would turn past the heading "
                            f"they aim for and oscillate; expected at most {fastest:.3g} rad/s (pi / 2 / dt), or a "
                            f"smaller dt" + NOT_A_COST)


def _check_walkers(scenario: dict, source: str) -> None:
    """A walker moves at most max_speed_factor x its speed_max: within a step, no farther than its radius (the
    contacts, like the robot's, look at each disc once a step)."""
    crowd, dt = scenario["crowd"], scenario["dt"]
    for name, t in crowd["agent_types"].items():
        fastest = crowd["max_speed_factor"] * t["speed_max"]
        if fastest * dt > STEP_MOVE_RADII * t["radius"]:
            raise ScenarioError(source, f"crowd.agent_types.{name}.speed_max",
                                f"{t['speed_max']:g} m/s, times crowd.max_speed_factor {crowd['max_speed_factor']:g}, "
                                f"moves a walker {fastest * dt:.3g} m in one step of {dt:g} s, more than its radius "
                                f"({t['radius']:g} m): it would pass walls and people unseen; expected at most "
                                f"{STEP_MOVE_RADII * t['radius'] / dt / crowd['max_speed_factor']:.3g} m/s, or a "
                                f"smaller dt" + NOT_A_COST)


def _check_map(scenario: dict, source: str) -> None:
    segments = len(wall_segments(scenario))
    if segments > MAX_WALL_SEGMENTS:
        raise ScenarioError(source, "map", f"{_n(segments)} wall and obstacle segments; expected at most "
                                           f"{_n(MAX_WALL_SEGMENTS)} (scenarios/costs.py MAX_WALL_SEGMENTS: every step "
                                           f"goes over every segment, about 28 us each here){ALLOW}")
    w, h = map_extent(scenario["map"])
    if max(w, h) > MAX_MAP_EXTENT:
        key = _farthest_line(scenario["map"])
        raise ScenarioError(source, key, f"the map's walls and obstacles span {w:.6g} m x {h:.6g} m; expected at most "
                                         f"{MAX_MAP_EXTENT:g} m across (scenarios/costs.py MAX_MAP_EXTENT: the cameras "
                                         f"render in 32-bit floats, 1 mm apart at 10 km){ALLOW}")
    mf = scenario["pipeline"]["map_filter"]
    if mf is None:
        return
    cols, rows = grid_shape(scenario["map"], mf)
    cells = cols * rows
    if cells <= MAX_GRID_CELLS:
        return
    coarsest = _grid_resolution(scenario["map"], mf)
    raise ScenarioError(source, "pipeline.map_filter.resolution",
                        f"{mf['resolution']:g} m cells over the map's {w:.6g} m x {h:.6g} m make an occupancy grid of "
                        f"{_n(cols)} x {_n(rows)} = {_n(cells)} cells; expected at most {_n(MAX_GRID_CELLS)} "
                        f"(scenarios/costs.py MAX_GRID_CELLS: about 50 bytes a cell while the grid is made), a "
                        f"resolution of at least {coarsest:.2g} m for this map, or no map filter{ALLOW}")


def _grid_resolution(map_: dict, map_filter: dict) -> float:
    """About the finest resolution (2 significant digits, rounded up) whose grid stays within MAX_GRID_CELLS."""
    lo, hi = _grid_ends(map_, map_filter)
    (w, h), inflation = hi - lo, map_filter["inflation"]
    res = max(math.sqrt((w + 2 * inflation) * (h + 2 * inflation) / MAX_GRID_CELLS), 1e-9)
    for _ in range(2000):
        cols, rows = _grid_size(lo, hi, res, inflation)
        if cols * rows <= MAX_GRID_CELLS:
            break
        res *= 1.01
    unit = 10.0 ** (math.floor(math.log10(res)) - 1)
    return math.ceil(res / unit - 1e-9) * unit


def _farthest_line(map_: dict) -> str:
    """The key of the wall polyline or obstacle whose point lies farthest from the median of all the map's points."""
    lines = [(f"map.walls[{i}]", np.asarray(p, float)) for i, p in enumerate(map_["walls"])]
    lines += [(f"map.obstacles[{i}]", np.asarray(p, float)) for i, p in enumerate(map_["obstacles"])]
    lines = [(key, p.reshape(-1, 2)) for key, p in lines if np.size(p)]
    centre = np.median(np.concatenate([p for _, p in lines]), axis=0)
    return max(lines, key=lambda kp: float(np.abs(kp[1] - centre).max()))[0]


def _check_chain(scenario: dict, source: str) -> None:
    tracker = scenario["pipeline"]["tracker"]
    if tracker["type"] != "rjmcmc":
        return
    steps = tracker["samples"] + tracker["burn_in"]
    if steps <= MAX_CHAIN_STEPS:
        return
    key = "samples" if tracker["samples"] >= tracker["burn_in"] else "burn_in"
    raise ScenarioError(source, f"pipeline.tracker.{key}",
                        f"{_n(tracker[key])}: samples {_n(tracker['samples'])} + burn_in {_n(tracker['burn_in'])} are "
                        f"{_n(steps)} steps of the Markov chain every tracking cycle; expected at most "
                        f"{_n(MAX_CHAIN_STEPS)} together (scenarios/costs.py MAX_CHAIN_STEPS: 60-150 us a step, "
                        f"seconds a cycle; seed 001 Table 1: 150 + 40){ALLOW}")
