"""Import of PedSim scenario files (pedsim_ros XML) into the scenario format.

``pedsim_to_scenario(path)`` returns raw scenario data (a dict as a YAML file would hold it);
``scenarios.load_scenario`` validates it, as it does any ``.xml`` path. Anything the importer cannot carry over, or has
to change, is reported as a ``PedsimWarning`` naming the XML file, the line and the element; malformed files raise
``ScenarioError`` naming the file and, where known, the line.

How PedSim's elements map (PedSim's units are metres, as ours):

``<obstacle x1 y1 x2 y2/>``
    one wall: a two-point polyline in ``map.walls`` (one per element, in file order). A zero-length obstacle is
    skipped with a warning.
``<waypoint id x y r [b]/>``
    ``waypoints.<id>`` with ``radius`` r. ``b`` is PedSim's waypoint behaviour (libpedsim: 0 simple, 1 source,
    2 sink). pedsim_ros acts only on sinks: an agent whose current destination is a sink is removed once inside its
    radius. So a route is cut after its first sink stage and gets ``sink: true``; stages after it (never reached in
    PedSim) are dropped with a warning. ``b="1"`` (source) changes nothing in pedsim_ros and is read as a plain
    waypoint. Any other value: a warning, then a plain waypoint.
``<queue id x y direction/>``
    ``queues.<id>``: the service point at (x, y), the line growing towards ``direction`` degrees. The service time
    is PedSim's mean: pedsim_ros releases the head of the line after a Gamma(2, 0.5 s) wait, 1 s on average.
``<attraction id x y width height strength/>``
    ``attractions.<id>``: the area centred at (x, y) (as pedsim_ros's shopping planner reads it), ``size`` [width,
    height] and ``strength`` as given; ``reach`` and ``visit_time`` keep the format's defaults (PedSim's own
    attraction probability and 15 s shopping time are modelled differently, see ``crowdsim.crowd``).
``<agent x y n dx dy type>`` with ``<addwaypoint id/>`` / ``<addqueue id/>`` children
    pedsim_ros's AgentCluster: n persons placed uniformly in the dx x dy rectangle centred at (x, y), who visit the
    stages in order and then start over (pedsim_ros's Agent cycles its destination list). With stages: a
    ``clusters`` entry on a route of its own named ``agent_line<L>`` (L: the element's line), ``sink: false``
    unless a stage is a sink. Without stages pedsim_ros's agents wait where they were put (StateWaiting): they become
    ``standing`` persons, one entry each on a regular grid over the dx x dy area (no random draw at import), or,
    for dx = dy = 0 and n <= 12, one standing group of n around (x, y).
    Types (pedsim_ros's Ped::Tagent::AgentType): 0 adult, 1 child, 2 robot, 3 elder; others: a warning, adult.
    pedsim_ros's elders walk slowly (vmax 0.9 m/s), which our ``elder`` type matches; older pedsim_ros releases
    made them stand still, which ``contexts/standing.xml`` still assumes - we import them as walking elders.
    The first type-2 agent is the ``robot``: start at its (x, y) (dx, dy and n ignored), heading towards its first
    stage at another place, its route the stages' positions, driven in a loop; a single stage gives the route
    [start, stage] driven once. Further type-2 agents: a warning, ignored. Without any, the robot is parked with no
    route at the first waypoint its radius away from every wall (else the walls' bounding-box centre, moved off the
    walls if need be) and a warning says so.
``<source x y n dx dy type>`` with stages
    pedsim_ros reads it as an AgentCluster of n persons (present from the start) plus a SpawnArea that adds n more
    every ``spawn_period`` (a ROS parameter, 5 s by default). So: a ``clusters`` entry of n persons and a
    ``sources`` entry over the same area emitting n / 5 s on average (Poisson, single persons), both on the route
    ``source_line<L>``. (pedsim_ros spawns later waves as adults whatever the type; we keep the given type.)
``<scenario>`` is the root; ``<welcome>`` is accepted and ignored, as pedsim_ros does. Any other element (and
``<addwaypoint>`` / ``<addqueue>`` outside an agent) gives one warning naming it and its line, and is ignored.
Comments are ignored. Stage names may refer to waypoints or queues defined anywhere in the file; as in pedsim_ros
waypoints and queues share one namespace, and a later definition of a name replaces an earlier one (a warning).

Places the loader requires to be walkable (waypoints, queues, sources, standing persons: at least the largest body
radius, 0.25 m, from every wall) that PedSim files put on or next to a wall are moved the least distance that gives
that clearance plus 5 cm, with a warning naming the element and its line (a place exactly on a wall leaves it towards
the side the walls' bounding-box centre is on). The robot's start needs its own radius, 0.425 m, in the same way.

The rest is filled in: name = file stem, description "PedSim scenario <file name>", seed 0, 60 s, the airport
scenario's two back-to-back lasers at 0.70 m, and the format's defaults (crowd, pipeline, evaluation), except that
``crowd.max_agents`` is raised above the number of persons present at the start when that reaches the default.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from .costs import MAX_AGENTS
from .format import CROWD, DEFAULT_AGENT_TYPES, ROBOT
from .geometry import closest_on_segments
from .schema import ScenarioError

# pedsim_ros's default ``group_size_lambda``: it divides the persons of an <agent> or <source> into groups whose
# sizes follow a Poisson distribution of this mean with size 0 redrawn
GROUP_SIZE_LAMBDA = 1.1
LARGEST_GROUP = 6  # sizes above this have probability < 0.1% at lambda 1.1 and are left out


def zero_truncated_poisson(lam: float, largest: int) -> list[float]:
    """P(size = k | size > 0) for k = 1 .. largest under Poisson(lam)."""
    k = np.arange(1, largest + 1)
    pmf = np.exp(-lam) * lam**k / np.array([math.factorial(int(i)) for i in k])
    return (pmf / -math.expm1(-lam)).tolist()


GROUP_SIZE_WEIGHTS = zero_truncated_poisson(GROUP_SIZE_LAMBDA, LARGEST_GROUP)
SPAWN_PERIOD = 5.0  # s, pedsim_ros's default ``spawn_period``: a <source> adds n persons this often
QUEUE_SERVICE_TIME = 1.0  # s, mean of pedsim_ros's Gamma(alpha=2, beta=0.5 s) wait at the head of a line
BODY_CLEARANCE = max(t["radius"] for t in DEFAULT_AGENT_TYPES.values())  # m, what the loader asks of places
MARGIN = 0.05  # m, added to a clearance when a place has to be moved
ROBOT_CLEARANCE = ROBOT.fields["radius"].default  # m, the robot start's least distance from every wall
DEFAULT_MAX_AGENTS = CROWD.fields["max_agents"].default
GRID_SPACING = 0.7  # m, between standing persons when a cluster without stages has no area to spread over
AGENT_TYPES = {0: "adult", 1: "child", 2: "robot", 3: "elder"}  # pedsim_ros's Ped::Tagent::AgentType
SINK = 2  # libpedsim's Twaypoint::Behavior: SIMPLE 0, SOURCE 1, SINK 2
MAX_DEPTH = 16  # nested elements (a PedSim file has 3: <scenario>, <agent>, <addwaypoint>)

# the airport scenario's sensors: two SICK LMS500 back to back at 0.70 m (seed 000 Sec. IV-A)
SENSORS = {"lasers": [{"name": "front_laser", "mount": [0.25, 0.0, 0.0], "height": 0.70},
                      {"name": "rear_laser", "mount": [-0.25, 0.0, math.pi], "height": 0.70}]}

KNOWN_ATTRIBUTES = {
    "scenario": set(), "welcome": None,  # None: any attribute
    "obstacle": {"x1", "y1", "x2", "y2"},
    "waypoint": {"id", "x", "y", "r", "b"},
    "queue": {"id", "x", "y", "direction"},
    "attraction": {"id", "x", "y", "width", "height", "strength"},
    "agent": {"x", "y", "n", "dx", "dy", "type"},
    "source": {"x", "y", "n", "dx", "dy", "type"},
    "addwaypoint": {"id"}, "addqueue": {"id"},
}


class PedsimWarning(UserWarning):
    """Something in a PedSim file that the import ignores or changes."""


@dataclass
class _Element:
    tag: str
    attrs: dict
    line: int
    children: list = field(default_factory=list)

    def __str__(self) -> str:
        return f"<{self.tag} id='{self.attrs['id']}'>" if "id" in self.attrs else f"<{self.tag}>"


@dataclass
class _Group:
    """An <agent> or <source> element, read."""

    element: _Element
    position: np.ndarray
    count: int
    spread: list
    type_code: int
    stages: list  # (stage name, <addwaypoint>/<addqueue> element)


def _parse(path: Path) -> _Element:
    """The XML tree with each element's line; ScenarioError for a file that cannot be read or parsed."""
    source = str(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise ScenarioError(source, "<file>", f"cannot be read: {e}") from None
    parser = expat.ParserCreate()
    stack: list[_Element] = []
    roots: list[_Element] = []

    def start(tag, attrs):
        if len(stack) >= MAX_DEPTH:
            raise ScenarioError(source, f"<{tag}> at line {parser.CurrentLineNumber}",
                                f"nested more than {MAX_DEPTH} elements deep; expected a PedSim scenario's <scenario> "
                                "with its elements and their <addwaypoint> children")
        el = _Element(tag, dict(attrs), parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(el)
        stack.append(el)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    try:
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise ScenarioError(source, "<file>", f"not valid XML at line {e.lineno}, column {e.offset + 1}: "
                                              f"{expat.ErrorString(e.code)}") from None
    except (LookupError, UnicodeError) as e:  # an encoding the declaration names that Python has not, or breaks
        raise ScenarioError(source, "<file>", f"cannot be decoded ({e}); expected UTF-8 or another encoding the "
                                              "XML declaration names rightly") from None
    root = roots[0]
    if root.tag != "scenario":
        raise ScenarioError(source, f"<{root.tag}> at line {root.line}",
                            "expected a PedSim scenario: a <scenario> root element")
    return root


class _Converter:
    def __init__(self, path: Path):
        self.path = path
        self.source = str(path)
        self.walls: list[list[list[float]]] = []
        self.waypoints: dict[str, dict] = {}
        self.queues: dict[str, dict] = {}
        self.attractions: dict[str, dict] = {}
        self.places: dict[str, _Element] = {}  # stage name -> the element defining it
        self.groups: list[_Group] = []
        self.sources: list[_Group] = []

    # -- reporting ----------------------------------------------------------------------------------------------

    def warn(self, el: _Element, message: str) -> None:
        warnings.warn(f"{self.source}:{el.line}: {el} {message}", PedsimWarning, stacklevel=2)

    def error(self, el: _Element, message: str) -> ScenarioError:
        return ScenarioError(self.source, f"{el} at line {el.line}", message)

    def number(self, el: _Element, name: str, default: float | None = None) -> float:
        text = el.attrs.get(name)
        if text is None:
            if default is None:
                raise self.error(el, f"missing attribute '{name}'")
            return default
        try:
            value = float(text)
        except ValueError:
            raise self.error(el, f"attribute '{name}': expected a number, got {text!r}") from None
        if not math.isfinite(value):
            raise self.error(el, f"attribute '{name}': expected a finite number, got {text!r}")
        return value

    def integer(self, el: _Element, name: str, default: int | None = None) -> int:
        value = self.number(el, name, None if default is None else float(default))
        if value != int(value):
            raise self.error(el, f"attribute '{name}': expected an integer, got {el.attrs[name]!r}")
        return int(value)

    def name(self, el: _Element) -> str:
        text = el.attrs.get("id", "").strip()
        if not text:
            raise self.error(el, "missing attribute 'id'")
        return text

    # -- reading ------------------------------------------------------------------------------------------------

    def read(self, parent: _Element, group: _Group | None = None) -> None:
        """Every element below ``parent`` in file order, at any depth as pedsim_ros's stream reader does;
        ``group``: the <agent> or <source> that <addwaypoint> and <addqueue> add stages to."""
        for el in parent.children:
            known = KNOWN_ATTRIBUTES.get(el.tag)
            if known is not None:
                extra = sorted(set(el.attrs) - known)
                if extra:
                    self.warn(el, f"has attributes PedSim does not read ({', '.join(extra)}); ignored")
            inner = group
            if el.tag in ("addwaypoint", "addqueue"):
                if group is None:
                    self.warn(el, "outside an <agent> or <source>; ignored")
                else:
                    group.stages.append((self.name(el), el))
            elif el.tag in ("agent", "source"):
                inner = self.read_group(el)
                (self.groups if el.tag == "agent" else self.sources).append(inner)
            elif el.tag in ("obstacle", "waypoint", "queue", "attraction"):
                getattr(self, f"read_{el.tag}")(el)
            elif el.tag not in ("scenario", "welcome"):
                self.warn(el, "is not a PedSim scenario element; ignored")
            self.read(el, inner)

    def read_obstacle(self, el: _Element) -> None:
        a = [self.number(el, "x1"), self.number(el, "y1")]
        b = [self.number(el, "x2"), self.number(el, "y2")]
        if a == b:
            self.warn(el, "has zero length; ignored")
            return
        self.walls.append([a, b])

    def define(self, el: _Element, name: str) -> None:
        old = self.places.get(name)
        if old is not None:
            self.warn(el, f"replaces the {old.tag} of the same name at line {old.line} (as in PedSim)")
            self.waypoints.pop(name, None)
            self.queues.pop(name, None)
        self.places[name] = el

    def read_waypoint(self, el: _Element) -> None:
        name = self.name(el)
        position = [self.number(el, "x"), self.number(el, "y")]
        radius = self.number(el, "r")
        behaviour = self.integer(el, "b", 0)
        if behaviour not in (0, 1, SINK):
            self.warn(el, f"has an unknown behaviour b={behaviour} (0 simple, 1 source, 2 sink); read as simple")
        if radius <= 0:
            raise self.error(el, f"attribute 'r': expected a radius greater than 0, got {el.attrs['r']!r}")
        self.define(el, name)
        self.waypoints[name] = {"position": position, "radius": radius, "sink": behaviour == SINK}

    def read_queue(self, el: _Element) -> None:
        name = self.name(el)
        position = [self.number(el, "x"), self.number(el, "y")]
        direction = self.number(el, "direction", 0.0)
        self.define(el, name)
        self.queues[name] = {"position": position, "direction_deg": direction, "service_time": QUEUE_SERVICE_TIME}

    def read_attraction(self, el: _Element) -> None:
        name = self.name(el)
        size = [self.number(el, "width"), self.number(el, "height")]
        strength = self.number(el, "strength")
        if min(size) < 0 or strength < 0:
            raise self.error(el, "expected a width, height and strength of at least 0")
        if name in self.attractions:
            self.warn(el, "replaces the attraction of the same name (as in PedSim)")
        self.attractions[name] = {"position": [self.number(el, "x"), self.number(el, "y")], "size": size,
                                  "strength": strength}

    def read_group(self, el: _Element) -> _Group:
        count = self.integer(el, "n")
        spread = [self.number(el, "dx", 0.0), self.number(el, "dy", 0.0)]
        if count < 0 or min(spread) < 0:
            raise self.error(el, "expected n, dx and dy of at least 0")
        return _Group(el, np.array([self.number(el, "x"), self.number(el, "y")]), count, spread,
                      self.integer(el, "type", 0), [])

    # -- building -----------------------------------------------------------------------------------------------

    def segments(self) -> np.ndarray:
        return np.array(self.walls, float).reshape(-1, 2, 2)

    def inside_hint(self) -> np.ndarray:
        """A point that is likely inside the walls: the centre of their bounding box."""
        segs = self.segments()
        if not len(segs):
            return np.zeros(2)
        pts = segs.reshape(-1, 2)
        return (pts.min(axis=0) + pts.max(axis=0)) / 2

    def clearance(self, p: np.ndarray) -> float:
        segs = self.segments()
        if not len(segs):
            return math.inf
        return float(closest_on_segments(np.asarray(p, float)[None], segs)[1].min())

    def off_walls(self, p, need: float) -> np.ndarray | None:
        """``p`` moved the least distance that puts it ``need`` + MARGIN from every wall; None when it already has
        ``need``."""
        p = np.asarray(p, float)
        segs = self.segments()
        if not len(segs) or self.clearance(p) >= need:
            return None
        target = need + MARGIN
        q = p.copy()
        for _ in range(8):  # push away from the nearest wall; a corner may take a second push
            away, dist = closest_on_segments(q[None], segs)
            k = int(dist[0].argmin())
            if dist[0, k] >= need:
                return q
            if dist[0, k] > 1e-9:
                u = away[0, k] / dist[0, k]
            else:  # on the wall: leave towards the side the map's centre is on
                d = segs[k, 1] - segs[k, 0]
                u = np.array([-d[1], d[0]]) / np.linalg.norm(d)
                if np.dot(self.inside_hint() - q, u) < 0:
                    u = -u
            q = q + u * (target - dist[0, k])
        # a narrow gap: the nearest point on rings around p that is clear
        for radius in np.arange(0.05, 5.0, 0.05):
            a = np.linspace(0, 2 * np.pi, 72, endpoint=False)
            ring = p + radius * np.stack([np.cos(a), np.sin(a)], 1)
            dist = closest_on_segments(ring, segs)[1].min(axis=1)
            if (dist >= target).any():
                return ring[int(np.argmax(dist >= target))]
        return None

    def fix(self, el: _Element, what: str, p, need: float = BODY_CLEARANCE) -> list[float]:
        moved = self.off_walls(p, need)
        if moved is None:
            return [float(c) for c in p]
        self.warn(el, f"{what} ({p[0]:g}, {p[1]:g}) lies {self.clearance(p):.2f} m from a wall; moved "
                      f"{np.linalg.norm(moved - np.asarray(p, float)):.2f} m to ({moved[0]:.2f}, {moved[1]:.2f})")
        return [float(moved[0]), float(moved[1])]

    def agent_type(self, g: _Group) -> str:
        name = AGENT_TYPES.get(g.type_code)
        if name is None or name == "robot":
            what = "the robot type (2)" if name else f"unknown type {g.type_code} (0 adult, 1 child, 2 robot, 3 elder)"
            self.warn(g.element, f"has {what}; persons imported as adults")
            return "adult"
        return name

    def route(self, g: _Group, routes: dict, name: str) -> tuple[str | None, list[np.ndarray]]:
        """The route of a group's stages (None when it has none), and their positions."""
        stages, positions = [], []
        for stage, child in g.stages:
            if stage in self.queues:  # also for <addwaypoint>: pedsim_ros has one namespace, and queues there
                positions.append(np.array(self.queues[stage]["position"]))
            elif stage in self.waypoints:
                if child.tag == "addqueue":
                    self.warn(child, f"names the waypoint '{stage}', not a queue; used as a waypoint")
                positions.append(np.array(self.waypoints[stage]["position"]))
            else:
                self.warn(child, f"names no waypoint or queue ('{stage}'); stage ignored")
                continue
            stages.append(stage)
            if stage in self.waypoints and self.waypoints[stage]["sink"]:
                if g.stages[-1][1] is not child:
                    self.warn(child, f"names the sink '{stage}': persons leave there, so the stages after it "
                                     "are never reached; dropped")
                routes[name] = {"waypoints": stages, "sink": True}
                return name, positions
        if not stages:
            return None, []
        routes[name] = {"waypoints": stages, "sink": False}
        return name, positions

    def standing(self, g: _Group, agent_type: str) -> list[dict]:
        """Persons of a cluster without stages: on a grid over its area (a group of n when it has none)."""
        el, n = g.element, g.count
        if n > MAX_AGENTS:  # each becomes an entry of its own: refused before they are made
            raise self.error(el, f"n={n:,} standing persons; expected at most {MAX_AGENTS:,} (scenarios/costs.py)")
        w, h = g.spread
        if w == 0 and h == 0 and n <= 12:
            pos = self.fix(el, "standing group", g.position)
            return [{"position": pos, "count": n, "agent_type": agent_type}]
        if w == 0 and h == 0:
            w = h = GRID_SPACING * math.ceil(math.sqrt(n))
        cols = n if h == 0 else 1 if w == 0 else min(n, max(1, round(math.sqrt(n * w / h))))
        rows = math.ceil(n / cols)
        out, moved = [], 0
        for i in range(n):
            r, c = divmod(i, cols)
            p = g.position + [(c + 0.5) * w / cols - w / 2, (r + 0.5) * h / rows - h / 2]
            q = self.off_walls(p, BODY_CLEARANCE)
            moved += q is not None
            p = p if q is None else q
            out.append({"position": [float(p[0]), float(p[1])], "agent_type": agent_type})
        if moved:
            self.warn(el, f"{moved} of its {n} standing persons lay within {BODY_CLEARANCE} m of a wall; moved off it")
        return out

    def build(self) -> dict:
        # places first: every later position (routes, the robot's) uses the moved ones
        for name, wp in self.waypoints.items():
            wp["position"] = self.fix(self.places[name], "position", wp["position"])
        for name, q in self.queues.items():
            q["position"] = self.fix(self.places[name], "position", q["position"])
        routes: dict[str, dict] = {}
        clusters, standing, sources = [], [], []
        robot = None
        for g in self.groups:
            el = g.element
            if g.type_code == 2:
                if robot is not None:
                    self.warn(el, "is a further robot (type 2); only the first is simulated; ignored")
                    continue
                if g.count != 1:
                    self.warn(el, f"is the robot but has n={g.count}; one robot is simulated")
                robot = self.robot(g)
                continue
            if g.count == 0:
                self.warn(el, "has n=0: no persons")
                continue
            agent_type = self.agent_type(g)
            name, _ = self.route(g, routes, f"agent_line{el.line}")
            if name is None:
                standing += self.standing(g, agent_type)
            else:
                clusters.append({"position": [float(c) for c in g.position], "count": g.count,
                                 "spread": [float(c) for c in g.spread], "route": name, "agent_type": agent_type,
                                 "group_size_weights": GROUP_SIZE_WEIGHTS})
        for g in self.sources:
            el = g.element
            agent_type = self.agent_type(g)
            name, _ = self.route(g, routes, f"source_line{el.line}")
            if name is None:
                self.warn(el, "has no stages; a source needs a route: ignored")
                continue
            if g.count == 0:
                self.warn(el, "has n=0: emits no persons")
                continue
            clusters.append({"position": [float(c) for c in g.position], "count": g.count,
                             "spread": [float(c) for c in g.spread], "route": name, "agent_type": agent_type,
                             "group_size_weights": GROUP_SIZE_WEIGHTS})
            sources.append({"position": self.fix(el, "position", g.position), "size": [float(c) for c in g.spread],
                            "rate": g.count / SPAWN_PERIOD, "routes": {name: 1.0}, "agent_types": {agent_type: 1.0},
                            "group_size_weights": GROUP_SIZE_WEIGHTS})
        if robot is None:
            robot = self.parked_robot()
        raw = {
            "name": self.path.stem,
            "description": f"PedSim scenario {self.path.name}",
            "seed": 0,
            "duration": 60.0,
            "map": {"walls": self.walls, "obstacles": []},
            "waypoints": {n: {"position": w["position"], "radius": w["radius"]} for n, w in self.waypoints.items()},
            "queues": self.queues,
            "attractions": self.attractions,
            "routes": routes,
            "sources": sources,
            "standing": standing,
            "clusters": clusters,
            "robot": robot,
            "sensors": {"lasers": [dict(laser, mount=list(laser["mount"])) for laser in SENSORS["lasers"]]},
        }
        alive = sum(c["count"] for c in clusters) + sum(s.get("count", 1) for s in standing)
        if alive >= DEFAULT_MAX_AGENTS:
            raw["crowd"] = {"max_agents": alive + 100}  # room for the sources beyond the persons present at start
        return raw

    def robot(self, g: _Group) -> dict:
        start = np.array(self.fix(g.element, "robot start", g.position, ROBOT_CLEARANCE))
        _, positions = self.route(g, {}, "robot")
        yaw = 0.0
        for p in positions:
            d = p - start
            if np.hypot(*d) > 1e-6:
                yaw = math.atan2(d[1], d[0])
                break
        out = {"start": [float(start[0]), float(start[1]), yaw]}
        if len(positions) == 1:
            out.update(route=[[float(c) for c in start], [float(c) for c in positions[0]]], loop=False)
        elif positions:
            out.update(route=[[float(c) for c in p] for p in positions], loop=True)
        return out

    def parked_robot(self) -> dict:
        candidates = [np.array(w["position"]) for w in self.waypoints.values()] + [self.inside_hint()]
        for p in candidates:
            if self.clearance(p) >= ROBOT_CLEARANCE:
                break
        else:
            p = candidates[0]
            moved = self.off_walls(p, ROBOT_CLEARANCE)
            p = p if moved is None else moved
        warnings.warn(f"{self.source}: no robot (an <agent> of type 2); the robot is parked at "
                      f"({p[0]:.2f}, {p[1]:.2f}) without a route", PedsimWarning, stacklevel=2)
        return {"start": [float(p[0]), float(p[1]), 0.0]}


def pedsim_to_scenario(path) -> dict:
    """The PedSim scenario file at ``path`` as raw scenario data, ready for ``scenario_from_dict``."""
    path = Path(path)
    converter = _Converter(path)
    converter.read(_parse(path))
    return converter.build()
