"""The scenario format: every key, its unit, default and allowed range, in one schema.

Defaults are the seeds' and the literature's values where they give one; each says where it comes from.
"""

from __future__ import annotations

import math

from pipeline.detectors import DETECTORS
from pipeline.fusion import FUSIONS
from pipeline.groups import GROUP_STAGES
from pipeline.map_filter import MapFilter
from pipeline.navigation.planners import PLANNER as PLANNER_SLOT
from pipeline.tracking.mht import MHTParams
from pipeline.tracking.nnt import NearestNeighbourTracker
from pipeline.tracking.rgbd_tracker import RgbdTracker
from pipeline.tracking.rjmcmc import RjmcmcTracker
from sensors.camera import DepthCamera, WallCamera
from sensors.laser import Laser
from sensors.tag import TagSensor

from crowdsim.drivers import DRIVERS  # (the robot's body and drivers only: they import no more of the simulator)
from crowdsim.robot import Robot

from .laser_presets import LASER_PRESETS
from .schema import Field, ListOf, MapOf, Schema, ScenarioError, Typed, schema_of, slot_field, slot_typed, validate

F = Field


# Checks across a part's keys, run when the file is loaded (scenarios.schema.Schema.checks): each takes the part's
# validated values and returns None, or the key at fault and what was expected. They are the rules the parts'
# constructors hold, so a file that breaks one gets one error naming the key before anything is built.

def _extent(key: str):
    def check(p: dict):
        if min(p[key]) < 0:
            return key, f"{p[key]}; expected a width and height of at least 0 m"
    return check


AGENT_TYPE = Schema({
    "speed_mean": F("float", 1.34, min=0.0, doc="m/s, mean desired speed"),
    "speed_std": F("float", 0.26, min=0.0, doc="m/s, standard deviation of the desired speed"),
    "speed_min": F("float", 0.6, min=0.0, doc="m/s, lower clip of the drawn desired speed"),
    "speed_max": F("float", 2.0, min=0.0, doc="m/s, upper clip of the drawn desired speed"),
    "radius": F("float", 0.25, min=0.05, max=1.0, doc="m, body radius for contacts (shoulder half-width)"),
})

# adults: Helbing & Molnar 1995, N(1.34, 0.26) m/s. Children and elders walk slower and are smaller; these values
# are assumptions of the order Weidmann's age curve gives, not measurements.
DEFAULT_AGENT_TYPES = {
    "adult": {"speed_mean": 1.34, "speed_std": 0.26, "speed_min": 0.6, "speed_max": 2.0, "radius": 0.25},
    "child": {"speed_mean": 1.1, "speed_std": 0.2, "speed_min": 0.5, "speed_max": 1.6, "radius": 0.18},
    "elder": {"speed_mean": 0.9, "speed_std": 0.2, "speed_min": 0.4, "speed_max": 1.4, "radius": 0.23},
}

CROWD = Schema({
    "agent_types": F(MapOf(F(AGENT_TYPE), by_name=True), DEFAULT_AGENT_TYPES,
                     doc="type name -> speed distribution and size; merged by name into the default types (adult, "
                         "child, elder): `NAME: !remove` drops one, `agent_types: !replace {...}` keeps only those "
                         "given"),
    "max_speed_factor": F("float", 1.3, min=1.0, doc="maximum speed = factor x desired speed (Helbing & Molnar 1995)"),
    "relaxation_time": F("float", 0.5, min=0.0, exclusive_min=True, doc="s, tau of the desired force (HM 1995)"),
    "interaction": F("str", "moussaid2009", choices=("moussaid2009", "helbing_molnar1995"),
                     doc="agent-agent force: Moussaid et al. 2009 (as PedSim) or Helbing & Molnar 1995"),
    "moussaid_strength": F("float", 4.5, min=0.0, doc="m/s^2, A (Moussaid et al. 2009)"),
    "moussaid_lambda": F("float", 2.0, min=0.0, doc="lambda, weight of the relative velocity (Moussaid 2009)"),
    "moussaid_gamma": F("float", 0.35, min=0.0, exclusive_min=True, doc="gamma (Moussaid et al. 2009)"),
    "moussaid_n": F("float", 2.0, min=0.0, doc="n, angular decay of the turning term (Moussaid et al. 2009)"),
    "moussaid_n_prime": F("float", 3.0, min=0.0, doc="n', angular decay of the braking term (Moussaid 2009)"),
    "agent_strength": F("float", 2.1, min=0.0, doc="m^2/s^2, V0 of the elliptical agent potential (HM 1995)"),
    "agent_range": F("float", 0.3, min=0.0, exclusive_min=True, doc="m, sigma of the agent potential (HM 1995)"),
    "step_time": F("float", 2.0, min=0.0, doc="s, Delta t of the elliptical potential's step width (HM 1995)"),
    "wall_strength": F("float", 25.0, min=0.0,
                       doc="m/s^2, A of the wall force at contact (Helbing, Farkas & Vicsek 2000: 2000 N / 80 kg)"),
    "wall_range": F("float", 0.08, min=0.0, exclusive_min=True,
                    doc="m, B, decay length of the wall force (Helbing, Farkas & Vicsek 2000)"),
    "fov_deg": F("float", 200.0, min=0.0, max=360.0, doc="deg, 2 phi of the anisotropic weighting (HM 1995)"),
    "out_of_view_weight": F("float", 0.46, min=0.0, max=1.0,
                            doc="c, weight of forces from behind (HM 1995 use 0.5; 0.46 puts the RiMEA 4 ring "
                                "within 20% of Weidmann from 0.5 to 3 persons/m^2)"),
    "interaction_range": F("float", 5.0, min=0.0, exclusive_min=True, doc="m, neighbour search radius"),
    "wall_interaction_range": F("float", 2.0, min=0.0, exclusive_min=True, doc="m, walls nearer than this repel"),
    "group_gaze": F("float", 4.0, min=0.0, doc="beta_1, gaze term of walking groups (Moussaid et al. 2010)"),
    "group_coherence": F("float", 3.0, min=0.0, doc="m/s^2, beta_2, coherence (Moussaid et al. 2010)"),
    "group_repulsion": F("float", 1.0, min=0.0, doc="m/s^2, beta_3, repulsion between members (Moussaid 2010)"),
    "robot_strength": F("float", 10.0, min=0.0, doc="m^2/s^2, U of the robot's potential U/R exp(-gap/R)"),
    "robot_range": F("float", 0.2, min=0.0, exclusive_min=True,
                     doc="m, R of the robot's potential (the HM 1995 wall range: the robot is kept clear of)"),
    "random_force": F("float", 0.1, min=0.0, doc="m/s^2, std of a small random force per axis (0 turns it off)"),
    "stuck_time": F("float", 1.0, min=0.0, exclusive_min=True,
                    doc="s, a walker this long at under a fifth of its desired speed slides along the wall that "
                        "hides its goal, or squeezes past walls for this long when it sees its goal"),
    "max_agents": F("int", 400, min=1, doc="most persons alive at once (sources wait beyond it)"),
})

WAYPOINT = Schema({
    "position": F("point", required=True, doc="m, world frame"),
    "radius": F("float", 1.0, min=0.0, exclusive_min=True, doc="m, reached when nearer than this"),
    "wait": F("float", 0.0, min=0.0, doc="s a walker stands at the waypoint once it has reached it, before going on "
                                        "to the next stage (a group gathering)"),
})

QUEUE = Schema({
    "position": F("point", required=True, doc="m, the service point: the head of the line"),
    "direction_deg": F("float", 0.0, doc="deg, direction in which the line grows from the service point (PedSim)"),
    "spacing": F("float", 0.7, min=0.3, doc="m, distance between people in line"),
    "service_time": F("float", 5.0, min=0.0, doc="s, mean of the exponential service time at the head"),
})

ATTRACTION = Schema({
    "position": F("point", required=True, doc="m, centre of the attraction's area (a shop, a window)"),
    "size": F("point", [2.0, 2.0], doc="m, width and height of the area (PedSim width, height)"),
    "strength": F("float", 1.0, min=0.0, doc="appeal: a passer-by within reach is drawn at strength x 0.05 /s"),
    "reach": F("float", 3.0, min=0.0, doc="m, how near the area a walker must pass to be drawn"),
    "visit_time": F("float", 10.0, min=0.0, doc="s, mean of the exponential time spent there"),
}, checks=(_extent("size"),))

CLUSTER = Schema({
    "position": F("point", required=True, doc="m, centre of the area the persons start in (PedSim <agent>)"),
    "count": F("int", 1, min=1, doc="persons"),
    "spread": F("point", [0.0, 0.0], doc="m, width and height of the start area (PedSim dx, dy)"),
    "route": F("str", required=True, doc="the route they follow from the start"),
    "agent_type": F("str", "adult", doc="agent type of the persons"),
    "group_size_weights": F(ListOf(F("float", min=0.0), min_items=1), [1.0],
                            doc="relative weights of group sizes 1, 2, 3, ... the persons walk in"),
}, checks=(_extent("spread"),))

ROUTE = Schema({
    "waypoints": F(ListOf(F("str"), min_items=1), required=True,
                   doc="stages visited in order: waypoint or queue names"),
    "sink": F("bool", True, doc="persons leave the simulation at the last stage; false: they start over"),
})

SOURCE = Schema({
    "position": F("point", required=True, doc="m, centre of the emission area"),
    "size": F("point", [1.0, 1.0], doc="m, width and height of the emission area"),
    "rate": F("float", required=True, min=0.0, doc="persons/s, mean emission rate (Poisson)"),
    "start": F("float", 0.0, doc="s, first emission time on the simulation clock (which starts with the warm-up)"),
    "stop": F("float", math.inf, allow_inf=True, doc="s, last emission time"),
    "routes": F(MapOf(F("float", min=0.0)), required=True, doc="route name -> relative weight"),
    "group_size_weights": F(ListOf(F("float", min=0.0), min_items=1), [1.0],
                            doc="relative weights of group sizes 1, 2, 3, ..."),
    "agent_types": F(MapOf(F("float", min=0.0)), {"adult": 1.0}, doc="agent type name -> relative weight"),
}, checks=(_extent("size"),))

STANDING = Schema({
    "position": F("point", required=True, doc="m, centre of the standing group"),
    "count": F("int", 1, min=1, max=12, doc="persons in the group (1 for a single standing person)"),
    "spacing": F("float", 0.9, min=0.0, doc="m, distance between neighbours on the group's circle"),
    "agent_type": F("str", "adult", doc="agent type of the group's members"),
})

# The robot's local planners (pipeline/navigation/planners.py builds them; each declares its keys on its class). A
# built-in planner also gets the robot's radius, max_speed, max_angular_speed and max_acceleration.
PLANNER = slot_typed(PLANNER_SLOT)

# seed 001 Sec. 3.2: the RFID reader's coverage; the errors, detection rate and read rate are assumptions
# (sensors/tag.py declares them and says why)
TAG = schema_of(TagSensor)

# the robot's body and its drivers declare their parameters on their classes (crowdsim/robot.py and
# crowdsim/drivers.py: where each default comes from is said there); a key two drivers share is declared once, on
# their common base
ROBOT = Schema({
    **schema_of(Robot).fields,
    "driver": F("str", "route", choices=tuple(DRIVERS),
                doc="what drives the robot: route (its route, stopping for what is in front), goals (the planner to "
                    "each of `goals` in turn; the run ends at the last), follow (the planner after `follow.target`), "
                    "script (the commands of `script` in turn, again from the first with `loop`)"),
    **{name: field for driver in DRIVERS.values() for name, field in schema_of(driver).fields.items()},
})

# the sensors declare their parameters on their classes (where each default comes from is said there)
LASER = schema_of(Laser, LASER_PRESETS)

DEPTH_CAMERA_PRESETS = {
    "kinect_640": {"width": 640, "height": 480, "fovy_deg": 43.0, "range_min": 0.5, "range_max": 8.0,
                   "noise": "kinect"},
    "kinect_160": {"width": 160, "height": 120, "fovy_deg": 43.0, "range_min": 0.5, "range_max": 8.0,
                   "noise": "kinect"},
}

DEPTH_CAMERA = schema_of(DepthCamera, DEPTH_CAMERA_PRESETS)
WALL_CAMERA = schema_of(WallCamera)

# The pipeline's parts (pipeline/assemble.py builds them): each role has its built-in types, each type the
# parameters its class declares (where each default comes from is said there), by the names of its package's
# registry; `type: module.path:ClassName` names a class of your own instead.

DETECTOR_TYPES = {name: schema_of(cls) for name, cls in DETECTORS.items()}
# the `sensors` list whose frames each built-in detector reads
DETECTOR_READS = {"laser_segments": "lasers", "laser_learned": "lasers", "laser_legs": "lasers",
                  "wall_people": "wall_cameras", "rgbd_people": "depth_cameras"}

FUSION_TYPES = {name: schema_of(cls) for name, cls in FUSIONS.items()}

# the NNT (pipeline/tracking/nnt.py): its parts, each named by type with the parameters its class declares (where
# each default comes from is said there)
FLAT_NNT = {
    "process_noise": ("motion", "process_noise"), "turn_rate_noise": ("motion", "turn_rate_noise"),
    "imm_models": ("motion", "models"), "imm_transition": ("motion", "transition"),
    "gate_chi2": ("association", "gate_chi2"),
    "n_confirm": ("initiation", "n_confirm"), "initial_velocity_variance": ("initiation", "initial_velocity_variance"),
    "n_min": ("initiation", "n_min"), "v_min": ("initiation", "v_min"), "v_max": ("initiation", "v_max"),
    "position_slack": ("initiation", "position_slack"),
    "n_delete": ("deletion", "n_delete"), "n_delete_tentative": ("deletion", "tentative"),
    "n_delete_young": ("deletion", "young"), "n_delete_mature": ("deletion", "mature"),
    "mature_after": ("deletion", "mature_after"),
    "duplicate_distance": ("duplicates", "distance"), "new_track_clearance": ("duplicates", "clearance"),
}
"""The NNT's keys before its parts were named (every bundled scenario and Table II's rows use them): each key ->
(the part, its parameter there). The parts ``motion``, ``association``, ``initiation`` and ``deletion`` were named by
a string, their type."""


def _old_model(m):
    """An ``imm_models`` entry ({model, process_noise, turn_rate_noise}) as a motion model's specification."""
    if not (isinstance(m, dict) and "model" in m):
        return m
    m = {"type": m["model"], **{k: v for k, v in m.items() if k != "model"}}
    if m["type"] != "ct":  # (every entry had a turn rate noise, which only ct has)
        m.pop("turn_rate_noise", None)
    return m


def _old_key(key: str, where: str, part: str, moved: dict[str, str]) -> str:
    """An error's key in a part made from old keys, as the old key (``moved``: parameter -> old key)."""
    prefix = f"{where}{part}."
    if not key.startswith(prefix):
        return key
    rest = key[len(prefix):]
    name = rest.split(".")[0].split("[")[0]
    old = {"type": part, **moved}.get(name)
    if old is None:
        return key
    tail = rest[len(name):]
    return where + old + (tail.replace(".type", ".model") if old == "imm_models" else tail)


def _flat_nnt(value: dict, source: str, key: str) -> dict:
    """The NNT's old keys (``FLAT_NNT``) moved into its parts, so that a file written before the parts had names
    builds the same tracker. An old key goes to its part when the part's type has it, and is checked and dropped
    when it does not (n_delete under young_mature did nothing before either); the duplicate guards are on when one
    of their old keys is given (the other's old default, 0, leaves that guard off). An error names the key the file
    gave; an old key given together with its new spelling is one error."""
    old = [k for k in value if k in FLAT_NNT]
    named = [p for p in NearestNeighbourTracker.PARTS if isinstance(value.get(p), str)]
    if not (old or named):
        return value
    where = f"{key}." if key else ""
    out = {k: v for k, v in value.items() if k not in FLAT_NNT}
    for part in NearestNeighbourTracker.PARTS:
        moved = {FLAT_NNT[k][1]: k for k in old if FLAT_NNT[k][0] == part}
        given = value.get(part)
        if not (moved or isinstance(given, str)):
            continue
        typed = NNT.fields[part].kind
        if not (given is None or isinstance(given, (str, dict))):
            validate(given, typed, source, where + part)  # names what is wrong with it
        spec = dict(given) if isinstance(given, dict) else {"type": given} if isinstance(given, str) else {}
        if part == "duplicates" and given is None:
            spec = {"distance": 0.0, "clearance": 0.0}  # the old keys' defaults: off
        kind = spec.get("type", typed.default)
        elsewhere: dict[str, dict] = {}  # another type's keys: checked as that type's (v_min below v_max, say)
        for name, k in moved.items():
            home = kind if kind in typed.types and name in typed.types[kind].fields else next(
                t for t, schema in typed.types.items() if name in schema.fields)
            item = [_old_model(m) for m in value[k]] if k == "imm_models" and isinstance(value[k], list) else value[k]
            try:
                checked = validate(item, typed.types[home].fields[name], source, where + k)
            except ScenarioError as e:  # (an imm_models entry's model is a type now)
                raise ScenarioError(source, e.key.replace(".type", ".model"), e.message) from None
            if home != kind:
                elsewhere.setdefault(home, {})[name] = checked
            elif isinstance(given, dict) and name in given:
                raise ScenarioError(source, where + k, f"the old spelling of {where}{part}.{name}, which is given too; "
                                                       f"expected only {where}{part}.{name} (`{k}: !remove` drops "
                                                       "the old one where a base scenario gives it)")
            else:
                spec[name] = checked
        for home, keys in elsewhere.items():  # checked, then dropped
            _as_old({"type": home, **keys}, typed, source, where, part, moved)
        out[part] = (validate(spec, typed, source, where + part) if isinstance(given, dict)
                     else _as_old(spec, typed, source, where, part, moved))
    return out


def _as_old(spec: dict, typed: Typed, source: str, where: str, part: str, moved: dict[str, str]) -> dict:
    """``spec``, a part made from old keys, validated; an error names the old key."""
    try:
        return validate(spec, typed, source, where + part)
    except ScenarioError as e:
        raise ScenarioError(source, _old_key(e.key, where, part, moved), e.message) from None


NNT = Schema({name: slot_field(slot) for name, slot in NearestNeighbourTracker.PARTS.items()}, upgrade=_flat_nnt)

# the other trackers declare their parameters on their classes (where each default comes from is said there)
MHT = schema_of(MHTParams)
RJMCMC = schema_of(RjmcmcTracker)
RGBD_TRACKER = schema_of(RgbdTracker)

TRACKER_TYPES = {"nnt": NNT, "mht": MHT, "rjmcmc": RJMCMC, "rgbd": RGBD_TRACKER}

# seed 000 Sec. V-C's static-map filter (pipeline/map_filter.py declares its parameters)
MAP_FILTER = schema_of(MapFilter)

# the group stage (pipeline/groups: relations, detection, composition tracking; SPENCER's defaults)
GROUP_STAGE_TYPES = {name: schema_of(cls) for name, cls in GROUP_STAGES.items()}

# the methods a class of one's own must have (pipeline/assemble.py's protocols; a test keeps them equal)
DETECTOR = Typed(DETECTOR_TYPES, "laser_segments", "detector", ("detect", "reset"))
# a user's sensor: the loop schedules it by its period and hands its frames to the detector named after it
CUSTOM_SENSOR = Typed({}, None, "sensor", ("start", "due", "captured", "capture", "pose_in_odom", "shown"))
FUSION = Typed(FUSION_TYPES, "nearest", "fusion", ("fuse", "reset"))
TRACKER = Typed(TRACKER_TYPES, "nnt", "tracker", ("update", "reset"))
GROUP_STAGE = Typed(GROUP_STAGE_TYPES, "coherent_motion", "groups", ("update", "reset"))

PIPELINE = Schema({
    "detector": F(DETECTOR, doc="the detector on every laser (laser_segments: seed 000's segments and geometry)"),
    "detectors": F(MapOf(F(DETECTOR, optional=True)), {},
                   doc="sensor name -> its own detector, in place of `detector` for that sensor (null: none)"),
    "cycle": F("str", "lasers",
               doc="what starts a tracking cycle: `lasers` (any laser's scan) or a depth camera's name (each of its "
                   "frames; seed 003's tracker runs at the camera's rate)"),
    "fusion": F(FUSION, doc="merges the detections of one cycle (nearest: seed 000's detection-to-detection fusion)"),
    "fusion_distance": F("float", None, min=0.0,
                         doc="the old spelling of fusion.distance, moved there when the file is loaded"),
    "tracker": F(TRACKER, doc="the tracker (nnt: seed 000's nearest-neighbour Kalman tracker; mht: its "
                                  "multi-hypothesis baseline; rjmcmc: seed 001's particle filter over the laser and "
                                  "the wall cameras; rgbd: seed 003's RGB-D tracker)"),
    "groups": F(GROUP_STAGE, doc="social relations, groups and their tracking (coherent_motion: seed 000's SPENCER "
                                 "group stage)"),
    "map_filter": F(MAP_FILTER, optional=True,
                    doc="drop every detector's detections on the map's walls and obstacles before fusion (seed 000 "
                        "Sec. V-C); left out or null: none"),
}, legacy={"fusion_distance": "fusion.distance"})

EVALUATION = Schema({
    "threshold": F("float", 1.0, min=0.0, exclusive_min=True, doc="m, CLEAR-MOT match threshold (seed 000: 1 m)"),
    "max_range": F("float", 20.0, min=0.0, exclusive_min=True, doc="m, ground truth is every person this near"),
})

MAP = Schema({
    "walls": F(ListOf(F("points")), [], doc="polylines of wall segments, m"),
    "obstacles": F(ListOf(F("points")), [], doc="closed polygons (columns, counters), m"),
})

# A file may start with ``base: NAME_OR_PATH``: the base scenario's data, with this file's keys laid over it
# (mappings merge key by key, lists and values are replaced, a part given another type is replaced whole; ``!replace``
# and ``!remove`` say otherwise), before validation. See scenarios.loader.merge and scenarios/reader.py.
SCENARIO = Schema({
    "name": F("str", required=True, doc="the scenario's name, used in outputs"),
    "description": F("str", "", doc="what happens, in a sentence or two (its first line is listed)"),
    "seed": F("int", 0, min=0, doc="seeds every random draw: same seed, same run, bit for bit"),
    "duration": F("float", 60.0, min=0.0, exclusive_min=True, doc="s of simulated time that are recorded"),
    "warmup": F("float", 0.0, min=0.0,
                doc="s of crowd-only simulation before the robot, sensors and scoring start, so flows are under way"),
    "dt": F("float", 0.04, min=0.0, exclusive_min=True, max=0.1, doc="s, simulation step"),
    "map": F(MAP, doc="the floor plan"),
    "crowd": F(CROWD, doc="the social-force model and the agent types"),
    "waypoints": F(MapOf(F(WAYPOINT)), {}, doc="named places routes lead through"),
    "queues": F(MapOf(F(QUEUE)), {}, doc="named waiting lines routes lead through (PedSim's queues)"),
    "attractions": F(MapOf(F(ATTRACTION)), {}, doc="places passers-by stop at for a while (PedSim's shopping)"),
    "routes": F(MapOf(F(ROUTE)), {}, doc="named sequences of stages"),
    "sources": F(ListOf(F(SOURCE)), [], doc="where persons enter, at a rate, in groups"),
    "standing": F(ListOf(F(STANDING)), [], doc="single standing persons and static conversation groups"),
    "clusters": F(ListOf(F(CLUSTER)), [], doc="persons present from the start, on a route"),
    "robot": F(ROBOT, required=True, doc="the robot's start, route and limits"),
    "sensors": F(Schema({"lasers": F(ListOf(F(LASER), min_items=1), required=True, doc="2D lasers on the robot"),
                         "depth_cameras": F(ListOf(F(DEPTH_CAMERA)), [], doc="RGB-D cameras on the robot"),
                         "wall_cameras": F(ListOf(F(WALL_CAMERA)), [], doc="fixed cameras in the world"),
                         "custom": F(ListOf(F(CUSTOM_SENSOR)), optional=True,
                                     doc="sensors of your own, each a class module.path:ClassName with the methods "
                                         "of sensors/base.py's Sensor (docs/extending.md)"),
                         "tag": F(TAG, optional=True,
                                  doc="the tag reader for the follow driver (seed 001's RFID; required with driver: "
                                      "follow): the target's coarse range and bearing all round the robot")}),
                 required=True, doc="the robot's sensors"),
    "pipeline": F(PIPELINE, doc="the robot's people pipeline: detectors, fusion and tracker, by type"),
    "evaluation": F(EVALUATION, doc="how the tracks are scored"),
})


def reference() -> str:
    """Every key of the scenario format as Markdown tables: key, kind, default, allowed range, meaning."""
    sections: list[tuple[str, str, Schema | Typed]] = [("`(top level)`", "", SCENARIO)]
    lines = ["# The scenario format", "", "Generated from `scenarios/format.py` by `crowdsim scenario-keys`; "
             "`NAME` stands for a name you choose.", ""]
    typed_at: dict[int, str] = {}  # a part's keys are listed once, where they first appear
    k = 0
    while k < len(sections):
        title, path, schema = sections[k]
        k += 1
        if isinstance(schema, Typed) and id(schema) in typed_at:
            lines += [f"## {title}", "", f"The keys of `{typed_at[id(schema)]}`.", ""]
            continue
        lines += [f"## {title}", "", "| key | kind | default | range | meaning |", "|---|---|---|---|---|"]
        if isinstance(schema, Typed):  # the type row; each built-in type's parameters in a section of its own
            typed_at[id(schema)] = path
            sections[k:k] = [(f"`{path}` with `type: {name}`", path, params) for name, params in schema.types.items()]
            lines += [f"| `type` | str | {schema.default!r} | {schema.expected.removeprefix('one of ')} | "
                      f"{schema.type_field().doc} |", ""]
            continue
        for name, field in schema.fields.items():
            kind, sub = field.kind, f"{path}.{name}" if path else name
            while isinstance(kind, Field):
                kind = kind.kind
            if isinstance(kind, (Schema, Typed)):
                sections.append((f"`{sub}`", sub, kind))
                text = "mapping" if isinstance(kind, Schema) else "mapping with a `type`"
            elif isinstance(kind, (ListOf, MapOf)):
                item = kind.item.kind if isinstance(kind.item, Field) else kind.item
                suffix = "[i]" if isinstance(kind, ListOf) else ".NAME"
                if isinstance(item, (Schema, Typed)):
                    sections.append((f"`{sub + suffix}`", sub + suffix, item))
                    text = "list of mappings" if isinstance(kind, ListOf) else "mapping of names to mappings"
                else:
                    if isinstance(item, ListOf):  # the script's rows
                        item = f"lists of {item.item.kind}"
                    text = f"list of {item}" if isinstance(kind, ListOf) else f"mapping of names to {item}"
            else:
                text = str(kind)
            default = "required" if field.required else "left out" if field.optional else (
                "" if isinstance(kind, (Schema, Typed)) or field.default is None and name in (schema.legacy or {})
                else repr(field.default))
            low = "" if field.min is None else (f"> {field.min:g}" if field.exclusive_min else f">= {field.min:g}")
            high = "" if field.max is None else f"<= {field.max:g}"
            bounds = ", ".join(b for b in (low, high) if b)
            if field.choices:
                bounds = " or ".join(field.choices)
            if len(default) > 40:
                default = "see scenarios/format.py"
            lines.append(f"| `{name}` | {text} | {default} | {bounds} | {field.doc} |")
        lines.append("")
    return "\n".join(lines)
