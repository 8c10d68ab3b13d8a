"""The crowd at its edges: groups reduced to one member, a crowd with nobody in it, a crowd that empties, persons
who start at a sink. Each of these once crashed a run or could have."""

import numpy as np
import pytest

from crowdsim.crowd import Crowd
from crowdsim.crowd.forces import group_forces

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
