"""What a scenario costs, checked before it runs (scenarios/costs.py): each limit refused naming its key and passed
with allow_large, the validity limits refused even then, the figures counted as the parts count them, every bundled
scenario and PedSim file within the limits; and the crowd and the scenes sized by the persons present, not by
crowd.max_agents."""

import copy
import math
import types
import warnings
from pathlib import Path

import numpy as np
import pytest

from crowdsim.crowd import contacts
from crowdsim.crowd.contacts import ContactSolver
from pipeline.map_filter import MapFilter
from scenarios import ScenarioError, bundled_scenarios
from scenarios import costs
from scenarios.costs import check_costs, grid_shape, laser_beams, scenario_costs
from scenarios.format import SCENARIO
from scenarios.loader import read_raw, resolve
from scenarios.pedsim import PedsimWarning, pedsim_to_scenario
from scenarios.schema import validate
from sensors.laser import Laser
from sensors.scene import Scene

PEDSIM = sorted((Path(__file__).parent / "data" / "pedsim").rglob("*.xml"))
RAW = {name: read_raw(resolve(name))
       for name in ("passers_by", "seed001_room_1", "airport_disembarkation", "ktp_group")}


def merged(base, changes):
    """``changes`` laid over ``base``: mappings key by key, anything else replaced."""
    if not (isinstance(base, dict) and isinstance(changes, dict)):
        return changes
    return {**base, **{k: merged(base[k], v) if k in base else v for k, v in changes.items()}}


def scenario(base: str, **changes) -> dict:
    """The bundled scenario ``base`` with ``changes`` laid over it, validated by the schema (as the loader does
    before anything else; the cost check is what is tested here)."""
    return validate(merged(copy.deepcopy(RAW[base]), changes), SCENARIO, f"{base}_changed.yaml")


def refused(sc: dict, key: str, *words: str, large_passes: bool = True) -> str:
    """The one ScenarioError check_costs raises names the file and ``key`` and says ``words``; with allow_large
    it passes (a cost limit) or is refused the same (a validity limit)."""
    with pytest.raises(ScenarioError) as info:
        check_costs(sc, "my.yaml")
    e = info.value
    assert (e.source, e.key) == ("my.yaml", key), str(e)
    for word in words:
        assert word in e.message, (word, e.message)
    if large_passes:
        assert "--allow-large runs it on purpose" in e.message
        check_costs(sc, "my.yaml", allow_large=True)
    else:
        assert "--allow-large does not pass it" in e.message
        with pytest.raises(ScenarioError) as again:
            check_costs(sc, "my.yaml", allow_large=True)
        assert again.value.key == key
    return e.message


# -- every bundled scenario and PedSim file passes ---------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(bundled_scenarios()))
def test_every_bundled_scenario_is_within_the_limits(name):
    sc = validate(read_raw(resolve(name)), SCENARIO, name)
    check_costs(sc, name)
    c = scenario_costs(sc)
    # with margin: a tenth of each limit at most, a hundredth of most
    assert c["steps"] <= costs.MAX_STEPS / 100
    assert max(c["beams_per_scan"]) <= costs.MAX_BEAMS_PER_SCAN / 100
    assert c["beams_per_second"] <= costs.MAX_BEAMS_PER_SECOND / 10
    assert c["pixels_per_second"] <= costs.MAX_PIXELS_PER_SECOND / 10
    assert c["grid_cells"] <= costs.MAX_GRID_CELLS / 10
    assert c["max_agents"] <= costs.MAX_AGENTS / 10


@pytest.mark.filterwarnings("ignore::scenarios.pedsim.PedsimWarning")
@pytest.mark.parametrize("path", PEDSIM, ids=[p.name for p in PEDSIM])
def test_every_pedsim_file_is_within_the_limits(path):
    check_costs(validate(pedsim_to_scenario(path), SCENARIO, str(path)), str(path))


# -- the figures, counted as the parts count them ------------------------------------------------------------------

@pytest.mark.parametrize("fov, res, beams", [(190.0, 0.5, 381), (180.0, 0.5, 361), (224.5, 0.5, 450),
                                             (270.0, 0.25, 1081), (360.0, 1.0, 360), (360.0, 0.036, 10000),
                                             (100.0, 0.3, 334), (1.0, 0.5, 3)])
def test_beams_are_counted_as_the_laser_counts_them(fov, res, beams):
    # a 190 deg laser at 0.5 deg has 381 beams: both ends are beams; a full circle has no last beam (it would repeat
    # the first)
    laser = {"name": "l", "mount": [0, 0, 0], "height": 0.7, "fov_deg": fov, "resolution_deg": res, "rate": 25.0,
             "range_min": 0.0, "range_max": 20.0, "noise": [], "no_return": "nan"}
    assert laser_beams(laser) == beams
    scene = types.SimpleNamespace(groups_at=Scene.groups_at)
    assert Laser(scene=scene, rng=np.random.default_rng(0), **laser).n_beams == beams


def test_huge_beam_counts_stay_numbers():
    laser = {"fov_deg": 190.0, "resolution_deg": 1e-320}
    assert laser_beams(laser) == math.inf
    assert laser_beams({"fov_deg": 190.0, "resolution_deg": 1e-7}) == pytest.approx(1.9e9 + 1)


def test_the_grid_is_counted_as_the_map_filter_makes_it():
    # a 10 m square room at 0.5 m with 0.25 m inflation: the margin is 0.25 + 0.5 = 0.75 m, the lowest walls lie in
    # the middle of a cell 2.5 cells in, so the grid starts at -1.25 m and has ceil((10 + 0.75 + 1.25) / 0.5) = 24
    # cells a side
    room = {"walls": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]], "obstacles": []}
    mf = {"resolution": 0.5, "inflation": 0.25, "max_occupied": 0.1, "obstacles": True}
    assert grid_shape(room, mf) == (24.0, 24.0)
    assert MapFilter(room["walls"], [], 0.5, 0.25).occupied.shape == (24, 24)
    airport = scenario("airport_disembarkation")
    mf = airport["pipeline"]["map_filter"]
    grid = MapFilter(airport["map"]["walls"], airport["map"]["obstacles"], mf["resolution"], mf["inflation"],
                     mf["max_occupied"]).occupied
    assert grid_shape(airport["map"], mf) == (grid.shape[1], grid.shape[0]) == (755, 715)


def test_the_figures_of_the_airport_and_the_room():
    c = scenario_costs(scenario("airport_disembarkation"))
    assert c["steps"] == pytest.approx((60 + 120) / 0.04)
    assert c["beams_per_scan"] == [381, 381] and c["beams_per_second"] == 2 * 381 * 25
    assert (c["persons_at_start"], c["max_agents"], c["chain_steps"]) == (34, 400, None)
    c = scenario_costs(scenario("seed001_room_1"))
    assert c["pixels_per_second"] == 2 * 640 * 480 * 5 and c["chain_steps"] == 150 + 40


# -- each cost limit refused, naming the key, and passed on purpose ------------------------------------------------

def test_steps_blame_a_tiny_dt():
    # H1: 10 s + 40 s at 1e-7 s are 5e8 steps; at the default 0.04 s they would be 1250
    message = refused(scenario("passers_by", dt=1e-7), "dt", "500,000,000 steps", "at most 1,000,000",
                      "a dt of at least 5e-05 s")
    assert "MAX_STEPS" in message


def test_steps_blame_a_huge_warm_up_or_duration():
    refused(scenario("passers_by", warmup=1e9), "warmup", "25,000,001,000 steps", "a warm-up of at most 39960 s")
    refused(scenario("passers_by", duration=1e6), "duration", "a duration of at most 39990 s")
    check_costs(scenario("passers_by", warmup=0.0, duration=costs.MAX_STEPS * 0.04 * 0.999), "my.yaml")
    refused(scenario("passers_by", warmup=5e4, duration=4.5e4), "warmup", "at most 40000 s together")


def test_beams_per_scan():
    # T16: 1e-7 deg over 190 deg would be 1.9e9 beams, 14 GiB
    laser = dict(RAW["seed001_room_1"]["sensors"]["lasers"][0], fov_deg=190.0, resolution_deg=1e-7)
    message = refused(scenario("seed001_room_1", sensors={"lasers": [laser]}), "sensors.lasers[0].resolution_deg",
                      "1,900,000,001 beams a scan", "at most 100,000", "at least 0.0019 deg")
    assert "MAX_BEAMS_PER_SCAN" in message


def test_beams_per_second_of_all_lasers():
    # 36,000 beams at 50 Hz: 1.8 million beams/s; the rear laser at 0.5 deg and 25 Hz adds 9,525
    front, rear = (dict(laser) for laser in RAW["airport_disembarkation"]["sensors"]["lasers"])
    front.update(fov_deg=360.0, resolution_deg=0.01, rate=50.0)
    sc = scenario("airport_disembarkation", dt=0.02, sensors={"lasers": [rear, front]})
    refused(sc, "sensors.lasers[1]", "36,000 beams a scan at 50 Hz", "1,800,000 beams/s",
            "all 2 lasers 1,809,525", "at most 1,000,000 beams/s")


def test_camera_pixels_per_second():
    # H3: 4096 x 4096 at 30 Hz, 503 million pixels/s
    cam = dict(RAW["ktp_group"]["sensors"]["depth_cameras"][0], width=4096, height=4096, rate=30.0)
    refused(scenario("ktp_group", sensors={"depth_cameras": [cam]}), "sensors.depth_cameras[0]",
            "4096 x 4096 pixels at 30 Hz", "503,316,480 pixels/s", "at most 100,000,000")


def test_camera_pixels_are_summed_over_depth_and_wall_cameras():
    room = RAW["seed001_room_1"]["sensors"]
    walls = [dict(c, width=4000, height=2500, rate=5.0) for c in room["wall_cameras"]]  # 50,000,000 each
    sc = scenario("seed001_room_1", sensors={"wall_cameras": walls})
    check_costs(sc, "my.yaml")  # 100,000,000: at the limit
    walls[1]["rate"] = 5.0 + 1e-6
    refused(scenario("seed001_room_1", sensors={"wall_cameras": walls}), "sensors.wall_cameras[1]",
            "all 2 cameras 100,000,")


def test_map_filter_grid():
    # T13: 1e-5 m over the airport: 1.3e13 cells, 12 TiB
    message = refused(scenario("airport_disembarkation", pipeline={"map_filter": {"resolution": 1e-5}}),
                      "pipeline.map_filter.resolution", "3,760,003 x 3,560,003", "at most 20,000,000")
    coarsest = float(message.split("a resolution of at least ")[1].split(" m")[0])
    sc = scenario("airport_disembarkation", pipeline={"map_filter": {"resolution": coarsest}})
    check_costs(sc, "my.yaml")  # the resolution the message proposes passes
    assert scenario_costs(sc)["grid_cells"] > costs.MAX_GRID_CELLS * 0.9  # and is about the finest that does


def test_map_extent():
    # T14: walls 1e9 m away; an obstacle far out is named rather than the walls
    far = [[[0, 0], [1e9, 0], [1e9, 1e9], [0, 1e9], [0, 0]]]
    refused(scenario("seed001_room_1", map={"walls": far}), "map.walls[0]", "span 1e+09 m x 1e+09 m",
            "at most 10000 m")
    pillar = [[5e4, 5e4], [5e4 + 1, 5e4], [5e4 + 1, 5e4 + 1]]
    refused(scenario("seed001_room_1", map={"obstacles": [pillar]}), "map.obstacles[0]")


def test_max_agents_and_persons_at_start():
    # T11, T12: max_agents 1e8 or 1e9 (6.4 GB, then a crash, before the contact solver's table followed the persons)
    refused(scenario("passers_by", crowd={"max_agents": 100_000_000}), "crowd.max_agents", "100,000,000 persons",
            "at most 10,000")
    clusters = [dict(RAW["seed001_room_1"]["clusters"][0], count=20_000)]
    refused(scenario("seed001_room_1", clusters=clusters, crowd={"max_agents": 20_000}), "clusters[0].count",
            "20,000 persons, 20,000 present at the start in all", "at most 10,000 persons at once")


def test_the_rjmcmc_chain():
    # T30: samples 1e9
    refused(scenario("seed001_room_1", pipeline={"tracker": {"type": "rjmcmc", "samples": 10 ** 9}}),
            "pipeline.tracker.samples", "1,000,000,040 steps", "at most 20,000")
    refused(scenario("seed001_room_1", pipeline={"tracker": {"type": "rjmcmc", "burn_in": 30_000}}),
            "pipeline.tracker.burn_in", "30,150 steps")
    sc = scenario("passers_by")
    sc["pipeline"]["tracker"] = {"type": "mht", "samples": 10 ** 9}  # no chain: not counted
    check_costs(sc, "my.yaml")


def test_a_pedsim_agent_cluster_is_named_by_its_line(tmp_path):
    # T24: <agent n="100000000">; the importer raises max_agents above it, so the cluster is what is named
    path = tmp_path / "huge.xml"
    path.write_text('<?xml version="1.0" encoding="UTF-8"?>\n<scenario>\n'
                    '  <obstacle x1="0" y1="0" x2="20" y2="0"/>\n  <obstacle x1="20" y1="0" x2="20" y2="20"/>\n'
                    '  <obstacle x1="20" y1="20" x2="0" y2="20"/>\n  <obstacle x1="0" y1="20" x2="0" y2="0"/>\n'
                    '  <waypoint id="a" x="5" y="5" r="1"/>\n  <waypoint id="b" x="15" y="15" r="1"/>\n'
                    '  <agent x="10" y="10" n="100000000" dx="4" dy="4" type="0"><addwaypoint id="a"/>'
                    '<addwaypoint id="b"/></agent>\n</scenario>\n')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PedsimWarning)
        sc = validate(pedsim_to_scenario(path), SCENARIO, str(path))
    with pytest.raises(ScenarioError) as info:
        check_costs(sc, str(path))
    assert info.value.key == "clusters[0].count"
    assert "100,000,000 persons (the PedSim <agent> on line 9)" in info.value.message
    check_costs(sc, str(path), allow_large=True)


# -- validity limits: refused even with allow_large -----------------------------------------------------------------

def test_persons_at_the_start_beyond_max_agents():
    # T09: two clusters of one person and max_agents 1; T10: a cluster of 5000 and the default 400
    refused(scenario("seed001_room_1", crowd={"max_agents": 1}), "crowd.max_agents", "1 persons at most at once",
            "2 are present at the start", "clusters[0].count 1, clusters[1].count 1", "at least 2",
            large_passes=False)
    clusters = [dict(RAW["seed001_room_1"]["clusters"][0], count=5000)]
    refused(scenario("seed001_room_1", clusters=clusters), "crowd.max_agents", "5,000 are present",
            large_passes=False)


def test_the_follow_target_counts_among_the_persons_at_the_start():
    raw = copy.deepcopy(read_raw(resolve("airport_follow")))
    raw["crowd"] = {**raw.get("crowd", {}), "max_agents": 34}  # 34 standing, and the target
    sc = validate(raw, SCENARIO, "follow.yaml")
    refused(sc, "crowd.max_agents", "34 persons at most at once, but 35 are present", large_passes=False)


def test_a_robot_faster_than_its_radius_a_step():
    # N04: 1e4 m/s leaves the building through its walls
    message = refused(scenario("airport_disembarkation", robot={"max_speed": 1e4, "max_acceleration": 1e6}),
                      "robot.max_speed", "400 m in one step", "radius (0.425 m)", "at most 10.6 m/s",
                      large_passes=False)
    assert "no cost limit" in message
    check_costs(scenario("airport_disembarkation", robot={"max_speed": 10.0, "max_acceleration": 1e9}), "my.yaml")


def test_a_robot_turning_more_than_a_quarter_turn_a_step():
    refused(scenario("airport_disembarkation", robot={"max_angular_speed": 50.0}), "robot.max_angular_speed",
            "2 rad in one step", "at most 39.3 rad/s", large_passes=False)


# -- memory follows the persons present ------------------------------------------------------------------------------

def test_the_contact_solver_table_is_unchanged_up_to_its_bound_and_grows_beyond(monkeypatch):
    walls = np.array([[[0.0, 0.0], [0.0, 10.0]]])
    assert ContactSolver(walls, 0.4, 400)._hash_bodies == 400  # as before: four cells per body of the capacity
    assert ContactSolver(walls, 0.4, 10 ** 9)._hash_bodies == contacts.HASH_BODIES  # not 4e9 cells

    def moved(solver):
        """Where 160 bodies go in 1 s: two overlapping discs part, one walking into the wall at x = 0 stops at it."""
        solver.add(np.full(150, 0.25))
        solver.add(np.full(10, 0.25))
        n = len(solver.bodies)
        pos = np.column_stack([np.arange(n) * 3.0 + 5.0, np.full(n, 5.0)])
        pos[1], pos[2] = pos[0] + [0.3, 0.0], [0.5, 5.0]
        for _ in range(25):
            vel = np.zeros((n, 2))
            vel[2] = [-2.0, 0.0]
            pos = solver.step(pos, vel, 0.04)
        return solver, pos

    sized, expected = moved(ContactSolver(walls, 0.0, 200))  # a table for 200 bodies from the start
    monkeypatch.setattr(contacts, "HASH_BODIES", 100)
    grown, pos = moved(ContactSolver(walls, 0.0, 10 ** 6))  # one for 100, grown to 200 by the 150 bodies
    assert (sized._hash_bodies, grown._hash_bodies) == (200, 200)
    assert np.linalg.norm(pos[1] - pos[0]) > 0.45 and 0.1 < pos[2, 0] < 0.3
    assert np.array_equal(pos, expected)  # the walls and bodies moved over to the new table whole


def test_a_scene_holds_more_than_its_bound_when_more_are_alive():
    # the follow driver's target joins a crowd that its sources filled to max_agents: one slot more
    walls = np.array([[[0.0, 0.0], [10.0, 0.0]]])
    scene = Scene(walls, 0.4, 2, ("torso",), initial_capacity=2)
    scene.sync(np.zeros(3), np.array([1, 2, 3]), np.array([[1.0, 1.0], [2.0, 1.0], [3.0, 1.0]]))
    assert scene.capacity == 3 and scene.alive == 3


def test_a_map_of_more_wall_segments_than_the_limit_is_refused_unless_allowed():
    from scenarios import scenario_from_dict
    from scenarios.costs import MAX_WALL_SEGMENTS
    from scenarios.loader import read_raw, resolve

    raw = read_raw(resolve("seed001_room_1"))
    # each obstacle a triangle, 3 segments, in place of the room's own; its outer wall, 4 segments, besides
    raw["map"]["obstacles"] = [[[5.0, 0.5], [5.01, 0.5], [5.01, 0.51]]] * (MAX_WALL_SEGMENTS // 3)
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(raw, "<many>")
    assert info.value.key == "map" and f"{MAX_WALL_SEGMENTS // 3 * 3 + 4:,} wall and obstacle segments" in str(info.value)
    assert scenario_from_dict(raw, "<many>", allow_large=True)["name"] == "seed001_room_1"
