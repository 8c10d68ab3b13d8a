"""Finding, reading and validating scenario files: schema checks first, then the checks that need geometry."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from .costs import check_costs
from .format import DETECTOR_READS, SCENARIO
from .geometry import closest_on_segments, inside_polygon, wall_segments
from .pedsim import pedsim_to_scenario
from .reader import Replace, read_yaml
from .schema import REMOVE, Field, MapOf, Schema, ScenarioError, Typed, validate
from .typed import Scenario, plain, scenario_of

BUNDLED = Path(__file__).parent / "bundled"
MIN_EXTENT = 1.0  # m, walls whose extent is narrower than this in x or y (a single wall) bound no area
SENSOR_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}")


# words a full stop follows without ending a sentence ("seed 003 Sec. 2", "et al. 2014")
ABBREVIATIONS = {"sec", "secs", "fig", "figs", "eq", "eqs", "tab", "no", "vs", "e.g", "i.e", "al", "cf", "approx",
                 "ch", "pp", "vol", "resp"}


def first_sentence(text: str) -> str:
    """The first sentence of ``text``, whole: it ends at a full stop (or ! or ?) before a space or the end that
    does not close an abbreviation or an initial."""
    text = " ".join(text.split())
    for stop in re.finditer(r"[.!?](?= |$)", text):
        word = re.split(r"[\s(]", text[:stop.start()])[-1]
        if stop.group() != "." or not (word.lower() in ABBREVIATIONS or re.fullmatch(r"[A-Z]", word)):
            return text[:stop.end()]
    return text + "." if text else ""


def bundled_scenarios() -> dict[str, str]:
    """Bundled scenario name -> the first sentence of its description."""
    return {path.stem: first_sentence(str((read_yaml(path) or {}).get("description", "")))
            for path in sorted(BUNDLED.glob("*.yaml"))}


def resolve(name_or_path: str) -> Path:
    """A bundled name (``airport_disembarkation``), a path to a YAML file, or a PedSim XML scenario file (a folder
    of the bundled name, a run's output say, does not hide the bundled scenario)."""
    path = Path(name_or_path)
    try:
        if path.suffix in (".yaml", ".yml", ".xml") or path.is_file():
            if not path.is_file():
                raise ScenarioError(str(path), "<file>", "no such scenario file")
            return path
        bundled = BUNDLED / f"{name_or_path}.yaml"
        if bundled.is_file():
            return bundled
    except (OSError, ValueError) as e:  # a name too long for the file system, a NUL byte
        raise ScenarioError(str(path)[:80], "<file>", f"not a usable path ({e}); expected a scenario file or a "
                                                      "bundled name") from None
    names = ", ".join(bundled_scenarios())
    raise ScenarioError(name_or_path, "<scenario>",
                        f"not a bundled scenario, a YAML file nor a PedSim XML file; bundled: {names}")


def _inner(spec: Any) -> Any:
    while isinstance(spec, Field):
        spec = spec.kind
    return spec


def merge(base: Any, changes: Any, spec: Any = SCENARIO) -> Any:
    """``base`` with ``changes`` laid over it, as the format ``spec`` reads them: mappings merge key by key; a part
    given another ``type`` than its base's is replaced whole (the old type's keys do not carry over), as is a
    mapping tagged ``!replace``; a key tagged ``!remove`` is dropped; lists and plain values are replaced."""
    spec = _inner(spec)
    if isinstance(changes, Replace) or not (isinstance(changes, dict) and isinstance(base, dict)):
        return changes
    if isinstance(spec, Typed):
        old = base.get("type", spec.default)
        if changes.get("type", old) != old:
            return changes
        spec = spec.types.get(old)  # a class of one's own: merged key by key, its keys unknown here
    out = dict(base)
    for key, value in changes.items():
        if value is REMOVE:
            out.pop(key, None)
            continue
        sub = spec.fields[key] if isinstance(spec, Schema) and key in spec.fields else (
            spec.item if isinstance(spec, MapOf) else None)
        out[key] = merge(out[key], value, sub) if key in out else value
    return out


def _paths(value: Any, key: str = ""):
    """The key paths of ``value`` as errors name them (``a.b``, ``a[0]``)."""
    if isinstance(value, dict):
        for k, v in value.items():
            sub = f"{key}.{k}" if key else str(k)
            yield sub
            yield from _paths(v, sub)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield f"{key}[{i}]"
            yield from _paths(v, f"{key}[{i}]")


def read_raw(path: Path) -> dict:
    """The file's data, with ``base: NAME_OR_PATH`` resolved: the base scenario's data, then this file's laid over
    it by ``merge``."""
    return _read(path)[0]


def _read(path: Path, seen: tuple = ()) -> tuple[dict, dict[str, str]]:
    """``read_raw``'s data, and for each key path the file that gave it last (empty without a base)."""
    source = str(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ScenarioError(source, "<top level>", "expected a mapping of keys")
    if "base" not in raw:
        return raw, {}
    name = raw.pop("base")
    if not isinstance(name, str):
        raise ScenarioError(source, "base", f"expected a scenario name or path, got {name!r}")
    local = path.parent / name
    try:
        base_path = resolve(str(local) if local.suffix in (".yaml", ".yml") and local.is_file() else name)
    except ScenarioError as e:
        raise ScenarioError(source, "base", f"{name!r}: {e.message}") from None
    if base_path.resolve() in seen:
        raise ScenarioError(source, "base", f"{name!r} leads back to this file; expected no cycle")
    base, origins = _read(base_path, seen + (path.resolve(),))
    merged, given = merge(base, raw), set(_paths(raw))
    return merged, {p: source if p in given else origins.get(p, str(base_path)) for p in _paths(merged)}


def _from_base(error: ScenarioError, origins: dict[str, str]) -> ScenarioError:
    """``error``, saying so when the key at fault came from a base scenario (the nearest key path a file gave)."""
    key = error.key
    while key and key not in origins:
        key = re.sub(r"(\.[^.\[\]]*|\[\d+\])$", "", key) if re.search(r"[.\]]", key) else ""
    origin = origins.get(key)
    if origin is None or origin == error.source:
        return error
    return ScenarioError(error.source, error.key, f"{error.message} ({key} comes from the base scenario {origin}; "
                                                  f"expected it overridden in {error.source} or fixed there)")


def load_scenario(name_or_path: str, allow_large: bool = False, **overrides) -> Scenario:
    """The validated scenario (scenarios/typed.py: ``scenario.robot.radius``), defaults filled in; ``overrides``
    replace top-level keys. A ``.xml``
    path is read as a PedSim scenario (``scenarios.pedsim``). ``allow_large`` lets a scenario past the cost limits
    run (scenarios/costs.py)."""
    path = resolve(name_or_path)
    origins: dict[str, str] = {}
    if path.suffix.lower() == ".xml":
        raw = pedsim_to_scenario(path)
    else:
        raw, origins = _read(path)
    raw.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return scenario_from_dict(raw, str(path), allow_large)
    except ScenarioError as e:
        raise _from_base(e, origins) from None


def scenario_from_dict(raw: dict, source: str = "<scenario>", allow_large: bool = False) -> Scenario:
    """Validate scenario data given as a dict (as a YAML file would hold it; a Scenario too); ``source`` names it in
    errors. What the scenario costs is checked too (scenarios/costs.py), unless ``allow_large``."""
    scenario = validate(plain(raw), SCENARIO, source)
    check_geometry(scenario, source)
    check_costs(scenario, source, allow_large)
    scenario["source"] = source
    return scenario_of(scenario)


def check_sensor(sensor: dict, key: str, dt: float, source: str) -> None:
    """A sensor's rate within the simulation's steps (a sensor is due at most once a step), its range limits in
    order, its noise bands nearest first."""
    if sensor["rate"] * dt > 1 + 1e-9:
        raise ScenarioError(source, f"{key}.rate",
                            f"{sensor['rate']:g} Hz is more than the simulation's {1 / dt:g} steps per second (dt "
                            f"{dt:g} s) can run; expected at most {1 / dt:g} Hz, or a dt of at most "
                            f"{1 / sensor['rate']:g} s")
    if "range_min" in sensor and sensor["range_min"] >= sensor["range_max"]:
        raise ScenarioError(source, f"{key}.range_min",
                            f"{sensor['range_min']:g} m; expected less than range_max ({sensor['range_max']:g} m)")
    bands = [band["up_to"] for band in sensor["noise"]] if isinstance(sensor.get("noise"), list) else []  # lasers
    for j in range(1, len(bands)):
        if bands[j] <= bands[j - 1]:
            raise ScenarioError(source, f"{key}.noise[{j}].up_to",
                                f"{bands[j]:g} m; expected the bands nearest first, beyond the previous one's "
                                f"{bands[j - 1]:g} m")


def check_detectors(scenario: dict, source: str) -> None:
    """Detectors attached to sensors of the scenario, each built-in one to a kind of sensor it reads."""
    kinds = {s["name"]: kind for kind in ("lasers", "depth_cameras", "wall_cameras", "custom")
             for s in (scenario["sensors"][kind] or [])}
    pipeline = scenario["pipeline"]
    attached = [("pipeline.detector", pipeline["detector"], "lasers", "every laser")]
    for name, spec in pipeline["detectors"].items():
        if name not in kinds:
            raise ScenarioError(source, f"pipeline.detectors.{name}",
                                f"no sensor of this scenario is called so; expected one of: {', '.join(kinds)}")
        if spec is not None:
            attached.append((f"pipeline.detectors.{name}", spec, kinds[name], name))
    cameras = [s["name"] for s in scenario["sensors"]["depth_cameras"]]
    if pipeline["cycle"] != "lasers" and pipeline["cycle"] not in cameras:
        raise ScenarioError(source, "pipeline.cycle", f"{pipeline['cycle']!r}; expected lasers or a depth camera's "
                                                      f"name: {', '.join(['lasers', *cameras])}")
    colour = {s["name"]: (f"sensors.{kind}[{i}].rgb", s["rgb"]) for kind in ("depth_cameras", "wall_cameras")
              for i, s in enumerate(scenario["sensors"][kind])}
    for key, spec, kind, what in attached:
        reads = DETECTOR_READS.get(spec["type"], kind)  # a class of one's own reads what it is given
        if reads != kind:
            raise ScenarioError(source, f"{key}.type", f"{spec['type']} reads sensors.{reads}, and {what} is one of "
                                                       f"sensors.{kind}; expected a detector for sensors.{kind}")
        needs_colour = spec["type"] == "wall_people" or (spec["type"] == "rgbd_people" and spec["hog"])
        camera, rgb = colour.get(what, ("", True))
        if needs_colour and not rgb:
            raise ScenarioError(source, camera, f"false, and {key} ({spec['type']}) needs this camera's colour images; "
                                                "expected true" + ("" if spec["type"] == "wall_people" else
                                                                   f", or {key}.hog: false"))


def check_driver(scenario: dict, source: str) -> None:
    """What the robot's driver needs: goals for the goals driver; a target on a known route, slower than the robot,
    and a tag reader for the follow driver; a band that is one."""
    robot = scenario["robot"]
    driver = robot["driver"]
    if driver == "goals" and not robot["goals"]:
        raise ScenarioError(source, "robot.goals", "missing; expected at least one goal [x, y] (m, world) when "
                                                   "robot.driver is goals")
    if driver == "script":
        rows = robot["script"] or []
        if not rows or any(len(row) != 3 or row[0] <= 0 for row in rows):
            raise ScenarioError(source, "robot.script", f"{rows}; expected [duration, v, omega] rows (s > 0, m/s, "
                                                        "rad/s) when robot.driver is script")
    near, far = robot["follow"]["band"] if robot["follow"] else (1.0, 2.0)
    if not 0 < near < far:
        raise ScenarioError(source, "robot.follow.band", f"[{near:g}, {far:g}]; expected [near, far] with "
                                                         f"0 < near < far (m)")
    if driver != "follow":
        return
    if robot["follow"] is None or robot["follow"]["target"] is None:
        raise ScenarioError(source, "robot.follow.target", "missing; expected the target person (start, route, "
                                                           "speed) when robot.driver is follow")
    target = robot["follow"]["target"]
    if target["route"] not in scenario["routes"]:
        known = ", ".join(scenario["routes"]) or "none (the scenario has no routes)"
        raise ScenarioError(source, "robot.follow.target.route",
                            f"unknown route {target['route']!r}; expected one of: {known}")
    if target["agent_type"] not in scenario["crowd"]["agent_types"]:
        raise ScenarioError(source, "robot.follow.target.agent_type", f"unknown agent type; expected one of: "
                                                                      f"{', '.join(scenario['crowd']['agent_types'])}")
    if target["speed"] >= robot["max_speed"]:
        raise ScenarioError(source, "robot.follow.target.speed",
                            f"{target['speed']:g} m/s; expected below robot.max_speed ({robot['max_speed']:g} m/s), "
                            f"or the robot could not keep up")
    if scenario["sensors"]["tag"] is None:
        raise ScenarioError(source, "sensors.tag", "missing; expected the tag reader ({} for its defaults) when "
                                                   "robot.driver is follow: the follower tells its target by the tag")


def check_geometry(scenario: dict, source: str) -> None:
    """Cross-key checks: names that must exist, places that must be walkable, limits that must be ordered."""
    if scenario["duration"] < scenario["dt"]:
        raise ScenarioError(source, "duration", f"{scenario['duration']:g} s; expected at least one step, dt "
                                                f"({scenario['dt']:g} s)")
    crowd = scenario["crowd"]
    types = crowd["agent_types"]
    for name, t in types.items():
        if t["speed_min"] > t["speed_max"]:
            raise ScenarioError(source, f"crowd.agent_types.{name}.speed_min",
                                f"expected at most crowd.agent_types.{name}.speed_max")
    known = ", ".join(types)
    for i, src in enumerate(scenario["sources"]):
        for name in src["agent_types"]:
            if name not in types:
                raise ScenarioError(source, f"sources[{i}].agent_types.{name}",
                                    f"unknown agent type; expected one of: {known}")
        if sum(src["agent_types"].values()) <= 0:
            raise ScenarioError(source, f"sources[{i}].agent_types", "expected at least one positive weight")
    for key in ("standing", "clusters"):
        for i, g in enumerate(scenario[key]):
            if g["agent_type"] not in types:
                raise ScenarioError(source, f"{key}[{i}].agent_type", f"unknown agent type; expected one of: {known}")
    for key in ("sources", "clusters"):
        for i, g in enumerate(scenario[key]):
            if sum(g["group_size_weights"]) <= 0:
                raise ScenarioError(source, f"{key}[{i}].group_size_weights",
                                    "expected at least one positive weight (of group sizes 1, 2, ...)")
    clash = set(scenario["waypoints"]) & set(scenario["queues"])
    if clash:
        name = sorted(clash)[0]
        raise ScenarioError(source, f"queues.{name}", "a waypoint has the same name; expected unique stage names")
    stages = list(scenario["waypoints"]) + list(scenario["queues"])
    for name, route in scenario["routes"].items():
        for i, wp in enumerate(route["waypoints"]):
            if wp not in stages:
                raise ScenarioError(source, f"routes.{name}.waypoints[{i}]",
                                    f"unknown stage {wp!r}; expected a waypoint or queue: {', '.join(stages)}")
    for i, c in enumerate(scenario["clusters"]):
        if c["route"] not in scenario["routes"]:
            raise ScenarioError(source, f"clusters[{i}].route",
                                f"unknown route {c['route']!r}; expected one of: {', '.join(scenario['routes'])}")
    for i, src in enumerate(scenario["sources"]):
        for r in src["routes"]:
            if r not in scenario["routes"]:
                raise ScenarioError(source, f"sources[{i}].routes.{r}",
                                    f"unknown route; expected one of: {', '.join(scenario['routes'])}")
        if sum(src["routes"].values()) <= 0:
            raise ScenarioError(source, f"sources[{i}].routes", "expected at least one route with a positive weight")
        if src["stop"] < src["start"]:
            raise ScenarioError(source, f"sources[{i}].stop", f"expected a time after sources[{i}].start")
    seen: dict[str, str] = {}
    for kind in ("lasers", "depth_cameras", "wall_cameras", "custom"):
        for i, sensor in enumerate((scenario["sensors"][kind] or [])):
            key = f"sensors.{kind}[{i}].name"
            if not isinstance(sensor.get("name"), str):
                raise ScenarioError(source, key, f"{'missing' if 'name' not in sensor else repr(sensor['name'])}; "
                                                 "expected the sensor's name (a sensor of your own is given one too)")
            if not SENSOR_NAME.fullmatch(sensor["name"]):
                raise ScenarioError(source, key, f"{sensor['name']!r}; expected a name of letters, digits and _ . - "
                                                 "(it names the sensor's frame, its MuJoCo body and its files)")
            if sensor["name"] in seen or sensor["name"] in ("robot", "floor"):
                raise ScenarioError(source, key, f"{sensor['name']!r} is taken ({seen.get(sensor['name'], 'reserved')})"
                                                 "; expected a name of its own for every sensor")
            seen[sensor["name"]] = key
            if kind != "custom":  # a sensor of one's own checks its own parameters
                check_sensor(sensor, f"sensors.{kind}[{i}]", scenario["dt"], source)
    check_detectors(scenario, source)
    check_driver(scenario, source)
    check_places(scenario, source)


def _outer_boundary(walls: list) -> np.ndarray | None:
    """The largest closed wall polyline (first point = last), the map's outer wall where it closes; else None."""
    closed = [np.asarray(w, float)[:-1] for w in walls if len(w) > 3 and w[0] == w[-1]]
    if not closed:
        return None
    area = [abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])) / 2 for p in closed]
    return closed[int(np.argmax(area))]


def check_places(scenario: dict, source: str) -> None:
    """Every place a person, the robot or a camera is put lies in the map's free space: outside every obstacle, and,
    for places a body stands on, at least its radius from every wall. Where people stay or start (standing
    persons, a cluster's start area, a source's area, the robot, its goals and route, the follow target's start) and
    wall cameras must also lie within the map: inside the outer wall where it closes, else within the walls' extent.
    Waypoints and queues may lie beyond it (an exit outside a door)."""
    segs = wall_segments(scenario)
    if len(segs) == 0:
        return
    body = max((t["radius"] for t in scenario["crowd"]["agent_types"].values()), default=0.25)
    robot = scenario["robot"]
    places = []  # (key, point, what, clearance, what the clearance is, whether it must lie within the map, the
    #              radius of the body standing there: nearer a wall than this, it is inside it)

    def add(key, point, what, clearance=body, why="the largest body radius", in_map=True, disc=None):
        places.append((key, [float(c) for c in point[:2]], what, clearance, why, in_map,
                       clearance if disc is None else disc))

    def area(key, centre, size, what, in_map=True):  # an area's corners lie in the map (clearance 0)
        half = np.asarray(size, float) / 2
        for corner in ([-1, -1], [1, -1], [1, 1], [-1, 1]):
            add(key, np.asarray(centre) + half * corner, f"a corner of {what}", 0.0, "", in_map)

    for n, w in scenario["waypoints"].items():
        add(f"waypoints.{n}.position", w["position"], "goal", in_map=False)
    for n, q in scenario["queues"].items():
        add(f"queues.{n}.position", q["position"], "queue", in_map=False)
    for i, src in enumerate(scenario["sources"]):
        add(f"sources[{i}].position", src["position"], "source")
        area(f"sources[{i}].size", src["position"], src["size"], "the source's area")
    for i, g in enumerate(scenario["standing"]):  # the members stand on a circle round it (turned at random)
        ring = g["spacing"] / (2 * np.sin(np.pi / g["count"])) if g["count"] > 1 else 0.0
        add(f"standing[{i}].position", g["position"], "standing place", body + ring,
            "the largest body radius" + (f" beyond the group's circle of {ring:.2f} m" if ring else ""), disc=body)
    for i, c in enumerate(scenario["clusters"]):  # a cluster may wait outside a door; one inside stays inside
        add(f"clusters[{i}].position", c["position"], "cluster", in_map=False)
        area(f"clusters[{i}].spread", c["position"], c["spread"], "the cluster's start area",
             _within(scenario, segs, c["position"]))
    add("robot.start", robot["start"], "robot start", robot["radius"], "robot.radius")
    for i, p in enumerate(robot["route"] or []):
        add(f"robot.route[{i}]", p, "robot waypoint", in_map=False)
    target = (robot["follow"] or {}).get("target")
    if target is not None:
        add("robot.follow.target.start", target["start"], "the target's start")
    # a goal the robot's centre must come within goal_radius of: its disc must fit there, or a wall is in the way
    for i, p in enumerate(robot["goals"] or [] if robot["driver"] == "goals" else []):
        add(f"robot.goals[{i}]", p, "robot goal", robot["radius"], "robot.radius")
    for i, camera in enumerate(scenario["sensors"]["wall_cameras"]):
        add(f"sensors.wall_cameras[{i}].position", camera["position"], "wall camera", 0.0, "")
    pts = np.array([place[1] for place in places], float)
    dist = closest_on_segments(pts, segs)[1].min(axis=1)
    inside = np.zeros(len(pts), bool)
    for poly in scenario["map"]["obstacles"]:
        inside |= inside_polygon(pts, np.asarray(poly, float))
    within = _within(scenario, segs, pts)
    lo, hi = segs.reshape(-1, 2).min(axis=0), segs.reshape(-1, 2).max(axis=0)
    outer = _outer_boundary(scenario["map"]["walls"])
    for (key, p, what, need, why, in_map, disc), d, ins, ok in zip(places, dist, inside, within):
        if in_map and not ok:
            extent = ("inside the outer wall" if outer is not None else
                      f"within the walls' extent x {lo[0]:g}..{hi[0]:g} m, y {lo[1]:g}..{hi[1]:g} m")
            raise ScenarioError(source, key, f"{what} {_point(p)} lies outside the map; expected it {extent}")
        if ins or d < need:
            where = "inside an obstacle" if ins else f"{d:.2f} m from a wall"
            verb = "lies inside a wall" if ins or d < disc else "is too near a wall"
            raise ScenarioError(source, key, f"{what} {_point(p)} {verb} ({where}); expected at least {need:.3g} m "
                                             f"({why}) of clearance from every wall")


def _within(scenario: dict, segs: np.ndarray, points) -> np.ndarray:
    """Whether each point lies within the map: inside its outer wall where it closes (or on it), else within the
    walls' extent."""
    pts = np.atleast_2d(np.asarray(points, float))
    lo, hi = segs.reshape(-1, 2).min(axis=0), segs.reshape(-1, 2).max(axis=0)
    within = np.all((pts >= lo - 1e-9) & (pts <= hi + 1e-9), axis=1)
    if np.any(hi - lo < MIN_EXTENT):  # walls in a line bound no area: nothing to lie outside of
        within[:] = True
    outer = _outer_boundary(scenario["map"]["walls"])
    if outer is not None:
        within &= inside_polygon(pts, outer) | (closest_on_segments(pts, segs)[1].min(axis=1) < 1e-9)
    return within if np.ndim(points) > 1 else bool(within[0])


def _point(p) -> str:
    return "[" + ", ".join(f"{c:g}" for c in p) + "]"
