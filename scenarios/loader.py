"""Finding, reading and validating scenario files: schema checks first, then the checks that need geometry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from .format import DETECTOR_READS, SCENARIO
from .geometry import closest_on_segments, inside_polygon, wall_segments
from .pedsim import pedsim_to_scenario
from .schema import ScenarioError, validate

BUNDLED = Path(__file__).parent / "bundled"


def bundled_scenarios() -> dict[str, str]:
    """Bundled scenario name -> the first sentence of its description."""
    out = {}
    for path in sorted(BUNDLED.glob("*.yaml")):
        with open(path) as f:
            description = (yaml.safe_load(f) or {}).get("description", "")
        first = description.strip().split("\n")[0]
        out[path.stem] = first.split(". ")[0].rstrip(".") + "."
    return out


def resolve(name_or_path: str) -> Path:
    """A bundled name (``airport_disembarkation``), a path to a YAML file, or a PedSim XML scenario file (a folder
    of the bundled name, a run's output say, does not hide the bundled scenario)."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml", ".xml") or path.is_file():
        if not path.is_file():
            raise ScenarioError(str(path), "<file>", "no such scenario file")
        return path
    bundled = BUNDLED / f"{name_or_path}.yaml"
    if bundled.is_file():
        return bundled
    names = ", ".join(bundled_scenarios())
    raise ScenarioError(name_or_path, "<scenario>",
                        f"not a bundled scenario, a YAML file nor a PedSim XML file; bundled: {names}")


def merge(base: dict, changes: dict) -> dict:
    """``base`` with ``changes`` laid over it: mappings merge key by key, anything else is replaced."""
    out = dict(base)
    for key, value in changes.items():
        out[key] = merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def read_raw(path: Path, seen: tuple = ()) -> dict:
    """The file's data, with ``base: NAME_OR_PATH`` resolved: the base scenario's data, then this file's over it."""
    source = str(path)
    try:
        with open(path, encoding="utf-8") as f:
            raw = yaml.safe_load(f)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise ScenarioError(source, "<file>", f"not valid YAML{where}: {problem}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ScenarioError(source, "<file>", f"cannot be read as UTF-8 text: {e}") from None
    if not isinstance(raw, dict):
        raise ScenarioError(source, "<top level>", "expected a mapping of keys")
    if "base" in raw:
        name = raw.pop("base")
        if not isinstance(name, str):
            raise ScenarioError(source, "base", f"expected a scenario name or path, got {name!r}")
        local = path.parent / name
        base_path = resolve(str(local) if local.suffix in (".yaml", ".yml") and local.is_file() else name)
        if base_path.resolve() in seen:
            raise ScenarioError(source, "base", f"{name!r} leads back to this file; expected no cycle")
        raw = merge(read_raw(base_path, seen + (path.resolve(),)), raw)
    return raw


def load_scenario(name_or_path: str, **overrides) -> dict:
    """The validated scenario as plain data, defaults filled in; ``overrides`` replace top-level keys. A ``.xml``
    path is read as a PedSim scenario (``scenarios.pedsim``)."""
    path = resolve(name_or_path)
    if path.suffix.lower() == ".xml":
        raw = pedsim_to_scenario(path)
    else:
        raw = read_raw(path)
    raw.update({k: v for k, v in overrides.items() if v is not None})
    return scenario_from_dict(raw, str(path))


def scenario_from_dict(raw: dict, source: str = "<scenario>") -> dict:
    """Validate scenario data given as a dict (as a YAML file would hold it); ``source`` names it in errors."""
    scenario = validate(raw, SCENARIO, source)
    check_geometry(scenario, source)
    scenario["source"] = source
    return scenario


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
    kinds = {s["name"]: kind for kind in ("lasers", "depth_cameras", "wall_cameras") for s in scenario["sensors"][kind]}
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
    for key, spec, kind, what in attached:
        reads = DETECTOR_READS.get(spec["type"], kind)  # a class of one's own reads what it is given
        if reads != kind:
            raise ScenarioError(source, f"{key}.type", f"{spec['type']} reads sensors.{reads}, and {what} is one of "
                                                       f"sensors.{kind}; expected a detector for sensors.{kind}")


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
    for kind in ("lasers", "depth_cameras", "wall_cameras"):
        for i, sensor in enumerate(scenario["sensors"][kind]):
            key = f"sensors.{kind}[{i}].name"
            if sensor["name"] in seen or sensor["name"] in ("robot", "floor"):
                raise ScenarioError(source, key, f"{sensor['name']!r} is taken ({seen.get(sensor['name'], 'reserved')})"
                                                 "; expected a name of its own for every sensor")
            seen[sensor["name"]] = key
            check_sensor(sensor, f"sensors.{kind}[{i}]", scenario["dt"], source)
    check_detectors(scenario, source)
    check_driver(scenario, source)
    segs = wall_segments(scenario)
    radius = max(t["radius"] for t in types.values()) if types else 0.25
    places = [(f"waypoints.{n}.position", w["position"], "goal") for n, w in scenario["waypoints"].items()]
    places += [(f"queues.{n}.position", q["position"], "queue") for n, q in scenario["queues"].items()]
    places += [(f"sources[{i}].position", s["position"], "source") for i, s in enumerate(scenario["sources"])]
    places += [(f"standing[{i}].position", s["position"], "standing place") for i, s in enumerate(scenario["standing"])]
    places += [("robot.start", scenario["robot"]["start"][:2], "robot start")]
    places += [(f"robot.route[{i}]", p, "robot waypoint") for i, p in enumerate(scenario["robot"]["route"] or [])]
    target = (scenario["robot"]["follow"] or {}).get("target")
    if target is not None:
        places += [("robot.follow.target.start", target["start"], "the target's start")]
    clearance = np.full(len(places), radius)
    what_clearance = ["the largest body radius"] * len(places)
    # a goal the robot's centre must come within goal_radius of: its disc must fit there, or a wall is in the way
    goals = (scenario["robot"]["goals"] or []) if scenario["robot"]["driver"] == "goals" else []
    places += [(f"robot.goals[{i}]", p, "robot goal") for i, p in enumerate(goals)]
    clearance = np.r_[clearance, np.full(len(goals), scenario["robot"]["radius"])]
    what_clearance += ["robot.radius"] * len(goals)
    if not places or len(segs) == 0:
        return
    pts = np.array([p for _, p, _ in places], float)
    dist = closest_on_segments(pts, segs)[1].min(axis=1)
    inside = np.zeros(len(pts), bool)
    for poly in scenario["map"]["obstacles"]:
        inside |= inside_polygon(pts, np.asarray(poly, float))
    for (key, p, what), d, ins, need, why in zip(places, dist, inside, clearance, what_clearance):
        if ins or d < need:
            where = "inside an obstacle" if ins else f"{d:.2f} m from a wall"
            raise ScenarioError(source, key, f"{what} {p} lies inside a wall ({where}); expected at least "
                                             f"{need:g} m ({why}) of clearance from every wall")
