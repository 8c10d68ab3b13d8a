"""Shared builders: small scenarios written as data, the way a user writes a YAML file."""

import sensors  # noqa: F401  (first: it chooses MuJoCo's OpenGL backend before anything imports mujoco)

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from scenarios import scenario_from_dict

LASERS = [{"name": "front_laser", "mount": [0.25, 0, 0]}, {"name": "rear_laser", "mount": [-0.25, 0, float(np.pi)]}]


def room(walls=None, obstacles=None, **extra) -> dict:
    """A scenario dict: a 40 m x 40 m walled room (unless ``walls`` is given), a parked robot, two lasers, and no
    random force (the checks are analytic)."""
    data = {
        "name": "test_room",
        "crowd": {"random_force": 0.0},
        "map": {"walls": walls if walls is not None else [[[0, 0], [40, 0], [40, 40], [0, 40], [0, 0]]],
                "obstacles": obstacles or []},
        "robot": {"start": [2, 2, 0]},
        "sensors": {"lasers": LASERS},
    }
    data["crowd"].update(extra.pop("crowd", {}))
    data.update(extra)
    return data


@pytest.fixture
def make_scenario():
    def make(**kw):
        return scenario_from_dict(room(**kw), source="<test>")
    return make
