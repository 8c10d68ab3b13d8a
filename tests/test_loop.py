"""The whole loop on the bundled airport: bit-for-bit determinism, ground-truth invariants, frames and scoring."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from crowdsim.groundtruth import GT_MARGIN
from crowdsim.loop import Simulation
from crowdsim.run import run
from pipeline.frames import compose, inverse, transform_points, wrap_angle
from scenarios import load_scenario
from scenarios.geometry import closest_on_segments, line_of_sight
from crowdsim.scoring import score_cycles


def airport(duration=4.0, warmup=20.0, seed=1):
    return load_scenario("airport_disembarkation", duration=duration, warmup=warmup, seed=seed)


def test_same_seed_same_run_bit_for_bit(tmp_path):
    a = run(airport(), tmp_path / "A", progress=False)
    b = run(airport(), tmp_path / "B", progress=False)
    assert a["tracking"] == b["tracking"]
    for name in ("groundtruth.csv", "tracks.csv", "visibility.csv"):
        assert (tmp_path / "A" / name).read_bytes() == (tmp_path / "B" / name).read_bytes()
    c = run(airport(seed=2), tmp_path / "C", progress=False)
    assert (tmp_path / "A" / "groundtruth.csv").read_bytes() != (tmp_path / "C" / "groundtruth.csv").read_bytes()
    assert c["seed"] == 2


def test_airport_groundtruth_invariants():
    sim = Simulation(airport(duration=6.0, warmup=40.0))
    sim.warm_up()
    counts = []
    for frame in sim.frames(6.0):
        a = frame.agents
        _, d = closest_on_segments(a.position, sim.walls)
        assert (d - a.radius[:, None]).min() >= -1e-9, "a person is inside a wall"
        pairs = cKDTree(a.position).query_pairs(0.6, output_type="ndarray")
        gap = np.linalg.norm(a.position[pairs[:, 0]] - a.position[pairs[:, 1]], axis=1)
        assert (a.radius[pairs[:, 0]] + a.radius[pairs[:, 1]] - gap <= 0.10).all(), "two persons overlap > 10 cm"
        gt, tags = frame.groundtruth, frame.gt_tags
        world = transform_points(frame.world_T_odom, gt.position)
        distance = np.linalg.norm(world - frame.robot_pose[:2], axis=1)
        assert distance.max() <= 20.0 + GT_MARGIN
        np.testing.assert_allclose(tags.range, distance, atol=1e-9)
        np.testing.assert_array_equal(tags.in_range, distance <= 20.0)
        # nobody a wall hides from every laser (the body's centre and its edges 0.25 m round it) is hit by a beam
        hidden = np.ones(len(world), bool)
        for laser in sim.lasers:
            origin = laser.pose_in(frame.robot_pose)[:2]
            for dx, dy in ((0, 0), (0.25, 0), (-0.25, 0), (0, 0.25), (0, -0.25)):
                hidden &= ~line_of_sight(origin, world + [dx, dy], sim.walls)
        assert not tags.visible[hidden].any()
        np.testing.assert_array_equal(tags.visible, tags.beams > 0)
        counts.append(int(tags.in_range.sum()))
    # the flow is under way after the warm-up: tens of persons around the robot (seed 000 Table I: 78.6 on average)
    assert np.mean(counts) > 40


def test_tracking_frame_and_score_are_consistent():
    sim = Simulation(airport(duration=3.0))
    sim.warm_up()
    frames = list(sim.frames(3.0))
    assert len(frames) == 75  # two lasers at 25 Hz share one tracking cycle per scan pair
    f = frames[-1]
    assert f.tracks.frame == f.groundtruth.frame == f.detections.frame == "odom"
    # perfect odometry: odom stays where the robot started
    assert np.allclose(f.world_T_odom, sim.scenario["robot"]["start"])
    summary = score_cycles(frames, sim.scenario["evaluation"]["threshold"])
    assert summary.frames == 75
    # the ground truth that counts: in range and hit by a beam
    assert summary.gt == sum(int((~fr.gt_tags.ignore).sum()) for fr in frames)
    # every track is a match, a false positive, or matched to an ignored person (within the threshold of one)
    ignored = 0
    for fr in frames:
        d = np.linalg.norm(fr.tracks.position[:, None] - fr.groundtruth.position[None, fr.gt_tags.ignore], axis=2)
        ignored += int((d <= 1.0).any(axis=1).sum()) if d.size else 0
    free = summary.fp + summary.matches
    assert free <= sum(len(fr.tracks) for fr in frames) <= free + ignored


def test_frames_compose_and_invert():
    a = np.array([1.0, 2.0, 0.5])
    b = np.array([-0.3, 0.7, 2.9])
    assert np.allclose(compose(a, inverse(a)), 0.0, atol=1e-12)
    ab = compose(a, b)
    # the point (1, 0) of frame b, moved through a*b, equals moving it through b then a
    p = np.array([[1.0, 0.0]])
    assert np.allclose(transform_points(ab, p), transform_points(a, transform_points(b, p)))
    assert ab[2] == pytest.approx(wrap_angle(3.4))
    assert wrap_angle(np.pi) == pytest.approx(np.pi) and wrap_angle(-np.pi) == pytest.approx(np.pi)


def test_reset_reruns_bit_for_bit_with_ids_from_one():
    def groundtruth(sim):
        sim.warm_up()
        return [(f.groundtruth.track_id.copy(), f.groundtruth.position.copy()) for f in sim.frames(1.0)]

    sim = Simulation(airport(duration=1.0, warmup=8.0))
    first = groundtruth(sim)
    sim.reset(seed=7)
    other = groundtruth(sim)
    assert sim.seed == 7 and sim.crowd.id.min() >= 1
    sim.reset()
    again = groundtruth(sim)
    fresh = groundtruth(Simulation(airport(duration=1.0, warmup=8.0)))
    for a, b, c in zip(first, again, fresh):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
        assert np.array_equal(a[0], c[0]) and np.array_equal(a[1], c[1])
    assert any(len(a[0]) != len(o[0]) or not np.array_equal(a[1], o[1]) for a, o in zip(first, other))
    assert min(first[0][0]) == 1  # ids restart at 1 after a reset


def camera_room(seed=4, change=lambda data: None):
    """A 14 m x 10 m room with a source, two lasers, a front Kinect-like camera at 15 Hz and a wall camera at 10 Hz;
    ``change`` changes its data before it is loaded."""
    from scenarios import scenario_from_dict

    data = {
        "name": "camera_room", "seed": seed, "warmup": 3.0, "duration": 2.0,
        "map": {"walls": [[[0, 0], [14, 0], [14, 10], [0, 10], [0, 0]]]},
        "waypoints": {"east": {"position": [12, 5], "radius": 1.0}},
        "routes": {"across": {"waypoints": ["east"]}},
        "sources": [{"position": [2, 5], "size": [1, 4], "rate": 2.0, "routes": {"across": 1.0}}],
        "standing": [{"position": [7, 8], "count": 3}],
        "robot": {"start": [6, 2, 1.5708]},
        "sensors": {"lasers": [{"name": "front_laser", "mount": [0.25, 0, 0]},
                               {"name": "rear_laser", "mount": [-0.25, 0, 3.14159]}],
                    "depth_cameras": [{"name": "front_depth", "preset": "kinect_160", "rate": 15.0}],
                    "wall_cameras": [{"name": "corner_cam", "position": [0.3, 0.3, 2.8], "yaw": 0.6, "pitch": 0.45}]},
    }
    change(data)
    return scenario_from_dict(data, source="<test>")


def test_cameras_run_at_their_rates_and_report_who_they_saw():
    sim = Simulation(camera_room())
    sim.warm_up()
    frames = list(sim.frames(2.0))
    assert len(frames) == 50  # the lasers' 25 Hz sets the tracking cycles
    depth = [d for f in frames for d in f.depth_frames]
    wall = [c for f in frames for c in f.camera_frames]
    # due at 3.0 + k / 15 and 3.0 + k / 10 s (the warm-up ends at 3 s), taken at the first 0.04 s tick at or after:
    # k = 0 .. 30 and 0 .. 20 up to 5 s
    assert len(depth) == 31 and len(wall) == 21
    assert all(0 <= d.stamp - (3.0 + k / 15) < 0.04 + 1e-9 for k, d in enumerate(depth))
    assert depth[0].depth.shape == (120, 160) and wall[0].rgb.shape == (240, 320, 3)
    # the depth frames carry their calibration: through their pose, the points on the floor lie at z = 0 in odom
    # (the robot stands on it), the rest up to the 2.5 m walls (Kinect noise: a few cm at 5 m)
    d = depth[-1]
    odom = d.points @ d.pose[:3, :3].T + d.pose[:3, 3]
    floor = odom[:, 2] < 0.2
    assert floor.mean() > 0.2 and abs(np.median(odom[floor, 2])) < 0.01
    assert (odom[:, 2] > -0.2).all() and (odom[:, 2] < 2.7).all()
    uv = d.points @ d.camera_matrix.T
    pixels = np.floor(uv[:, :2] / uv[:, 2:]).astype(int)
    assert np.array_equal(pixels[:, ::-1], np.argwhere(np.isfinite(d.depth)))  # each point in its own pixel
    last = frames[-1].visibility
    assert last.sensors == ["front_laser", "rear_laser", "front_depth", "corner_cam"]
    assert np.array_equal(last.ids, frames[-1].agents.id)
    beams = last.amount[:, :2]
    assert (beams[~last.in_view[:, :2]] == 0).all()  # no beam hits a person outside the laser's field of view
    # a person whose middle is out of the image shows at most the part inside it
    assert (last.amount[~last.in_view[:, 3], 3] < 0.6).all()
    assert last.occluded.shape == last.amount.shape
    assert (last.amount[:, 3] > 0).sum() >= 3  # the corner camera sees people


def test_cameras_go_on_when_everyone_has_left():
    # four people walk from the room's middle to a sink 4 m away: once the last has left, the cameras' latest
    # frames still list who they saw, and the cycles go on with nobody
    scenario = camera_room(change=lambda data: data.update(
        waypoints={"exit": {"position": [12.0, 8.0], "radius": 1.0}},
        routes={"out": {"waypoints": ["exit"], "sink": True}}, sources=[], standing=[],
        clusters=[{"position": [8.0, 8.0], "count": 4, "spread": [1.0, 1.0], "route": "out",
                   "agent_type": "adult", "group_size_weights": [0.0, 1.0]}], warmup=0.0))
    sim = Simulation(scenario)
    frames = list(sim.frames(8.0))
    alive = [len(f.agents.id) for f in frames]
    assert alive[0] == 4 and alive[-1] == 0
    assert max(f.visibility.amount[:, 3].max(initial=0) for f in frames) > 0  # the corner camera saw them
    empty = [f for f in frames if not len(f.agents.id)]
    assert len(empty) > 25 and all(f.visibility.amount.shape == (0, 4) and not len(f.groundtruth) for f in empty)


def test_camera_runs_are_bit_for_bit_repeatable():
    images = []
    for _ in range(2):
        sim = Simulation(camera_room())
        sim.warm_up()
        images.append([d.depth.tobytes() for f in sim.frames(0.6) for d in f.depth_frames])
    assert len(images[0]) == 10  # k / 15 <= 0.6 s for k = 0 .. 9
    assert images[0] == images[1]


@pytest.mark.filterwarnings("error")  # rerun warns, and drops the entity, where a log call is malformed
def test_the_recording_holds_the_camera_images_boxes_and_the_robots_frames(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    sc = camera_room().replace(duration=0.4)
    run(sc, tmp_path / "out", rrd=True, progress=False)
    rerun_cli = Path(sys.executable).parent / "rerun"  # the viewer's command line, installed with rerun-sdk
    listing = subprocess.run([str(rerun_cli), "rrd", "print", str(tmp_path / "out" / "recording.rrd")],
                             capture_output=True, text=True, check=True).stdout
    for entity in ("/cameras/front_depth/depth", "/cameras/front_depth/people", "/cameras/corner_cam/rgb",
                   "/cameras/corner_cam/rgb/people", "/cameras/corner_cam/segmentation", "Pinhole",
                   "/world/laser_points", "/world/tracks", "/world/robot/base_link", "/world/robot/sensors",
                   "/world/wall_cameras", "/world/odom", "/world/groups", "/world/groups/id"):
        assert entity in listing, entity


def test_lasers_at_different_rates_keep_their_latest_scan():
    # a front laser at 12.5 Hz and a rear one at 25 Hz: the front one scans every other cycle; between its scans
    # its visibility is its latest scan's, not "everyone in view occluded"
    def two_lasers(data):
        data["sensors"]["depth_cameras"], data["sensors"]["wall_cameras"] = [], []
        data["sensors"]["lasers"][0]["rate"] = 12.5

    sim = Simulation(camera_room(change=two_lasers))
    sim.warm_up()
    frames = list(sim.frames(0.4))
    # both due at the end of the warm-up (3 s), scanned at the first tick after it; then the front every 0.08 s
    assert [[s.frame for s in f.scans] for f in frames] == [["front_laser", "rear_laser"]] * 2 + [
        ["rear_laser"], ["front_laser", "rear_laser"]] * 4
    for previous, f in zip(frames, frames[1:]):
        front = next(s for s in (f.scans if len(f.scans) == 2 else previous.scans) if s.frame == "front_laser")
        beams = np.array([(front.person_id == i).sum() for i in f.visibility.ids])
        assert beams.sum() > 0  # the robot faces the walkers and the standing group
        np.testing.assert_array_equal(f.visibility.of("front_laser"), beams)
        k = f.visibility.sensors.index("front_laser")
        np.testing.assert_array_equal(f.visibility.occluded[:, k], f.visibility.in_view[:, k] & (beams == 0))
