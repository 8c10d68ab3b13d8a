"""People leave the bundled scenarios out of the robot's sight: a person who vanished in the lasers' view would leave
a ghost track coasting on where nobody is. Before the exits were moved behind corners, all 30 passengers who left the
airport in the first 30 s of seed 1 vanished in a laser's line of sight (at the passport booths, the transfer and the
gate corridor's mouths), 19 of them with beams on them; now 20 leave then, none in sight."""

import numpy as np
import pytest

from crowdsim.loop import Simulation
from scenarios import load_scenario
from scenarios.geometry import line_of_sight


def removals(name: str, duration: float) -> tuple[list[dict], Simulation]:
    """Every person gone from one frame to the next: where they were last, the beams the lasers had on them then,
    and whether any laser had a line of sight to their body (its centre or either side, across the ray)."""
    sim = Simulation(load_scenario(name, duration=duration))
    sim.warm_up()
    out, previous = [], None
    n_lasers = len(sim.lasers)
    for frame in sim.frames(duration):
        if previous is not None:
            a = previous.agents
            for row in np.flatnonzero(~np.isin(a.id, frame.agents.id)):
                seen = False
                for laser in sim.lasers:
                    origin = laser.pose_in(previous.robot_pose)[:2]
                    ray = a.position[row] - origin
                    side = np.array([-ray[1], ray[0]]) / np.linalg.norm(ray) * a.radius[row]
                    body = a.position[row] + np.array([[0.0, 0.0], [1.0, 1.0], [-1.0, -1.0]]) * side
                    seen |= bool(line_of_sight(origin, body, sim.walls).any())
                out.append({"position": a.position[row], "beams": np.nansum(previous.visibility.amount[row, :n_lasers]),
                            "line_of_sight": seen})
        previous = frame
    return out, sim


def exits(sim: Simulation) -> np.ndarray:
    """The last stage of every route that ends in a sink (x, y, radius)."""
    sc = sim.scenario
    last = {route["waypoints"][-1] for route in sc["routes"].values() if route["sink"]}
    return np.array([[*sc["waypoints"][w]["position"], sc["waypoints"][w]["radius"]] for w in sorted(last)])


@pytest.mark.parametrize("name, duration, least", [
    # seed 1: 20 and 10 people leave (passers_by and person_following still remove people in view: their change
    # waits until it is measured against issue 12's navigation figures)
    ("airport_disembarkation", 30.0, 15),
    ("airport_follow", 20.0, 6),
])
def test_people_leave_where_no_laser_can_see_them(name, duration, least):
    gone, sim = removals(name, duration)
    assert len(gone) >= least
    where = exits(sim)
    for person in gone:
        assert person["beams"] == 0 and not person["line_of_sight"], person
        # at an exit (within its radius and a step), not somewhere on the way
        assert (np.hypot(*(where[:, :2] - person["position"]).T) <= where[:, 2] + 0.1).any(), person
