"""The scenario format: every key, its unit, default and allowed range, in one schema.

Defaults are the seeds' and the literature's values where they give one; each says where it comes from.
"""

from __future__ import annotations

import math

from pipeline.tracking.nnt import NearestNeighbourTracker

from .costs import laser_beams
from .laser_presets import LASER_PRESETS
from .schema import Field, ListOf, MapOf, Schema, ScenarioError, Typed, slot_field, validate

F = Field
INIT_CONFIDENCE = 0.325  # the shipped robot-camera HOG model's track-start score (train-hog --camera robot prints it)


# Checks across a part's keys, run when the file is loaded (scenarios.schema.Schema.checks): each takes the part's
# validated values and returns None, or the key at fault and what was expected. They are the rules the parts'
# constructors hold, so a file that breaks one gets one error naming the key before anything is built.

def _ordered(low: str, high: str, strict: bool = False):
    def check(p: dict):
        if p[low] > p[high] or (strict and p[low] == p[high]):
            return low, f"{p[low]:g}; expected {'below' if strict else 'at most'} {high} ({p[high]:g})"
    return check


def _extent(key: str):
    def check(p: dict):
        if min(p[key]) < 0:
            return key, f"{p[key]}; expected a width and height of at least 0 m"
    return check


def _two_beams(p: dict):
    """The laser's beams as sensors/laser.py counts them (scenarios.costs.laser_beams)."""
    beams = laser_beams(p)
    if beams < 2:
        return "resolution_deg", (f"{p['resolution_deg']:g} deg over fov_deg {p['fov_deg']:g} gives {beams:.0f} beam; "
                                  "expected at least 2 beams (a finer resolution or a wider field of view)")


def _sectors(p: dict):
    if p["sectors"] % 4:
        return "sectors", f"{p['sectors']}; expected a multiple of 4 (the nearness diagram's quadrants)"


def _foreground_or_hog(p: dict):
    if not (p["foreground"] or p["hog"]):
        return "hog", "false with foreground false too; expected at least one of foreground and hog on"


def _up_direction(p: dict):
    if math.hypot(*p["up"]) < 1e-6:
        return "up", f"{p['up']}; expected a direction (a non-zero vector), e.g. [0, -1, 0]: y is down in the image"


def _outcomes_sum_to_one(p: dict):
    total = p["p_det"] + p["p_occ"] + p["p_del"]
    if abs(total - 1.0) > 1e-9:
        return "p_del", f"p_det + p_occ + p_del = {total:g}; expected 1 (seed 000 Sec. IV-C)"


def _rjmcmc_sources(p: dict):
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

ODOMETRY = Schema({
    "distance_scale_error": F("float", 0.0, min=-0.5, max=0.5,
                              doc="relative error of the distance measured (a wheel radius off by this share)"),
    "yaw_drift": F("float", 0.0, doc="rad/m, heading error per metre driven (wheels of unequal diameter)"),
    "distance_noise": F("float", 0.0, min=0.0, doc="m/sqrt(m): the distance error's variance grows by this^2 per m"),
    "yaw_noise": F("float", 0.0, min=0.0, doc="rad/sqrt(rad): heading error variance per radian turned"),
    "yaw_noise_per_distance": F("float", 0.0, min=0.0,
                                doc="rad/sqrt(m): heading error variance per metre driven"),
})

# The robot's local planners (pipeline/navigation/planners.py builds them; a test keeps these defaults equal to the
# classes'). A built-in planner also gets the robot's radius, max_speed, max_angular_speed and max_acceleration.
PLANNER_COMMON = {
    "goal_tolerance": F("float", 0.1, min=0.0,
                        doc="m, the planner stops this near its goal (well inside the follower's band; an assumption)"),
    "stop_margin": F("float", 0.05, min=0.0,
                     doc="m, every planner brakes to stop this short of the nearest laser return in its path (an "
                         "assumption)"),
}
ND_PLANNER = {
    **PLANNER_COMMON,
    "security_distance": F("float", 0.5, min=0.0, exclusive_min=True,
                           doc="m, ds: obstacles nearer the robot's edge are dangerous (Player's nd driver, avoid_dist)"),
    "sectors": F("int", 180, min=8, doc="sectors of the nearness diagram, a multiple of 4 (Minguez's SECTORES)"),
    "wide_fraction": F("float", 0.25, min=0.0, exclusive_min=True, max=1.0,
                       doc="a region wider than this share of the sectors is wide (Minguez & Montano 2004)"),
}
PLANNER_TYPES = {
    "zone": Schema({
        **ND_PLANNER,
        "zone_radius": F("float", 0.5, min=0.0, exclusive_min=True,
                         doc="m, r: the disc round each tracked person (seed 001 Fig. 11)"),
        "zone_reach": F("float", 1.5, min=0.0, exclusive_min=True,
                        doc="m, R: the sector ahead of a walking person (seed 001 Fig. 11)"),
        "zone_opening_deg": F("float", 30.0, min=0.0, exclusive_min=True, max=180.0,
                              doc="deg, omega: the sector's full opening (seed 001 Fig. 11; "
                                  "pipeline/navigation/zones.py says why full)"),
        "standing_speed": F("float", 0.25, min=0.0,
                            doc="m/s, slower tracks get the disc alone (above the tracker's speed for a person "
                                "standing still; pipeline/navigation/zones.py)"),
        "zone_rays": F("int", 360, min=8, doc="rays that read the zones as a scan (two per ND sector)"),
        "zone_security_distance": F("float", 0.2, min=0.0, exclusive_min=True,
                                    doc="m, ND's security distance for the zones (a zone is a margin already; "
                                        "pipeline/navigation/planners.py says why 0.2)"),
        "yield_time": F("float", 2.0, min=0.0,
                        doc="s, give way to a passer-by crossing the robot's course ahead within this time (0: "
                            "never; an addition to seed 001, pipeline/navigation/planners.py)"),
    }, checks=(_sectors,)),
    "nd": Schema(ND_PLANNER, checks=(_sectors,)),
    "straight": Schema({
        **PLANNER_COMMON,
        "safety_distance": F("float", 0.6, min=0.0, doc="m, stop for a laser return this near ahead (robot.safety_distance)"),
        "heading_gain": F("float", 2.0, min=0.0, doc="1/s, omega = gain x heading error (the route driver's)"),
        "drive_cone_deg": F("float", 60.0, min=0.0, max=180.0,
                            doc="deg, drive only with the goal this near the heading (the route driver's)"),
        "corridor_margin": F("float", 0.1, min=0.0, doc="m, the path checked is the robot's width plus this each side"),
    }),
    "social_force": Schema({
        **PLANNER_COMMON,
        "relaxation_time": F("float", 0.5, min=0.0, doc="s, tau (Helbing & Molnar 1995)"),
        "person_strength": F("float", 2.1, min=0.0, doc="m^2/s^2, V0 of the pedestrian potential (HM 1995)"),
        "person_range": F("float", 0.3, min=0.0, exclusive_min=True, doc="m, sigma of that potential (HM 1995)"),
        "obstacle_strength": F("float", 10.0, min=0.0, doc="m^2/s^2, U0 of the wall potential (HM 1995)"),
        "obstacle_range": F("float", 0.2, min=0.0, exclusive_min=True, doc="m, R of the wall potential (HM 1995)"),
        "fov_deg": F("float", 200.0, min=0.0, max=360.0, doc="deg, 2 phi, the field of view (HM 1995)"),
        "out_of_view_weight": F("float", 0.5, min=0.0, max=1.0, doc="c, weight of what is out of view (HM 1995)"),
        "obstacle_sectors": F("int", 36, min=1, doc="laser returns count once per sector (an assumption)"),
        "person_radius": F("float", 0.4, min=0.0,
                           doc="m, laser returns this near a track are that person's (body 0.25 m plus track "
                               "error; an assumption)"),
    }),
}
# a class of one's own: made as Class(**keys), with command(stamp, pose, velocity, obstacles, tracks, goal) and reset()
PLANNER = Typed(PLANNER_TYPES, "zone", "planner", ("command", "reset"))

FOLLOW_TARGET = Schema({
    "start": F("point", required=True, doc="m, world: where the target appears when recording starts (after the warm-up)"),
    "route": F("str", required=True, doc="the route (a name under `routes`) the target walks; with sink: false, round "
                                          "and round"),
    "speed": F("float", required=True, min=0.0, exclusive_min=True,
               doc="m/s, the target's desired speed; below robot.max_speed, or the robot could not keep up"),
    "agent_type": F("str", "adult", doc="the target's agent type (its size)"),
})

FOLLOW = Schema({
    "band": F("point", [1.0, 2.0], doc="m, [near, far]: the robot keeps the target's centre this far away "
                                       "(pipeline/navigation/follow.py)"),
    "target": F(FOLLOW_TARGET, optional=True, doc="the person the robot follows, who wears the tag (required)"),
})

# seed 001 Sec. 3.2: the RFID reader's coverage; the errors, detection rate and read rate are assumptions
# (sensors/tag.py says why); a test keeps these equal to sensors.tag.TAG_DEFAULTS
TAG = Schema({
    "rate": F("float", 5.0, min=0.0, exclusive_min=True, doc="Hz, readings per second (an assumption)"),
    "range_min": F("float", 0.5, min=0.0, doc="m, nearest tag read (seed 001 Sec. 3.2)"),
    "range_max": F("float", 4.5, min=0.0, exclusive_min=True, doc="m, farthest tag read (seed 001 Sec. 3.2)"),
    "range_sd": F("float", 0.5, min=0.0, doc="m, range error sd (an assumption: coarse)"),
    "bearing_sd_deg": F("float", 20.0, min=0.0, doc="deg, bearing error sd (an assumption: one antenna lobe)"),
    "detection_probability": F("float", 0.9, min=0.0, max=1.0, doc="chance a due reading is had (an assumption)"),
}, checks=(_ordered("range_min", "range_max", strict=True),))

ROBOT = Schema({
    "start": F("pose", required=True, doc="m, m, rad: initial pose in the world frame"),
    "route": F("points", None, doc="m, waypoints the robot drives through"),
    "loop": F("bool", True, doc="drive the route again after the last waypoint"),
    "radius": F("float", 0.425, min=0.0, exclusive_min=True, doc="m, footprint radius (SPENCER platform ~0.85 m wide)"),
    "max_speed": F("float", 0.6, min=0.0, doc="m/s"),
    "max_angular_speed": F("float", 1.0, min=0.0, doc="rad/s"),
    "max_acceleration": F("float", 0.5, min=0.0, exclusive_min=True, doc="m/s^2 (an assumption for a ~1.5 m platform)"),
    "max_angular_acceleration": F("float", 1.5, min=0.0, exclusive_min=True, doc="rad/s^2 (an assumption)"),
    "safety_distance": F("float", 0.6, min=0.0, doc="m, stop when a laser return is this close in front"),
    "odometry": F(ODOMETRY, doc="wheel odometry's systematic and random errors (all 0: perfect odometry)"),
    "driver": F("str", "route", choices=("route", "goals", "follow", "script"),
                doc="what drives the robot: route (its route, stopping for what is in front), goals (the planner to "
                    "each of `goals` in turn; the run ends at the last), follow (the planner after `follow.target`), "
                    "script (the commands of `script` in turn, again from the first with `loop`)"),
    "script": F(ListOf(F(ListOf(F("float"), min_items=3)), min_items=1), None,
                doc="s, m/s, rad/s: [duration, v, omega] rows the script driver holds in turn (seed 003's KTP: the "
                    "robot still, translating, rotating or driving an arc), within the speed and acceleration "
                    "limits; after the last, 0 unless `loop`"),
    "goals": F(ListOf(F("point"), min_items=1), None, doc="m, world: the goals the goals driver visits in order"),
    "goal_radius": F("float", 0.3, min=0.0, exclusive_min=True,
                     doc="m, a goal is reached with the robot's centre this near (CrowdNav: the robot radius, 0.3 m)"),
    "planner": F(PLANNER, doc="the local planner of the goals and follow drivers (zone: seed 001 Sec. 7); a built-in "
                              "type gets the robot's radius, speed limits and max_acceleration besides its keys, a "
                              "class of your own is made as Class(**keys) and needs command(stamp, pose, velocity, "
                              "obstacles, tracks, goal) -> (v, omega) and reset() (pipeline/navigation/planners.py)"),
    "follow": F(FOLLOW, optional=True, doc="the follow driver's target and band (required with driver: follow)"),
})

NOISE_BAND = Schema({
    "up_to": F("float", required=True, min=0.0, exclusive_min=True, doc="m, the band covers ranges up to this"),
    "systematic": F("float", 0.0, min=0.0,
                    doc="m, +- bound of the laser's offset (drawn uniformly once per laser, the same on every beam)"),
    "statistical": F("float", 0.0, min=0.0, doc="m, 1-sigma Gaussian noise drawn anew for every return"),
})

LASER = Schema({
    "name": F("str", required=True, doc="the laser's frame name"),
    "preset": F("str", None, choices=tuple(LASER_PRESETS),
                doc="a datasheet model whose values fill the keys not given (scenarios/laser_presets.py)"),
    "mount": F("pose", required=True, doc="m, m, rad: pose in base_link"),
    "height": F("float", 0.70, min=0.0, doc="m above the floor (seed 000: two lasers at 70 cm)"),
    "fov_deg": F("float", 190.0, min=0.0, exclusive_min=True, max=360.0, doc="deg (SICK LMS500)"),
    "resolution_deg": F("float", 0.5, min=0.0, exclusive_min=True, doc="deg between beams (SICK LMS500)"),
    "range_min": F("float", 0.0, min=0.0, doc="m, nearer returns are no-returns"),
    "range_max": F("float", 20.0, min=0.0, exclusive_min=True, doc="m (seed 000: detections up to 20 m)"),
    "rate": F("float", 25.0, min=0.0, exclusive_min=True,
              doc="Hz (SICK LMS500: 25 or 50 Hz), at most the simulation's steps per second (1 / dt)"),
    "noise": F(ListOf(F(NOISE_BAND)), LASER_PRESETS["sick_lms500"]["noise"],
               doc="range error bands, nearest first; beyond the last, the last applies (SICK LMS5xx HR)"),
    "no_return": F("str", "nan", choices=("nan", "range_max"),
                   doc="what a beam without a return reads: NaN, or range_max as many drivers report"),
}, presets=LASER_PRESETS, checks=(_two_beams,))

# Kinect-like RGB-D cameras (Microsoft Kinect / Asus Xtion: 640 x 480 at up to 30 Hz, 43 degrees vertical field of
# view, about 0.5-8 m; Khoshelham & Elberink 2012); the 160 x 120 variant is the same camera at a quarter resolution.
# The rate is the scenario's to choose (15 Hz unless given): 30 Hz would need a simulation step of 1/30 s or less
DEPTH_CAMERA_PRESETS = {
    "kinect_640": {"width": 640, "height": 480, "fovy_deg": 43.0, "range_min": 0.5, "range_max": 8.0,
                   "noise": "kinect"},
    "kinect_160": {"width": 160, "height": 120, "fovy_deg": 43.0, "range_min": 0.5, "range_max": 8.0,
                   "noise": "kinect"},
}

DEPTH_CAMERA = Schema({
    "name": F("str", required=True, doc="the camera's optical frame name"),
    "preset": F("str", None, choices=tuple(DEPTH_CAMERA_PRESETS),
                doc="a camera model whose values fill the keys not given"),
    "position": F("point3", [0.45, 0.0, 1.45],
                  doc="m, in base_link (SPENCER: RGB-D cameras at head height, front and rear)"),
    "yaw": F("float", 0.0, doc="rad, viewing direction in base_link (pi: looking backwards)"),
    "pitch": F("float", 0.0, min=-1.57, max=1.57, doc="rad, tilt down (positive) or up"),
    "width": F("int", 160, min=8, max=4096, doc="pixels"),
    "height": F("int", 120, min=8, max=4096, doc="pixels"),
    "fovy_deg": F("float", 43.0, min=1.0, max=170.0, doc="deg, vertical field of view (Kinect: 43)"),
    "range_min": F("float", 0.5, min=0.0, doc="m, nearer depths read NaN (Kinect: 0.5)"),
    "range_max": F("float", 8.0, min=0.0, exclusive_min=True, doc="m, farther depths read NaN (Kinect: ~8)"),
    "rate": F("float", 15.0, min=0.0, exclusive_min=True, doc="Hz, at most 1 / dt"),
    "noise": F("str", "kinect", choices=("kinect", "none"),
               doc="kinect: Gaussian depth noise, then depth quantized through the disparity (the keys below)"),
    "noise_sigma": F("float", 1.425e-3, min=0.0,
                     doc="1/m, the noise's sigma per z^2 (Khoshelham & Elberink 2012: 1.425e-3)"),
    "ir_focal_px": F("float", 580.0, min=0.0, exclusive_min=True,
                     doc="px, focal length of the IR camera the disparity is measured in (Kinect: 580)"),
    "ir_baseline": F("float", 0.075, min=0.0, exclusive_min=True,
                     doc="m, IR projector to IR camera (Kinect: 0.075)"),
    "disparity_subpixel": F("int", 8, min=1, doc="disparity steps per pixel (Kinect: 8, a 1/8-pixel step)"),
    "rgb": F("bool", False, doc="render a colour image too (a second pass)"),
}, presets=DEPTH_CAMERA_PRESETS)

WALL_CAMERA = Schema({
    "name": F("str", required=True, doc="the camera's frame name"),
    "position": F("point3", required=True, doc="m, in the world"),
    "yaw": F("float", 0.0, doc="rad, viewing direction in the world"),
    "pitch": F("float", 0.5, min=-1.57, max=1.57, doc="rad, tilt down (positive)"),
    "width": F("int", 320, min=8, max=4096, doc="pixels (seed 001: flea2 cameras, up to 640 x 480)"),
    "height": F("int", 240, min=8, max=4096, doc="pixels"),
    "fovy_deg": F("float", 45.0, min=1.0, max=170.0, doc="deg, vertical field of view"),
    "rate": F("float", 10.0, min=0.0, exclusive_min=True, doc="Hz, at most 1 / dt"),
    "rgb": F("bool", True, doc="render a colour image (the segmentation and boxes come without it)"),
})

# The pipeline's parts (pipeline/assemble.py builds them): each role has its built-in types, each type its own
# parameters; `type: module.path:ClassName` names a class of your own instead. The names are assemble's (a test
# keeps the two registries equal, and each type's defaults equal to its class's).

SEGMENT_DETECTOR = Schema({
    "jump_distance": F("float", 0.4, min=0.0, exclusive_min=True, doc="m, seed 000 Sec. 4.2: 0.4 m"),
    "min_points": F("int", 3, min=1, doc="seed 000 Sec. IV-C: far echoes of fewer than 3 points are unreliable"),
    "min_width": F("float", 0.1, min=0.0, doc="m, narrowest segment taken for a person"),
    "max_width": F("float", 0.9, min=0.0, doc="m, widest segment taken for a person"),
    "min_bulge": F("float", 0.03, min=0.0,
                   doc="m, least mean depth of the interior points behind the chord (walls are flat)"),
    "position_variance": F("float", 0.1, min=0.0, exclusive_min=True,
                           doc="m^2, seed 000 Sec. IV-C: fixed R = diag(0.1, 0.1)"),
})

LEARNED_DETECTOR = Schema({
    "model": F("str", "forest",
               doc="adaboost (Arras et al. 2007's boosted stumps, seed 000 Sec. II-A), forest (15 trees of depth 10, "
                   "seed 000 Sec. III-A: best there), or the path of a .json/.npz model `crowdsim experiment "
                   "train-detector --out` wrote"),
    "threshold": F("float", None, min=0.0, max=1.0, optional=True,
                   doc="least person probability detected; left out: the model's own (peak F1 on validation seeds)"),
    "jump_distance": F("float", 0.4, min=0.0, exclusive_min=True, doc="m, seed 000 Sec. 4.2: 0.4 m"),
    "min_points": F("int", 3, min=1, doc="seed 000 Sec. IV-C: far echoes of fewer than 3 points are unreliable"),
    "position_variance": F("float", 0.1, min=0.0, exclusive_min=True,
                           doc="m^2, seed 000 Sec. IV-C: fixed R = diag(0.1, 0.1)"),
})

# seed 001 Sec. 4.1 gives the steps and Xavier et al. 2005's properties but no threshold: ours are chosen on this
# testbed's legs (pipeline/detectors/legs.py says how)
LEG_DETECTOR = Schema({
    "jump_distance": F("float", 0.08, min=0.0, exclusive_min=True, doc="m, consecutive returns farther apart start a "
                                                                      "new blob"),
    "min_points": F("int", 3, min=3, doc="returns of a leg (an inscribed angle needs an interior one)"),
    "min_width": F("float", 0.05, min=0.0, exclusive_min=True, doc="m, narrowest leg (first to last return)"),
    "max_width": F("float", 0.15, min=0.0, exclusive_min=True, doc="m, widest leg"),
    "min_angle_deg": F("float", 90.0, min=0.0, max=180.0, doc="deg, least mean inscribed angle (a half circle's)"),
    "max_angle_deg": F("float", 160.0, min=0.0, max=180.0, doc="deg, largest mean inscribed angle (flatter is a wall)"),
    "max_angle_sd_deg": F("float", 30.0, min=0.0, doc="deg, largest spread of the inscribed angles (a circle's: 0)"),
    "sharp_angle_deg": F("float", 60.0, min=0.0, max=180.0,
                         doc="deg, a blob with a sharper inscribed angle is a sharp structure, no leg"),
    "pair_distance": F("float", 0.5, min=0.0, doc="m, farthest two legs of one person"),
    "single_legs": F("bool", True, doc="a leg without a partner is a person too (the other hidden behind it)"),
    "blobs": F("bool", False, doc="also give the raw blobs: the named batches `legs` and `blobs` (seed 001's l_b, "
                                  "which the rjmcmc tracker's likelihood weighs)"),
    "blob_min_radius": F("float", 0.03, min=0.0, doc="m, least half-width of a raw blob (thinner: a table leg)"),
    "blob_max_radius": F("float", 0.3, min=0.0, doc="m, largest half-width of a raw blob (wider: a wall)"),
    "position_variance": F("float", 0.05, min=0.0, exclusive_min=True, doc="m^2, of each person's position"),
}, checks=(_ordered("min_width", "max_width"), _ordered("min_angle_deg", "max_angle_deg")))

# seed 001 Sec. 4.2-4.3 names the methods (Sigma-Delta, morphology, an aspect ratio; HOG) but gives no parameter
WALL_CAMERA_DETECTOR = Schema({
    "foreground": F("bool", True, doc="Sigma-Delta foreground blobs (the batch `fseg`)"),
    "hog": F("bool", True, doc="HOG person windows (the batch `hog`)"),
    "model": F("str", None, optional=True,
               doc="the HOG model: left out, the shipped one (`crowdsim experiment train-hog`); or the path of the "
                   ".npz it wrote with --out"),
    "hog_scales": F(ListOf(F("float", min=0.1), min_items=1), [float(1.2 ** k) for k in range(8)],
                    doc="window scales searched (1: 64 x 128 pixels); the default covers a person 2.2-8 m from a "
                        "640 x 480 camera at 45 degrees"),
    "bootstrap": F("int", 15, min=1, doc="frames whose median starts the background model (no detection before)"),
    "min_area": F("int", 150, min=1, doc="pixels, least foreground blob"),
    "min_aspect": F("float", 1.2, min=0.0, doc="least height / width of a foreground blob"),
    "max_aspect": F("float", 5.0, min=0.0, doc="largest height / width of a foreground blob"),
    "robot_radius": F("float", 0.5, min=0.0,
                      doc="m, a detection whose floor point is this near the robot is the robot, masked out (Rackham's "
                          "0.26 m and a margin for the foot point's error)"),
    "position_variance": F("float", 0.09, min=0.0, exclusive_min=True,
                           doc="m^2 along the floor (seed 001 Table 1: Sigma = diag(0.09, 0.09))"),
}, checks=(_foreground_or_hog,))

# seed 003's RGB-D detector (Munaro & Menegatti Sec. 3); the paper gives the head distance and voxels under 0.1 m
# (Table 7), the rest are its authors' released code's (PCL's ground-based people detection), see
# pipeline/detectors/head_clusters.py
RGBD_DETECTOR = Schema({
    "voxel": F("float", 0.06, min=0.0, exclusive_min=True, max=0.1,
               doc="m, the voxel grid's leaf (Table 7: below 0.1; PCL's 0.06)"),
    "cluster_tolerance": F("float", 0.15, min=0.0, exclusive_min=True,
                           doc="m, largest gap between neighbours of a Euclidean cluster (PCL: two voxels, 0.12 m; "
                               "our bodies' torso ends in a flat top 12 cm wider than the neck all round, and from "
                               "below a camera sees a gap there: at 0.12 m a person 2-3 m away loses their head)"),
    "head_distance": F("float", 0.3, min=0.0, exclusive_min=True,
                       doc="m, least distance between two people's heads when a cluster is split (Table 7)"),
    "up": F("point3", [0.0, -1.0, 0.0], doc="the floor's up direction in the camera's optical frame, roughly (y is "
                                            "down): the first ground plane is searched near it"),
    "max_tilt_deg": F("float", 30.0, min=0.0, max=90.0, doc="deg, the first ground plane's largest tilt from `up`"),
    "sub_clustering": F("bool", True, doc="split clusters at their heads (seed 003 Sec. 3.1.1; false: Table 2's "
                                          "\"No sub.\" row)"),
    "hog": F("bool", True, doc="score each candidate's box with the HOG classifier and keep those above threshold"),
    "model": F("str", None, optional=True,
               doc="the HOG model: left out, the shipped one (`crowdsim experiment train-hog --camera robot`); or the "
                   "path of the .npz it wrote with --out"),
    "threshold": F("float", None, optional=True,
                   doc="least HOG score of a detection; left out: the model's (the score 97% of its validation "
                       "people pass, as seed 003 keeps it low: Sec. 4.1.2)"),
    "colour_space": F("str", "rgb", choices=("rgb", "hsv"),
                      doc="the detections' colour histograms (Tables 2-5: RGB; Table 7 recommends HSV); the tracker's "
                          "colour_space must be the same"),
    "position_variance": F("float", 0.036, min=0.0, exclusive_min=True,
                           doc="m^2 along the floor (the authors' later tracker: 30 (2 voxel)^2 / 12 at 0.06 m)"),
}, checks=(_up_direction,))

DETECTOR_TYPES = {"laser_segments": SEGMENT_DETECTOR, "laser_learned": LEARNED_DETECTOR, "laser_legs": LEG_DETECTOR,
                  "wall_people": WALL_CAMERA_DETECTOR, "rgbd_people": RGBD_DETECTOR}
# the `sensors` list whose frames each built-in detector reads
DETECTOR_READS = {"laser_segments": "lasers", "laser_learned": "lasers", "laser_legs": "lasers",
                  "wall_people": "wall_cameras", "rgbd_people": "depth_cameras"}

NEAREST_FUSION = Schema({
    "distance": F("float", 0.4, min=0.0, doc="m, detections of two sensors nearer than this are one person"),
})

FUSION_TYPES = {"nearest": NEAREST_FUSION}

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

MHT = Schema({
    "process_noise": F("float", 0.267, min=0.0, exclusive_min=True,
                       doc="m^2/s^3, q_L of the CV model: the NNT's (seed 000 Sec. IV-C)"),
    "gate_chi2": F("float", 13.82, min=0.0, exclusive_min=True, doc="Mahalanobis gate (chi2 0.999 for 2 dof)"),
    "p_det": F("float", 0.7, min=0.0, exclusive_min=True, max=1.0,
               doc="probability a track is detected in a cycle (seed 000 Sec. IV-C)"),
    "p_occ": F("float", 0.27, min=0.0, exclusive_min=True, max=1.0,
               doc="probability a track is occluded in a cycle (seed 000 Sec. IV-C)"),
    "p_del": F("float", 0.03, min=0.0, exclusive_min=True, max=1.0,
               doc="probability a track is deleted in a cycle (seed 000 Sec. IV-C); p_det + p_occ + p_del = 1"),
    "lambda_new": F("float", 0.005, min=0.0, exclusive_min=True,
                    doc="1/(m^2 cycle), Poisson rate of new tracks (seed 000 Sec. IV-C)"),
    "lambda_fal": F("float", 0.005, min=0.0, exclusive_min=True,
                    doc="1/(m^2 cycle), Poisson rate of false alarms (seed 000 Sec. IV-C)"),
    "n_scan": F("int", 30, min=1, doc="cycles of n-scanback pruning (seed 000 Sec. IV-C: 30)"),
    "n_delete": F("int", 10, min=1, doc="cycles without a detection that delete a track (seed 000 Sec. IV-C: 10)"),
    "max_hypotheses": F("int", 50, min=1,
                        doc="hypotheses generated per cycle, in place of seed 000's t_max = 0.03 s so results do "
                            "not depend on the machine (about 0.03 s with 80 people; pipeline/tracking/mht.py)"),
    "n_confirm": F("int", 3, min=1, doc="detections before a track is output (the NNT's)"),
    "initial_velocity_variance": F("float", 1.0, min=0.0, exclusive_min=True, doc="m^2/s^2 of a new track"),
}, checks=(_outcomes_sum_to_one,))

# seed 001's RJMCMC particle filter (pipeline/tracking/rjmcmc.py; its Table 1 unless said; a test keeps these
# defaults equal to the class's)
RJMCMC = Schema({
    "weights": F(MapOf(F("float", min=0.0)),
                 {"laser/legs": 0.16, "laser/blobs": 0.16, "camera_1/fseg": 0.22, "camera_1/hog": 0.2,
                  "camera_2/fseg": 0.22, "camera_2/hog": 0.2},
                 doc="k_d per detection source (`sensor/batch`, as the detectors name their batches; Table 1)"),
    "proposal_sources": F(ListOf(F("str")), ["laser/legs", "camera_1/fseg", "camera_1/hog", "camera_2/fseg",
                                             "camera_2/hog"],
                          doc="the sources where targets are born (Eq. 2: the leg detector's persons and the "
                              "cameras')"),
    "likelihood_sources": F(ListOf(F("str")), ["laser/blobs", "camera_1/fseg", "camera_1/hog", "camera_2/fseg",
                                               "camera_2/hog"],
                            doc="the sources the likelihood weighs (Eq. 5: the laser's raw blobs l_b and the "
                                "cameras')"),
    "move_probabilities": F(ListOf(F("float", min=0.0, max=1.0), min_items=4), [0.15, 0.8, 0.02, 0.03],
                            doc="q_m of add, update, remove, swap (Table 1)"),
    "step_variance": F("float", 0.09, min=0.0, exclusive_min=True,
                       doc="m^2, Sigma of the random walk and of every Gaussian kernel (Table 1)"),
    "interaction_sd": F("float", 0.75, min=0.0, exclusive_min=True, doc="m, sigma of the MRF (Eq. 4, Table 1)"),
    "samples": F("int", 150, min=1, doc="N, particles kept per cycle (Table 1)"),
    "burn_in": F("int", 40, min=0, doc="N_B, burn-in steps per cycle (Table 1)"),
    "likelihood": F("str", "pooled", choices=("pooled", "mean"),
                    doc="pooled: each source's detections a Poisson process of clutter and of the targets, the sources "
                        "pooled with the weights k_d, each target with a prior (ours); mean: Eq. 5 as written"),
    "p_detect": F("float", 0.7, min=0.0, exclusive_min=True, max=1.0,
                  doc="pooled: chance that a source sees a person in its view"),
    "clutter": F(MapOf(F("float", min=0.0, exclusive_min=True)),
                 {"laser/blobs": 0.08, "camera_1/fseg": 0.003, "camera_1/hog": 0.006, "camera_2/fseg": 0.003,
                  "camera_2/hog": 0.006},
                 doc="pooled: false detections per m^2 and cycle of each likelihood source (measured on training "
                     "sequences of seed 001's room)"),
    "looks": F("float", 2.0, min=0.0, exclusive_min=True,
               doc="pooled: the independent sources whose evidence the weights k_d (summing to 1) share out"),
    "newcomer": F("float", 0.0003, min=0.0, exclusive_min=True,
                  doc="pooled: prior odds of a person not tracked before, per kernel area (2 pi Sigma = 0.57 m^2)"),
    "survival": F("float", 0.6, min=0.0, exclusive_min=True, max=0.999,
                  doc="pooled: chance that a tracked person is still there a cycle later"),
    "birth_floor": F("float", 0.01, min=0.0, exclusive_min=True,
                     doc="least birth density (kernel units): where no detection is, a target can still be removed"),
    "colour_lambda": F("float", 20.0, min=0.0, doc="lambda of exp(-lambda B^2) (Perez et al. 2002; seed 001: none)"),
    "alpha": F("float", 0.9, min=0.0, max=1.0, doc="colour model update weight (Eq. 6, Table 1)"),
    "update_threshold": F("float", 0.24, min=0.0, max=1.0, doc="beta_t: the model follows only closer histograms"),
    "reid_threshold": F("float", 0.1, min=0.0, max=1.0, doc="beta_o: a new id this close to a gone person's model "
                                                             "takes their id"),
    "seed": F("int", 0, doc="the filter's random stream (one run = one draw; seed 001 reports eight)"),
}, checks=(_rjmcmc_sources, _move_probabilities))

# seed 003's tracker (pipeline/tracking/rgbd_tracker.py): Table 7 where it gives a value, else the authors' later
# OpenPTrack's (tracker.yaml) and their AdaBoost demo's; a test keeps these defaults equal to the class's
RGBD_TRACKER = Schema({
    "frame": F("str", "odom", doc="the tracks' frame (the detections')"),
    "motion_weight": F("float", 0.5, min=0.0, doc="gamma of the Mahalanobis distance in the joint cost (Table 7)"),
    "appearance_weight": F("float", 30.0, min=0.0,
                           doc="alpha of the colour classifier's confidence (Table 7: 30-100; 0: no colour term)"),
    "detector_weight": F("float", 1.0, min=0.0, doc="beta of the HOG score (Table 7)"),
    "acceleration_variance": F("float", 100.0, min=0.0, exclusive_min=True,
                               doc="m^2/s^4, white acceleration of the constant-velocity model (OpenPTrack)"),
    "initial_velocity_variance": F("float", 100.0, min=0.0, exclusive_min=True,
                                   doc="m^2/s^2, a new track's velocity variance (OpenPTrack)"),
    "use_velocity": F("bool", True, doc="the Mahalanobis distance over position and velocity (false: position only, "
                                        "seed 003's RGB-D People test)"),
    "velocity_lag": F("float", 1.0, min=0.0, exclusive_min=True,
                      doc="s, a detection's velocity is measured from the track's position 1-2 lags back (OpenPTrack)"),
    "gate_probability": F("float", 0.999, min=0.0, exclusive_min=True, max=0.999999,
                          doc="chi-square gate on the Mahalanobis distance (OpenPTrack)"),
    "init_confidence": F("float", INIT_CONFIDENCE, doc="least HOG score of a detection that starts or validates a "
                                                       "track: the shipped robot-camera model's, passed by 90% of its "
                                                       "validation people (Table 7's [-1, -0.5] on the paper's scale)"),
    "confirm": F("int", 3, min=1, doc="detections at init_confidence that confirm a new track (OpenPTrack)"),
    "confirm_time": F("float", 2.4, min=0.0, doc="s, an unconfirmed track is dropped after this (OpenPTrack)"),
    "max_missed_time": F("float", 8.0, min=0.0, doc="s without a detection before a track is deleted (OpenPTrack)"),
    "report_time": F("float", 0.1, min=0.0,
                     doc="s since its latest detection that a track is still reported (kept, unreported, to "
                         "max_missed_time for a person who comes back; chosen on training seed 100 of the KTP "
                         "room: 0 s, 0.1, 0.2, 0.5 gave MOTA 96.2, 94.8, 93.5, 88.6% with 59, 10, 7, 9 ID switches)"),
    "clearance": F("float", 0.3, min=0.0,
                   doc="m: no track starts this near a track that took a detection in the cycle (Table 7: heads "
                       "are at least 0.3 m apart)"),
    "learn": F("bool", True, doc="the colour classifiers keep learning (false: frozen after their first cycle, "
                                 "seed 003's ablation)"),
    "learn_interval": F("float", 1.0, min=0.0,
                        doc="s between a track's learning cycles, one track a cycle (0: every track every cycle; an "
                            "update costs about 0.5 ms here)"),
    "random_windows": F("int", 10, min=0, doc="random image windows learnt as negatives (the authors' demo)"),
    "colour_space": F("str", "rgb", choices=("rgb", "hsv"), doc="of the histograms; the detector's must be the same"),
    "bins": F("int", 16, min=2, doc="histogram bins a channel (seed 003 Sec. 3.2.1)"),
    "pool": F("int", 250, min=1, doc="weak classifiers (Table 7)"),
    "selectors": F("int", 50, min=1, doc="selectors of the strong classifier (Table 7)"),
    "seed": F("int", 0, doc="the classifiers' and windows' random stream"),
})

TRACKER_TYPES = {"nnt": NNT, "mht": MHT, "rjmcmc": RJMCMC, "rgbd": RGBD_TRACKER}

# seed 000 Sec. V-C's static-map filter (pipeline/map_filter.py; a test keeps these defaults equal to the class's)
MAP_FILTER = Schema({
    "resolution": F("float", 0.05, min=0.0, exclusive_min=True,
                    doc="m, cell size of the occupancy grid made from the map (a common ROS map's; an assumption)"),
    "inflation": F("float", 0.15, min=0.0,
                   doc="m, radius of the circle checked round each detection (seed 000: 15 cm)"),
    "max_occupied": F("float", 0.1, min=0.0, max=1.0,
                      doc="share of the circle's cells that may be occupied (seed 000: rejected when under 90% free; "
                          "0: any occupied cell rejects)"),
    "obstacles": F("bool", True, doc="the map's obstacles block detections as its walls do (false: walls only, for a "
                                     "map that leaves out furniture, which moves)"),
})

# the group stage (pipeline/groups: relations, detection, composition tracking; SPENCER's defaults, a test keeps
# them equal to the class's)
COHERENT_MOTION = Schema({
    "model": F("str", "spencer",
               doc="relation classifier: spencer (SPENCER's released linear SVM, groups_probabilistic_small.model), "
                   "svm (ours: linear SVM on cubic monomials + Platt) or forest (ours: random forest), both trained "
                   "on airport tracker output by `crowdsim experiment train-relations`, or the path of a model it "
                   "wrote"),
    "threshold": F("float", 0.5, min=0.0, max=1.0,
                   doc="least relation strength that joins two tracks (SPENCER's tracked_groups.py: 0.5)"),
    "linkage": F("str", "single", choices=("single", "complete", "average"),
                 doc="single: groups are the connected components (SPENCER's); complete/average: each component "
                     "clustered again so a queue of strangers does not chain (pipeline/groups/detection.py)"),
    "smoothing": F("bool", False, doc="SPENCER's long-term relations: strengths rise and fall at limited rates"),
    "max_distance": F("float", 3.0, min=0.0, doc="m, farther pairs get strength 0.1 (SPENCER's gate)"),
    "max_speed_difference": F("float", 1.0, min=0.0, doc="m/s, pairs with speeds further apart get 0.1"),
    "max_heading_difference": F("float", 0.7853981633974483, min=0.0,
                                doc="rad, pairs with headings further apart get 0.1 (SPENCER's: pi/4)"),
    "min_speed": F("float", 0.1, min=0.0, doc="m/s, a slower track's heading is taken as 0 (SPENCER's)"),
    "memory": F("int", 300, min=1, doc="member sets the composition tracker remembers (SPENCER's: 300)"),
})

GROUP_STAGE_TYPES = {"coherent_motion": COHERENT_MOTION}

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
