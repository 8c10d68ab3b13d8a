"""The social-force crowd against analytic expectations: free walking, passing, walls, sources, sinks, groups."""

import numpy as np
import pytest

from crowdsim.crowd import Crowd
from crowdsim.crowd.behaviours import along_nearest_wall
from scenarios.geometry import closest_on_segments

DT = 0.04


def one_route(*points, radius=0.3, sink=True):
    wps = {f"w{k}": {"position": list(p), "radius": radius} for k, p in enumerate(points)}
    return {"waypoints": wps, "routes": {"r": {"waypoints": list(wps), "sink": sink}}}


def test_lone_agent_reaches_goal_at_desired_speed(make_scenario):
    # From rest, tau dv/dt = v0 - v gives x(t) = v0 (t - tau (1 - exp(-t/tau))): 20 m at v0 = 1.2 m/s take
    # 20/1.2 + tau = 17.17 s once the exponential has died out. No wall is within the 2 m wall range.
    sc = make_scenario(**one_route((25, 20), radius=0.05, sink=False))
    crowd = Crowd(sc, np.random.default_rng(0))
    crowd.add_walkers(np.array([[5.0, 20.0]]), "r", desired_speed=1.2)
    speeds, arrival = [], None
    for k in range(int(25 / DT)):
        crowd.step(DT)
        speeds.append(np.linalg.norm(crowd.vel[0]))
        if arrival is None and crowd.pos[0, 0] >= 25.0 - 1e-9:
            arrival = (k + 1) * DT
    assert arrival == pytest.approx(20 / 1.2 + 0.5, abs=0.1)
    assert np.mean(speeds[int(5 / DT):int(15 / DT)]) == pytest.approx(1.2, rel=1e-3)
    assert abs(crowd.pos[0, 1] - 20.0) < 1e-9  # a straight line: nothing pushed it sideways


def test_speed_never_exceeds_max_factor(make_scenario):
    sc = make_scenario(**one_route((35, 20), sink=False))
    crowd = Crowd(sc, np.random.default_rng(0))
    crowd.add_walkers(np.array([[5.0, 20.0], [5.0, 20.6], [5.6, 20.0]]), "r", desired_speed=1.0)
    for _ in range(200):
        crowd.step(DT)
        assert np.linalg.norm(crowd.vel, axis=1).max() <= 1.3 * 1.0 + 1e-9 + 0.6 / DT  # contacts may add a push
    assert np.linalg.norm(crowd.vel, axis=1).max() <= 1.3 + 1e-9


def test_two_agents_head_on_pass_without_overlapping(make_scenario):
    data = {"waypoints": {"east": {"position": [30, 20], "radius": 0.5}, "west": {"position": [10, 20], "radius": 0.5}},
            "routes": {"to_east": {"waypoints": ["east"]}, "to_west": {"waypoints": ["west"]}}}
    sc = make_scenario(**data)
    crowd = Crowd(sc, np.random.default_rng(0))
    a = crowd.add_walkers(np.array([[10.0, 20.05]]), "to_east", desired_speed=1.3)[0]
    b = crowd.add_walkers(np.array([[30.0, 19.95]]), "to_west", desired_speed=1.3)[0]
    closest, lateral = np.inf, 0.0
    for _ in range(int(30 / DT)):
        crowd.step(DT)
        if len(crowd.pos) == 2:
            closest = min(closest, np.linalg.norm(crowd.pos[0] - crowd.pos[1]))
            lateral = max(lateral, np.abs(crowd.pos[:, 1] - 20).max())
    assert closest >= 2 * 0.25 - 1e-9  # the bodies (radius 0.25 m) never overlapped
    assert lateral > 0.2  # they stepped aside for each other
    assert len(crowd.pos) == 0  # both reached their goals and left
    assert a != b


def test_agent_pushed_at_a_wall_never_crosses_it(make_scenario):
    # a wall across the room at y = 20; the goal lies behind it, so everyone presses into it, and pushes each other
    walls = [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]], [[0, 20], [40, 20]]]
    sc = make_scenario(walls=walls, **one_route((20, 30), sink=False))
    crowd = Crowd(sc, np.random.default_rng(1))
    start = np.stack([np.linspace(17, 23, 15), np.full(15, 15.0)], 1)
    crowd.add_walkers(np.concatenate([start, start + [0, -1.0]]), "r", desired_speed=1.8)
    for _ in range(int(20 / DT)):
        crowd.step(DT)
        assert crowd.pos[:, 1].max() <= 20 - 0.25 + 1e-9
        _, d = closest_on_segments(crowd.pos, crowd.walls)
        assert d.min() >= 0.25 - 1e-9


def test_corner_keeps_agents_out_of_both_walls(make_scenario):
    sc = make_scenario(**one_route((39.9 - 0.3, 39.9 - 0.3), radius=0.01, sink=False))
    crowd = Crowd(sc, np.random.default_rng(2))
    crowd.add_walkers(np.random.default_rng(3).uniform(25, 35, (20, 2)), "r", desired_speed=1.5)
    for _ in range(int(20 / DT)):
        crowd.step(DT)
    _, d = closest_on_segments(crowd.pos, crowd.walls)
    assert d.min() >= 0.25 - 1e-9
    assert crowd.pos.max() <= 40 - 0.25 + 1e-9


def test_source_rate_and_sink(make_scenario):
    # 1 person/s for 100 s (singles): a Poisson count with mean 100, sd 10; all leave at the sink 10 m away
    sc = make_scenario(sources=[{"position": [5, 20], "size": [1, 3], "rate": 1.0, "stop": 100.0, "routes": {"r": 1}}],
                       **one_route((15, 20), radius=0.8))
    crowd = Crowd(sc, np.random.default_rng(4))
    seen = set()
    for _ in range(int(130 / DT)):
        crowd.step(DT)
        seen.update(crowd.id.tolist())
    assert 70 <= len(seen) <= 130
    assert len(crowd.pos) == 0  # everyone reached the sink and left


def test_groups_are_emitted_together_and_stay_together(make_scenario):
    sc = make_scenario(sources=[{"position": [5, 20], "size": [2, 4], "rate": 0.5, "stop": 40.0, "routes": {"r": 1},
                                 "group_size_weights": [0, 0, 1]}], **one_route((35, 20), sink=False))
    crowd = Crowd(sc, np.random.default_rng(5))
    spread = []
    for _ in range(int(50 / DT)):
        crowd.step(DT)
        for g in np.unique(crowd.group):
            members = crowd.pos[crowd.group == g]
            spread.append(np.linalg.norm(members - members.mean(0), axis=1).max())
    sizes = np.unique(crowd.group, return_counts=True)[1]
    assert (sizes == 3).all() and len(sizes) >= 3
    assert np.max(spread) < 2.0


def test_standing_group_stays_in_place(make_scenario):
    sc = make_scenario(standing=[{"position": [20, 20], "count": 4, "spacing": 0.9}])
    crowd = Crowd(sc, np.random.default_rng(6))
    start = crowd.pos.copy()
    for _ in range(200):
        crowd.step(DT)
    # they settle where the anchor's pull balances the members' mutual repulsion, a few centimetres out
    assert np.abs(crowd.pos - start).max() < 0.1
    assert np.abs(crowd.vel).max() < 0.01
    # four on a circle with 0.9 m between neighbours: radius 0.9 / (2 sin(pi/4))
    assert np.linalg.norm(start - [20, 20], axis=1) == pytest.approx(np.full(4, 0.9 / np.sqrt(2)))
    assert len(np.unique(crowd.group)) == 1 and crowd.group[0] >= 0


def test_same_seed_same_crowd(make_scenario):
    sc = make_scenario(sources=[{"position": [5, 20], "size": [2, 4], "rate": 2.0, "routes": {"r": 1},
                                 "group_size_weights": [0.6, 0.3, 0.1]}], **one_route((35, 20)))
    runs = []
    for _ in range(2):
        crowd = Crowd(sc, np.random.default_rng(7))
        for _ in range(300):
            crowd.step(DT)
        runs.append(crowd.states())
    assert np.array_equal(runs[0].id, runs[1].id)
    assert np.array_equal(runs[0].position, runs[1].position)
    assert np.array_equal(runs[0].group_id, runs[1].group_id)


def queue_room(make_scenario, service_time):
    return make_scenario(
        waypoints={"exit": {"position": [20, 5], "radius": 0.5}},
        queues={"desk": {"position": [20, 20], "direction_deg": 0.0, "spacing": 0.7, "service_time": service_time}},
        routes={"r": {"waypoints": ["desk", "exit"]}})


def test_queue_lines_people_up_behind_the_service_point(make_scenario):
    # the line grows along +x from the desk at (20, 20): slot k is at (20 + 0.7 k, 20)
    crowd = Crowd(queue_room(make_scenario, service_time=1e6), np.random.default_rng(8))
    ids = crowd.add_walkers(np.stack([np.full(5, 30.0), np.linspace(16, 24, 5)], 1), "r", desired_speed=1.2)
    for _ in range(int(40 / DT)):
        crowd.step(DT)
    line = crowd.queues.members[0]
    assert sorted(line) == sorted(ids.tolist())
    idx = np.searchsorted(crowd.id, line)
    slots = np.stack([20 + 0.7 * np.arange(5), np.full(5, 20.0)], 1)
    assert np.abs(crowd.pos[idx] - slots).max() < 0.15
    assert len(crowd.id) == 5  # nobody served yet: the service takes "forever"


def test_queue_serves_first_come_first_served(make_scenario):
    crowd = Crowd(queue_room(make_scenario, service_time=2.0), np.random.default_rng(9))
    crowd.add_walkers(np.stack([np.full(4, 30.0), np.linspace(17, 23, 4)], 1), "r", desired_speed=1.2)
    joined, left, alive = [], [], set(crowd.id.tolist())
    for _ in range(int(120 / DT)):
        crowd.step(DT)
        joined += [i for i in crowd.queues.members[0] if i not in joined]
        now = set(crowd.id.tolist())
        left += sorted(alive - now)
        alive = now
    assert len(joined) == 4 and len(crowd.id) == 0
    # served in the order they joined; they walk the same 15 m to the exit, so they also leave in that order
    assert left == joined


def test_groups_too_wide_for_a_corridor_enter_one_behind_another(make_scenario):
    # a 2 m corridor (y 19..21): four abreast need 4 x 0.6 = 2.4 m, so each group is emitted in file, inside it
    walls = [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]], [[2, 19], [38, 19]], [[2, 21], [38, 21]]]
    sc = make_scenario(walls=walls, sources=[{"position": [4, 20], "size": [1, 2], "rate": 1.0, "stop": 20.0,
                                              "routes": {"r": 1}, "group_size_weights": [0, 0, 0, 1]}],
                       **one_route((36, 20), radius=0.8))
    crowd = Crowd(sc, np.random.default_rng(10))
    emitted = set()
    for _ in range(int(30 / DT)):
        crowd.step(DT)
        emitted.update(crowd.id.tolist())
        inside = (crowd.pos[:, 0] > 2) & (crowd.pos[:, 0] < 38)
        assert (np.abs(crowd.pos[inside, 1] - 20) <= 1 - 0.25 + 1e-9).all()
    assert len(emitted) >= 8  # the groups did get in


@pytest.mark.parametrize("strength", [0.0, 1000.0])
def test_attraction_draws_passers_by_then_lets_them_go(make_scenario, strength):
    # walking along y = 20 past a shop whose area spans y 22..24: with strength 0 nobody turns; with a huge
    # strength the walker is drawn at once (p = 1 - exp(-0.05 x 1000 x 0.04) = 0.86 per step), walks to the
    # area's nearest edge (y = 22), lingers, then walks on to the sink
    sc = make_scenario(attractions={"shop": {"position": [20, 23], "size": [2, 2], "strength": strength,
                                             "reach": 3.0, "visit_time": 5.0}},
                       **one_route((35, 20), radius=0.5))
    crowd = Crowd(sc, np.random.default_rng(11))
    crowd.add_walkers(np.array([[5.0, 20.0]]), "r", desired_speed=1.3)
    top, steps = 20.0, 0
    while len(crowd.id) and steps < int(120 / DT):
        crowd.step(DT)
        steps += 1
        if len(crowd.id):
            top = max(top, crowd.pos[0, 1])
    assert len(crowd.id) == 0  # it reached the sink either way
    if strength == 0:
        assert top == pytest.approx(20.0, abs=1e-6)
    else:
        assert top > 21.5  # it walked to the edge of the shop area, y = 22


def test_slow_walker_squeezes_through_a_door_it_fits(make_scenario):
    # A 0.8 m door in a wall at x = 20. At 0.6 m/s the drive (0.6 / 0.5 s = 1.2 m/s^2) is weaker than the two door
    # edges' repulsion 0.25 m off the doorway (2 x 25 exp(-0.24 / 0.08) x 0.58 = 1.4 m/s^2), so the social forces
    # alone hold the walker before the door; after stuck_time (1 s) it ignores the walls' repulsion and passes,
    # its body (0.5 m) still clear of both edges.
    walls = [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]], [[20, 0], [20, 19.6]], [[20, 20.4], [20, 40]]]
    sc = make_scenario(walls=walls, **one_route((25, 20), radius=0.3, sink=True))
    crowd = Crowd(sc, np.random.default_rng(0))
    crowd.add_walkers(np.array([[17.0, 20.0]]), "r", desired_speed=0.6)
    passed = None
    for k in range(int(30 / DT)):
        crowd.step(DT)
        if len(crowd.pos) == 0:
            break
        _, d = closest_on_segments(crowd.pos, crowd.walls)
        assert d.min() >= 0.25 - 1e-9
        if passed is None and crowd.pos[0, 0] > 20.0:
            passed = (k + 1) * DT
    assert passed is not None and passed < 12.0
    assert len(crowd.pos) == 0  # reached the goal behind the door


def test_walker_whose_goal_a_wall_hides_slides_round_its_end(make_scenario):
    # a free-standing partition from x = 14 to 26 at y = 20 lies between the walker and its goal straight behind
    # it: the wall's repulsion balances the drive, so it stops there until it slides along the wall, past the
    # end, and on to the goal
    walls = [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]], [[14, 20], [26, 20]]]
    sc = make_scenario(walls=walls, **one_route((20.5, 25), radius=0.5, sink=True))
    crowd = Crowd(sc, np.random.default_rng(0))
    crowd.add_walkers(np.array([[20.0, 15.0]]), "r", desired_speed=1.2)
    for _ in range(int(40 / DT)):
        crowd.step(DT)
        if len(crowd.pos) == 0:
            break
    assert len(crowd.pos) == 0


def test_pressure_from_ahead_stops_a_walker_without_walking_it_backwards(make_scenario):
    # a robot stands 2 m ahead; its repulsion (U/R = 10 / 0.2 = 50 m/s^2 at its rim) overwhelms the drive when the
    # walker comes close: the walker stops short of it, never moving backwards along its way
    sc = make_scenario(**one_route((30, 20), radius=0.3, sink=False))
    crowd = Crowd(sc, np.random.default_rng(0))
    crowd.add_walkers(np.array([[16.0, 20.0]]), "r", desired_speed=1.34)
    robot, robot_radius = np.array([18.9, 20.0]), 0.425
    along = []
    for _ in range(int(5 / DT)):
        crowd.step(DT, robot, robot_radius)
        along.append(crowd.vel[0, 0])
    assert min(along) >= -1e-9
    assert crowd.pos[0, 0] < robot[0] - robot_radius - 0.25  # stopped short of the robot's body
    assert abs(along[-1]) < 0.05


def test_wall_following_keeps_the_wall_on_its_side_round_a_corner(make_scenario):
    # in the 40 m room, the wall y = 0 below: with it on the right a walker heads +x; near the corner (40, 0),
    # where the wall x = 40 is nearer, it turns left and heads +y, the wall still on its right. With the walls on
    # the left it heads -x along y = 0, and -y along x = 40 (towards the corner, where it turns right onto y = 0)
    crowd = Crowd(make_scenario(**one_route((20, 20))), np.random.default_rng(0))
    crowd.add_walkers(np.array([[20.0, 0.5], [39.6, 0.5]]), "r")
    right = along_nearest_wall(crowd.pos, crowd.walls, np.array([1.0, 1.0]))
    left = along_nearest_wall(crowd.pos, crowd.walls, np.array([-1.0, -1.0]))
    assert right == pytest.approx(np.array([[1.0, 0.0], [0.0, 1.0]]))
    assert left == pytest.approx(np.array([[-1.0, 0.0], [0.0, -1.0]]))


def test_the_step_kernels_by_hand(make_scenario):
    from crowdsim.crowd import forces
    from crowdsim.crowd.crowd import _desired, _moved, _velocity
    from scenarios.wall_grid import WallGrid

    # the goal 5 m away at (3, 4): e = (0.6, 0.8) at the desired speed; a standing person 0.15 m from their spot
    # (half the arrival radius) wants half their speed; one waiting at a waypoint wants none
    pos, goal = np.zeros((3, 2)), np.array([[3.0, 4.0], [0.15, 0.0], [0.0, 2.0]])
    e, speed = _desired(goal, pos, np.array([1.2, 1.0, 1.0]), np.array([False, True, True]),
                        np.array([False, False, True]), 0.3)
    assert e == pytest.approx(np.array([[0.6, 0.8], [1.0, 0.0], [0.0, 1.0]]))
    assert speed == pytest.approx([1.2, 0.5, 0.0])

    # three persons 10 m apart (out of each other's reach), no walls, no robot, no random force: each feels only the
    # relaxation (v0 e - v) / tau, tau = 0.5 s, for dt = 0.1 s. From rest at 1.2 m/s: v = 0.24 m/s. Walking at 2 m/s
    # wanting 1 m/s: 2 - 0.2 = 1.8, capped at 1.3 x 1 m/s. Walking backwards at 1 m/s wanting to stand: -0.8 m/s,
    # which a walker does not keep (it stops) and a person holding a spot does (pushed back to it, under the cap)
    crowd = Crowd(make_scenario(crowd={"random_force": 0.0}), np.random.default_rng(0))
    pos = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]])
    vel = np.array([[0.0, 0.0], [2.0, 0.0], [-1.0, 0.0]])
    east = np.array([[1.0, 0.0]] * 3)
    no_groups = (np.zeros(0, np.int64), np.zeros(0, np.int64), 0)
    order = np.arange(3)  # the order of the pair forces' sums
    args = (np.full(3, 0.25), *no_groups, np.ones(3, bool), forces.NO_FORCE, forces.NO_PAIRS, order, True, np.nan,
            np.nan, 0.0, 0.1, *crowd._parameters, *WallGrid.of(np.zeros((0, 2, 2))).arrays())
    walking = _velocity(pos, vel, np.array([1.2, 1.0, 1.0]), east, np.array([1.2, 1.0, 0.0]), np.zeros(3, bool),
                        *args)
    assert walking == pytest.approx(np.array([[0.24, 0.0], [1.3, 0.0], [0.0, 0.0]]))
    holding = _velocity(pos[2:], vel[2:], np.ones(1), east[:1], np.zeros(1), np.ones(1, bool),
                        *(order[:1] if a is order else a[2:] if isinstance(a, np.ndarray) and a.shape == (3,) else a
                          for a in args))
    assert holding == pytest.approx(np.array([[-0.8, 0.0]]))

    # a move of (0.3, 0.4) in 0.1 s is 5 m/s and 0.5 m walked; one that crossed a wall is undone: 0 m/s
    before, after = np.zeros((2, 2)), np.array([[0.3, 0.4], [1.0, 0.0]])
    walked = np.array([2.0, 2.0])
    assert _moved(after, before, np.array([False, True]), walked, 0.1) == pytest.approx(np.array([[3.0, 4.0],
                                                                                                   [0.0, 0.0]]))
    assert walked == pytest.approx([2.5, 2.0]) and np.array_equal(after[1], [0.0, 0.0])


def test_held_time_counts_walkers_under_a_fifth_of_their_speed():
    from crowdsim.crowd.behaviours import _held_for

    # desired 1 m/s: 0.1 m/s is held (+dt), 0.3 m/s walks (back to 0), and a person holding a spot is never held
    held = _held_for(np.array([1.0, 1.0, 1.0]), np.array([[0.06, 0.08], [0.3, 0.0], [0.0, 0.0]]), np.ones(3),
                     np.array([False, False, True]), 0.04)
    assert held == pytest.approx([1.04, 0.0, 0.0])


def test_arrival_within_the_goal_radius():
    from crowdsim.crowd.behaviours import _arrived

    # 5 m from the goal arrives within 5.1 m, not within 5 m (strictly inside), nor when not a candidate
    goal, pos = np.zeros((3, 2)), np.array([[3.0, 4.0]] * 3)
    assert _arrived(goal, pos, np.array([5.1, 5.0, 5.1]), np.array([True, True, False])).tolist() == [True, False,
                                                                                                      False]
