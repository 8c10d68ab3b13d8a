"""Waiting at a waypoint (the waypoint's ``wait``): a walker stands there for the wait once inside its radius, then
goes on; a wait of 0 is the walk without one, bit for bit; a group gathering at one waypoint stands round it, as
the bundled ktp_group's five do."""

import numpy as np
import pytest

from crowdsim.crowd import Crowd
from scenarios import load_scenario

DT = 0.04


def a_then_b(wait_a=None, radius=0.5, random_force=0.0):
    """Waypoint A at (10, 20), then B at (20, 20), a sink; A's wait left out when ``wait_a`` is None."""
    a = {"position": [10.0, 20.0], "radius": radius}
    if wait_a is not None:
        a["wait"] = wait_a
    return {"waypoints": {"a": a, "b": {"position": [20.0, 20.0], "radius": 0.3}},
            "routes": {"r": {"waypoints": ["a", "b"]}}, "crowd": {"random_force": random_force}}


def walk(crowd: Crowd, seconds: float) -> list[tuple[float, np.ndarray, np.ndarray, np.ndarray]]:
    """(time, positions, velocities, goals) after every step."""
    out = []
    for _ in range(int(round(seconds / DT))):
        crowd.step(DT)
        out.append((crowd.t, crowd.pos.copy(), crowd.vel.copy(), crowd.goal.copy()))
    return out


def test_a_walker_stands_at_a_for_its_wait_then_walks_on_to_b(make_scenario):
    # From rest, x(t) = v0 (t - tau (1 - exp(-t/tau))) with v0 1.2 m/s, tau 0.5 s: the 4.5 m to A's radius take
    # 4.5 / 1.2 + 0.5 = 4.25 s. With no desired velocity the walker then brakes over v0 tau = 0.6 m, to x = 10.1,
    # inside A's 0.5 m; 3 s after reaching A it heads for B.
    crowd = Crowd(make_scenario(**a_then_b(wait_a=3.0)), np.random.default_rng(0))
    crowd.add_walkers(np.array([[5.0, 20.0]]), "r", desired_speed=1.2)
    run = walk(crowd, 12.0)
    t = np.array([s[0] for s in run])
    x = np.array([s[1][0, 0] for s in run])
    speed = np.array([np.linalg.norm(s[2][0]) for s in run])
    to_b = np.array([s[3][0, 0] == 20.0 for s in run])
    reached = t[np.argmax(x > 9.5)]
    left = t[np.argmax(to_b)]
    assert reached == pytest.approx(4.25, abs=0.05)
    assert left - reached == pytest.approx(3.0, abs=DT + 1e-9)
    waiting = (t >= reached) & (t < left)
    assert (np.abs(x[waiting] - 10.0) < 0.5).all()  # stood within A's radius all the while
    assert x[waiting].max() == pytest.approx(10.1, abs=0.06)  # braked over v0 tau = 0.6 m
    assert speed[t == t[waiting][-1]][0] < 0.01  # standing still by the end of the wait
    assert x[-1] > 14.0  # and then walked on towards B: 1.2 m/s for 12 - 4.25 - 3 - 0.5 s
    assert np.allclose([s[1][0, 1] for s in run], 20.0)  # a straight line throughout


def test_without_a_wait_the_walk_is_unchanged_bit_for_bit(make_scenario):
    # wait 0 and the key left out are the same walk, random force and all; a wait changes nothing before A
    starts = np.array([[5.0, 20.0], [4.0, 20.6], [3.0, 19.4]])
    runs = {}
    for wait in (None, 0.0, 3.0):
        crowd = Crowd(make_scenario(**a_then_b(wait_a=wait, random_force=0.1)), np.random.default_rng(3))
        crowd.add_walkers(starts, "r")
        runs[wait] = walk(crowd, 12.0)
    for none, zero in zip(runs[None], runs[0.0]):
        assert all(np.array_equal(p, q) for p, q in zip(none, zero))
    first_in = next(k for k, s in enumerate(runs[None]) if (np.abs(s[1][:, 0] - 10.0) < 0.5).any())
    for k in range(first_in + 1):  # identical up to the step the first walker reaches A
        assert np.array_equal(runs[None][k][1], runs[3.0][k][1])
    assert not np.array_equal(runs[None][first_in + 2][1], runs[3.0][first_in + 2][1])


def test_the_same_seed_waits_the_same_bit_for_bit(make_scenario):
    def run():
        crowd = Crowd(make_scenario(**a_then_b(wait_a=2.0, random_force=0.1)), np.random.default_rng(5))
        crowd.add_walkers(np.array([[5.0, 20.0], [4.0, 20.6], [3.0, 19.4]]), "r")
        return np.concatenate([s[1].ravel() for s in walk(crowd, 10.0)])
    assert np.array_equal(run(), run())


def test_a_gathering_group_stands_round_its_waypoint_then_leaves(make_scenario):
    # five walkers from five sides meet at G (radius 1 m, wait 6 s), then leave through the exit at (35, 20)
    data = {"waypoints": {"g": {"position": [20.0, 20.0], "radius": 1.0, "wait": 6.0},
                          "exit": {"position": [35.0, 20.0], "radius": 0.5}},
            "routes": {"gather": {"waypoints": ["g", "exit"]}}, "crowd": {"random_force": 0.1}}
    crowd = Crowd(make_scenario(**data), np.random.default_rng(1))
    angles = np.radians([0, 72, 144, 216, 288])
    crowd.add_walkers(20.0 + 6.0 * np.stack([np.cos(angles), np.sin(angles)], 1), "gather", desired_speed=1.2)
    run = walk(crowd, 30.0)
    # the 5 m to G's radius take 5 / 1.2 + 0.5 = 4.7 s (the others, slowed by each other, arrive by 6 s); each
    # leaves 6 s after arriving, so at 9 s all five are waiting
    t, pos, vel, goal = next(s for s in run if s[0] >= 9.0 - 1e-9)
    assert len(pos) == 5 and (goal == [20.0, 20.0]).all()  # all still waiting at G
    dist = np.linalg.norm(pos - [20.0, 20.0], axis=1)
    # they stopped within G's 1 m radius, round it; neighbours about 1 m apart still repel, so the ring spreads
    # slowly (a few cm/s), never towards G's centre
    assert 0.7 < dist.min() and dist.max() < 1.3
    assert np.linalg.norm(vel, axis=1).max() < 0.1  # standing
    gaps = np.linalg.norm(pos[:, None] - pos[None], axis=-1)[np.triu_indices(5, 1)]
    assert gaps.min() >= 0.5 - 1e-6  # round G, bodies (0.25 m) apart, not on its centre
    assert len(run[-1][1]) == 0  # after the wait, all walked the 15-16 m to the exit (13 s) and left


def test_the_bundled_ktp_group_gathers_stands_and_leaves():
    # seed 003's group situation: five gather at (3.7, 1.5) (radius 1 m, 6 s wait), then leave the room (y 0..3 m)
    # for the halls beyond its doors, where they stand out of sight
    scenario = load_scenario("ktp_group")
    crowd = Crowd(scenario, np.random.default_rng(scenario["seed"]))
    robot = np.array(scenario["robot"]["start"][:2])
    dt = scenario["dt"]
    for _ in range(int(round(6.0 / dt))):
        crowd.step(dt, robot, scenario["robot"]["radius"])
    assert len(crowd.pos) == 5 and crowd.waiting.sum() >= 4
    assert (np.linalg.norm(crowd.pos - [3.7, 1.5], axis=1) < 1.5).all()
    assert (np.linalg.norm(crowd.vel[crowd.waiting], axis=1) < 0.2).all()
    for _ in range(int(round((scenario["duration"] - 6.0) / dt))):
        crowd.step(dt, robot, scenario["robot"]["radius"])
    assert ((crowd.pos[:, 1] < 0.0) | (crowd.pos[:, 1] > 3.0)).all()
