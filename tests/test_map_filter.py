"""The static-map filter (seed 000 Sec. V-C): the occupancy grid made from walls and obstacles, detections on it
dropped, the tracking frame placed on the map through the localisation, and the filter in the loop."""

import numpy as np
import pytest
from conftest import room

from crowdsim.loop import Simulation
from pipeline.map_filter import MapFilter, disc_counts, occupancy_grid
from pipeline.types import DetectedPersons
from scenarios import scenario_from_dict
from scenarios.geometry import closest_on_segments, wall_segments

SQUARE = [[[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]]]  # a 4 m room's walls
SEGMENTS = wall_segments({"map": {"walls": SQUARE, "obstacles": []}})


def centres(origin, shape, resolution):
    """Every cell's centre [rows, columns, 2] (world)."""
    cols, rows = np.meshgrid(np.arange(shape[1]), np.arange(shape[0]))
    return origin + (np.stack([cols, rows], -1) + 0.5) * resolution


def detections(xy, frame="odom"):
    n = len(xy)
    position = np.column_stack([np.asarray(xy, float).reshape(n, 2), np.zeros(n)])
    return DetectedPersons(1.0, frame, "laser2d", np.arange(n), position, np.tile(0.1 * np.eye(3), (n, 1, 1)),
                           np.ones(n))


def test_a_map_of_walls_only_keeps_detections_on_its_obstacles():
    from pipeline.assemble import build_pipeline
    from scenarios.format import PIPELINE
    from scenarios.schema import validate

    pillar = [[1.0, 1.0], [1.8, 1.0], [1.8, 1.8], [1.0, 1.8]]
    plan = {"walls": SQUARE, "obstacles": [pillar]}
    on = np.array([[1.4, 1.4], [0.02, 2.0], [2.5, 2.5]])  # on the pillar, on the west wall, in the room
    for obstacles, kept in ((True, [False, False, True]), (False, [True, False, True])):
        spec = validate({"map_filter": {"obstacles": obstacles}}, PIPELINE, "<test>", "pipeline")
        assert build_pipeline(spec, ["laser"], plan).map_filter.keep(on).tolist() == kept


def test_a_square_rooms_grid_has_its_walls_occupied_and_its_inside_free():
    occupied, origin = occupancy_grid(SQUARE, [], 0.1, 0.3)
    c = centres(origin, occupied.shape, 0.1)
    wall = closest_on_segments(c.reshape(-1, 2), SEGMENTS)[1].min(axis=1).reshape(occupied.shape)
    # the walls run through the middle of cells: those cells, and no others, are occupied
    np.testing.assert_array_equal(occupied, wall < 0.05)
    assert occupied.sum() == 4 * 40  # 41 cells along each wall, the corners shared
    inside = (c > 0.05).all(axis=-1) & (c < 3.95).all(axis=-1)
    assert inside.sum() == 39 * 39 and not occupied[inside].any()
    assert ((c.reshape(-1, 2).min(axis=0) < -0.3) & (c.reshape(-1, 2).max(axis=0) > 4.3)).all()  # the margin


def test_obstacles_are_solid():
    pillar = [[1.0, 1.0], [1.8, 1.0], [1.8, 1.8], [1.0, 1.8]]
    f = MapFilter([], [pillar], resolution=0.1, inflation=0.0)
    assert not f.keep(np.array([[1.4, 1.4], [1.05, 1.75]])).any()  # its middle and inside a corner
    assert f.keep(np.array([[2.0, 1.4], [0.8, 0.8]])).all()
    assert f.keep(np.array([[-100.0, 1.4], [1.4, 100.0], [1e6, -1e6]])).all()  # off the grid: nothing known there


def test_detections_near_a_wall_are_dropped_and_those_in_the_room_kept():
    # seed 000's rule: a 15 cm circle with more than 10% of it occupied; 0.1 m from the wall, 5 of its 29 cells are
    seed000 = MapFilter(SQUARE, [])
    xy = np.array([[0.1, 2.0], [2.0, 3.9], [2.0, 2.0], [0.2, 2.0]])
    np.testing.assert_array_equal(seed000.keep(xy), [False, False, True, True])
    # any occupied cell within 0.25 m: 0.2 m from the wall is dropped too, 0.3 m kept
    inflated = MapFilter(SQUARE, [], inflation=0.25, max_occupied=0.0)
    np.testing.assert_array_equal(inflated.keep(np.array([[0.2, 2.0], [0.3, 2.0], [2.0, 2.0]])), [False, True, True])
    # blocked cells are exactly those within the inflation of a wall
    c = centres(inflated.origin, inflated.blocked.shape, inflated.resolution)
    wall = closest_on_segments(c.reshape(-1, 2), SEGMENTS)[1].min(axis=1).reshape(c.shape[:2])
    np.testing.assert_array_equal(inflated.blocked, wall <= 0.25 + 1e-9)
    # a batch keeps its kept rows' ids, positions and covariances; beyond the grid nothing is known: kept
    kept = seed000.filter(detections([[0.1, 2.0], [2.0, 2.0], [-5.0, 2.0]]), np.zeros(3))
    np.testing.assert_array_equal(kept.detection_id, [1, 2])
    np.testing.assert_array_equal(kept.position[:, :2], [[2.0, 2.0], [-5.0, 2.0]])
    assert kept.covariance.shape == (2, 3, 3) and kept.frame == "odom"


def test_detections_in_odom_are_looked_up_through_the_localisation():
    # odom sits at (2, 3) in the world, turned by +90 degrees: odom (x, y) is world (2 - y, 3 + x)
    f = MapFilter([[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]], [])
    world_T_odom = np.array([2.0, 3.0, np.pi / 2])
    odom = np.array([
        [2.0, -7.95],  # world (9.95, 5): on the east wall
        [7.0, -3.0],  # world (5, 10): on the north wall
        [2.0, -3.0],  # world (5, 5): the room's middle
        [5.0, 0.0],  # world (2, 8): free, though odom (5, 0) read as world lies on the south wall
    ])
    np.testing.assert_array_equal(f.filter(detections(odom), world_T_odom).detection_id, [2, 3])
    np.testing.assert_array_equal(f.filter(detections(odom), np.zeros(3)).detection_id, [0, 1, 2])


class Ahead:
    """A detector that finds one person ``distance`` metres straight ahead of its laser, whatever the scan shows."""

    def __init__(self, distance: float = 2.0):
        self.distance = distance

    def reset(self):
        pass

    def detect(self, scan):
        return DetectedPersons(scan.stamp, scan.frame, "test", np.zeros(1, np.int64), np.array([[self.distance, 0, 0]]),
                               0.01 * np.eye(3)[None], np.ones(1))


@pytest.mark.parametrize("map_filter", [None, {}])
def test_the_loop_drops_each_detectors_detections_on_the_map_before_fusion(map_filter):
    # the parked robot at (5, 5) facing +x: its front laser's detection (7.25, 5) lies in a pillar, its rear
    # laser's (2.75, 5) in the room; odom is the start pose, so they read (2.25, 0) and (-2.25, 0) there
    pillar = [[7.0, 4.8], [7.5, 4.8], [7.5, 5.2], [7.0, 5.2]]
    sc = scenario_from_dict(room(obstacles=[pillar], robot={"start": [5, 5, 0]},
                                 pipeline={"detector": {"type": "test_map_filter:Ahead"}, "map_filter": map_filter}))
    sim = Simulation(sc)
    assert (sim.pipeline.map_filter is None) == (map_filter is None)
    frames = list(sim.frames(0.2))
    assert len(frames) == 5
    for frame in frames:
        expected = [[-2.25, 0.0]] if map_filter is not None else [[2.25, 0.0], [-2.25, 0.0]]
        np.testing.assert_allclose(np.sort(frame.detections.position[:, :2], axis=0), np.sort(expected, axis=0),
                                   atol=1e-9)
        assert len(frame.detector_outputs["front_laser"]) == (0 if map_filter is not None else 1)


def test_disc_counts_by_hand():
    # a plus-shaped disc (half widths 0, 1, 0) round each cell of a 3 x 4 grid with cells (0, 0) and (1, 2) set:
    # a cell counts the set cells among itself and its four neighbours; off the grid counts nothing
    grid = np.zeros((3, 4), bool)
    grid[0, 0] = grid[1, 2] = True
    assert disc_counts(grid, np.array([0, 1, 0])).tolist() == [[1, 1, 1, 0],
                                                               [1, 1, 1, 1],
                                                               [0, 0, 1, 0]]
    # a 3 x 3 square (half widths 1, 1, 1): the centre cell of the set pair's neighbourhood counts both
    assert disc_counts(grid, np.array([1, 1, 1]))[1, 1] == 2
