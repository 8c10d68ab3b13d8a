"""The crowd at its edges: groups reduced to one member, a crowd with nobody in it, a crowd that empties, persons
who start at a sink. Each of these once crashed a run or could have."""

import numpy as np
import pytest

from crowdsim.crowd import Crowd
from crowdsim.crowd.forces import group_forces
from scenarios.geometry import closest_on_segments, segments_cross

DT = 0.04
TAU = 0.5  # s, the default relaxation time


def sink_at(x, y, radius):
    return {"waypoints": {"exit": {"position": [x, y], "radius": radius}},
            "routes": {"out": {"waypoints": ["exit"]}}}


def test_group_forces_act_only_within_groups_of_two_or_more():
    # two persons alone in their groups (labels 3 and 8), a pair side by side 0.4 m apart (label 5), one person in
    # no group: the pair's members are nearer than their radii plus the 0.3 m margin, so each is pushed away from
    # the other with the repulsion's full strength (1 m/s^2); their centre is 0.2 m off, within the coherence's
    # (2 - 1) / 2 m, and each sees the other at the edge of its 90 degree vision: no other term
    pos = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0], [10.0, 0.4], [20.0, 0.0]])
    vel = np.tile([1.0, 0.0], (5, 1))
    direction = np.tile([1.0, 0.0], (5, 1))
    radius = np.full(5, 0.25)
    f = group_forces(pos, vel, direction, radius, np.array([3, 8, 5, 5, -1]), 4.0, 3.0, 1.0)
    assert f == pytest.approx(np.array([[0, 0], [0, 0], [0, -1], [0, 1], [0, 0]]))
    # only groups of one, or nobody at all: no force, and no error
    assert not group_forces(pos, vel, direction, radius, np.array([3, 8, 5, 6, 7]), 4.0, 3.0, 1.0).any()
    assert group_forces(pos[:0], vel[:0], direction[:0], radius[:0], np.zeros(0, np.int64), 4.0, 3.0, 1.0).shape \
        == (0, 2)


def test_members_left_alone_by_their_group_walk_on_as_singles(make_scenario):
    # The reported crash (shopping.xml, seed 1): every walking group present had one member, the others being at a
    # shop, and the group forces failed. Here two pairs each lose a member at the sink on the first tick (they start
    # inside its 1 m radius); the two left walk on, each the only member of its group, along y = 20 to the sink.
    crowd = Crowd(make_scenario(**sink_at(30, 20, 1.0)), np.random.default_rng(0))
    a = crowd.add_walkers(np.array([[30.0, 20.0], [10.0, 20.0]]), "out", desired_speed=1.2, group=True)
    b = crowd.add_walkers(np.array([[30.6, 20.0], [20.0, 20.0]]), "out", desired_speed=1.2, group=True)
    groups = crowd.group.copy()
    assert groups[0] == groups[1] != groups[2] == groups[3] >= 0
    crowd.step(DT)
    assert crowd.id.tolist() == [a[1], b[1]]  # the two at the sink left at once
    assert crowd.group.tolist() == [groups[1], groups[3]]  # the others keep their group's id in the ground truth
    arrival = {}
    for k in range(2, int(25 / DT)):
        crowd.step(DT)
        assert (np.abs(crowd.pos[:, 1] - 20.0) < 1e-9).all()  # nothing pulls them off their line
        for i in {a[1], b[1]} - set(crowd.id.tolist()) - set(arrival):
            arrival[i] = k * DT
    assert len(crowd.id) == 0
    # each leaves when within 1 m of the sink: x(t) = v0 (t - tau) once the start has died out, a little earlier
    # for the push towards the partner on the first tick (3 m/s^2 for 0.04 s, 0.06 m over tau)
    assert arrival[b[1]] == pytest.approx(9.0 / 1.2 + TAU, abs=0.1)
    assert arrival[a[1]] == pytest.approx(19.0 / 1.2 + TAU, abs=0.1)


def test_pairs_split_by_a_shop_walk_on_and_all_visit_it(make_scenario):
    # the reported crash's own situation: two pairs walk along y = 20 past a shop (its area spans y 23.2..25.2,
    # reach 3 m, so irresistible that whoever comes within reach goes): members are drawn one at a time, and
    # while one member of each pair shops, every walking group has one member. Each walks up to the area's edge,
    # lingers, and everyone reaches the sink at x = 18
    sc = make_scenario(attractions={"shop": {"position": [10, 24.2], "size": [2, 2], "strength": 1e6, "reach": 3.0,
                                             "visit_time": 1.0}}, **sink_at(18, 20, 1.0))
    crowd = Crowd(sc, np.random.default_rng(0))
    for x in (5.0, 0.5):
        crowd.add_walkers(np.array([[x, 19.6], [x, 20.4]]), "out", desired_speed=1.2, group=True)
    top, alone = np.zeros(5), False
    while len(crowd.id) and crowd.t < 30:
        crowd.step(DT)
        top[crowd.id] = np.maximum(top[crowd.id], crowd.pos[:, 1])
        walking = crowd.group[~crowd.holding]
        alone |= len(walking) >= 2 and len(np.unique(walking)) == len(walking)
        _, d = closest_on_segments(crowd.pos, crowd.walls)
        assert (d.min(axis=1) >= crowd.radius - 1e-9).all()
    assert alone
    assert (top[1:] > 23.2 - 0.3).all()  # each came within 0.3 m (the spot's radius) of the area's edge
    assert len(crowd.id) == 0 and crowd.t < 30


def test_a_crowd_with_nobody_in_it_steps_and_reports_no_one(make_scenario):
    # routes but no sources, clusters or standing people: ten seconds of simulation with the robot passing through
    crowd = Crowd(make_scenario(**sink_at(30, 20, 1.0)), np.random.default_rng(0))
    for k in range(int(10 / DT)):
        crowd.step(DT, np.array([5.0 + 0.04 * k, 20.0]), 0.425)
        states = crowd.states()
        assert states.id.shape == (0,) and states.position.shape == (0, 2) and states.velocity.shape == (0, 2)
    assert states.stamp == pytest.approx(10.0)
    # the first person placed afterwards is person 1, and asking for nobody gives no ids
    assert crowd.add_walkers(np.zeros((0, 2)), "out").tolist() == []
    assert crowd.add_walkers(np.array([[10.0, 20.0]]), "out").tolist() == [1]
    assert crowd.add_walkers(np.zeros((0, 2)), "out").tolist() == []


def test_a_crowd_that_empties_then_fills_again_keeps_its_ids_and_its_walls(make_scenario):
    # a wall at x = 20 with a 2 m door (y 19..21); adults enter at (15, 20) for 3 s, pass the door and leave at
    # the sink 4 m behind it; the slowest (0.6 m/s) need about 8 m / 0.6 = 13 s, so the hall is empty well before
    # a second source opens at 25 s for 2 s
    walls = [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]], [[20, 0], [20, 19]], [[20, 21], [20, 40]]]
    source = {"position": [15, 20], "size": [2, 2], "rate": 3.0, "routes": {"out": 1}, "group_size_weights": [1, 1]}
    sc = make_scenario(walls=walls, sources=[{**source, "stop": 3.0}, {**source, "start": 25.0, "stop": 27.0}],
                       **sink_at(24, 20, 1.0))
    crowd = Crowd(sc, np.random.default_rng(1))
    first, second, gone, empty_at = set(), set(), set(), []
    for _ in range(int(45 / DT)):
        before = dict(zip(crowd.id.tolist(), crowd.pos))
        crowd.step(DT)
        ids = crowd.id.tolist()
        (first if crowd.t < 25 else second).update(ids)
        assert not gone & set(ids)  # nobody comes back under an id that has left
        gone |= set(before) - set(ids)
        if not ids:
            empty_at.append(crowd.t)
            continue
        _, d = closest_on_segments(crowd.pos, crowd.walls)
        assert (d.min(axis=1) >= crowd.radius - 1e-9).all()
        stayed = np.isin(crowd.id, list(before))
        start = np.array([before[i] for i in crowd.id[stayed].tolist()]).reshape(-1, 2)
        assert not segments_cross(start, crowd.pos[stayed], crowd.walls).any()
    assert 3 <= len(first) <= 16 and 2 <= len(second) <= 11  # Poisson counts of mean 9 and 6
    assert sorted(first) == list(range(1, len(first) + 1))
    assert min(second) == max(first) + 1  # ids go on counting after the crowd emptied
    assert min(empty_at) < 20.0 and any(20.0 < t < 25.0 for t in empty_at)  # empty between the two sources
    assert len(crowd.id) == 0 and gone == first | second  # everyone reached the sink


def test_persons_who_start_at_a_sink_leave_on_the_first_tick(make_scenario):
    # a cluster of three (one group) starts within the sink's 2 m radius, a walker 10 m before it and a standing
    # person right at it (standing people have no route, so no sink); a source inside the sink's radius emits
    # people who leave on the tick they enter
    sc = make_scenario(clusters=[{"position": [30, 20], "count": 3, "spread": [1, 1], "route": "out",
                                  "group_size_weights": [0, 0, 1]}],
                       standing=[{"position": [31, 21]}],
                       sources=[{"position": [29.5, 19], "rate": 5.0, "stop": 2.0, "routes": {"out": 1}}],
                       **sink_at(30, 20, 2.0))
    crowd = Crowd(sc, np.random.default_rng(2))
    walker = crowd.add_walkers(np.array([[20.0, 20.0]]), "out", desired_speed=1.0)[0]
    start = crowd.states()
    assert start.id.tolist() == [1, 2, 3, 4, 5]  # the standing person, the cluster, the walker
    assert len(np.unique(start.group_id[1:4])) == 1 and start.group_id[1] >= 0
    crowd.step(DT)
    assert crowd.id.tolist() == [1, walker]
    assert crowd.pos[0] == pytest.approx([31, 21], abs=0.01)
    # the walker, from rest: v = v0 dt / tau after one tick, so it moved v dt along x
    assert crowd.pos[1] == pytest.approx([20.0 + 1.0 * DT / TAU * DT, 20.0], abs=1e-9)
    for _ in range(int(3 / DT)):
        crowd.step(DT)
        assert crowd.id.tolist() == [1, walker]  # whoever the source emits is gone within the tick
    assert crowd.add_walkers(np.array([[10.0, 10.0]]), "out")[0] > walker + 5  # the source did emit persons
