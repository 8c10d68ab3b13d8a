"""The pipeline assembled from the scenario: built-in parts by type, a user's classes by ``module:Class`` (the
classes below, named as ``test_assemble:...``: pytest puts tests/ on the path), detectors attached to sensors by
name, old files unchanged, and one clear error for every wrong part or parameter."""

import numpy as np
import pytest
import yaml
from conftest import LASERS, room

from crowdsim.loop import Simulation
from crowdsim.run import run
from pipeline.assemble import DETECTORS, TRACKERS, Detector, Fusion, GroupStage, Tracker, build_pipeline
from pipeline.detectors.laser_segments import SegmentDetector
from pipeline.fusion import NearestFusion
from pipeline.frames import compose, inverse, transform_points
from pipeline.tracking.deletion import FixedDeletion
from pipeline.tracking.nnt import NearestNeighbourTracker
from pipeline.types import DetectedPersons, TrackedPersons
from scenarios import ScenarioError, load_scenario, scenario_from_dict
from scenarios.typed import as_written, plain
from scenarios.format import DETECTOR, DETECTOR_READS, FUSION, GROUP_STAGE, GROUP_STAGE_TYPES, TRACKER, TRACKER_TYPES
from scenarios.schema import Field, Schema
from crowdsim.scoring import score_cycles


class EchoTracker:
    """Every detection a confirmed track of its own (id: the detection's + 1), moved by ``shift``."""

    def __init__(self, shift=(0.0, 0.0)):
        self.shift = np.asarray(shift, float)
        self.resets = 0

    def reset(self):
        self.resets += 1

    def update(self, stamp, detections):
        n, ids = len(detections), detections.detection_id
        zeros = np.zeros((n, 2, 2))
        return TrackedPersons(stamp, detections.frame, ids + 1, np.ones(n, bool), np.zeros(n, bool), ids.copy(),
                              detections.position[:, :2] + self.shift, np.zeros((n, 2)), zeros, zeros.copy(),
                              np.zeros(n))


class SchemaTracker(EchoTracker):
    """The same, its parameters checked (and filled) by a schema of its own."""

    SCHEMA = Schema({"shift": Field("point", [0.25, 0.0], doc="m")})


class NeedsGain(EchoTracker):
    def __init__(self, gain):
        super().__init__()


class OneAhead:
    """A detector that finds one person ``distance`` metres along its sensor's axis (x for a laser, the optical z
    for a camera), whatever the frame shows; it keeps the frames it was given."""

    def __init__(self, distance: float = 2.0):
        self.distance = distance
        self.frames = []
        self._next_id = 0

    def reset(self):
        self.frames, self._next_id = [], 0

    def detect(self, frame):
        self.frames.append(frame)
        xyz = [0.0, 0.0, self.distance] if hasattr(frame, "rgb") else [self.distance, 0.0, 0.0]
        self._next_id += 1
        return DetectedPersons(frame.stamp, frame.frame, "test", np.array([self._next_id - 1]), np.array([xyz]),
                               0.01 * np.eye(3)[None], np.ones(1))


class NearAndFar(OneAhead):
    """Two kinds of detection from one frame, as named batches: one person 1 m ahead, one 3 m ahead."""

    def detect(self, frame):
        near, far = OneAhead(1.0), OneAhead(3.0)
        return {"near": near.detect(frame), "far": far.detect(frame)}


def walkers(pipeline=None, **extra) -> dict:
    """The conftest room with people ahead of the parked robot (at (2, 2), facing +x): a standing group and a flow."""
    return room(waypoints={"east": {"position": [30, 6]}}, routes={"across": {"waypoints": ["east"]}},
                sources=[{"position": [5, 6], "size": [1, 2], "rate": 2.0, "routes": {"across": 1.0}}],
                standing=[{"position": [6, 2], "count": 3}], warmup=2.0, duration=1.0, pipeline=pipeline or {},
                **extra)


def load(tmp_path, data) -> dict:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_scenario(str(path))


# --- registries --------------------------------------------------------------------------------------------------

def test_the_format_and_assemble_name_the_same_types_with_the_same_defaults():
    assert set(DETECTOR_READS) == set(DETECTORS)  # the sensors every built-in detector reads
    assert set(TRACKER_TYPES) == set(TRACKERS)
    # the methods the format asks of a class of one's own are the interfaces'
    for typed, protocol in ((DETECTOR, Detector), (FUSION, Fusion), (TRACKER, Tracker), (GROUP_STAGE, GroupStage)):
        assert set(typed.methods) == {m for m in vars(protocol) if not m.startswith("_")}


# --- today's files, today's parts --------------------------------------------------------------------------------

def test_old_keys_give_todays_parts_and_the_resolved_section_reloads_equal(tmp_path):
    old = {"detector": {"jump_distance": 0.5}, "fusion_distance": 0.3, "tracker": {"n_delete": 25}}
    sc = load(tmp_path, walkers(old))
    assert sc["pipeline"] == {
        "detector": {"type": "laser_segments", "jump_distance": 0.5, "min_points": 3, "min_width": 0.1,
                     "max_width": 0.9, "min_bulge": 0.03, "position_variance": 0.1},
        "detectors": {},
        "cycle": "lasers",
        "fusion": {"type": "nearest", "distance": 0.3},
        "map_filter": None,
        "groups": {"type": "coherent_motion",
                   **{k: f.default for k, f in GROUP_STAGE_TYPES["coherent_motion"].fields.items()}},
        "tracker": {"type": "nnt", "motion": {"type": "cv", "process_noise": 0.267},  # its parts' defaults
                    "association": {"type": "greedy", "gate_chi2": 13.82},
                    "initiation": {"type": "none", "n_confirm": 3, "initial_velocity_variance": 1.0},
                    "deletion": {"type": "fixed", "n_delete": 25, "tentative": 2}, "duplicates": None}}
    parts = build_pipeline(sc["pipeline"], ["front_laser", "rear_laser"])
    front, rear = parts.detectors["front_laser"], parts.detectors["rear_laser"]
    assert type(front) is type(rear) is SegmentDetector and front is not rear  # each laser its own ids
    assert (front.jump_distance, front.min_points) == (0.5, 3)
    assert type(parts.fusion) is NearestFusion and parts.fusion.distance == 0.3
    assert type(parts.tracker) is NearestNeighbourTracker and parts.tracker.frame == "odom"
    assert parts.tracker.deletion == FixedDeletion(n_delete=25)
    # what `crowdsim run` writes as scenario.yaml loads to the same scenario
    again = load(tmp_path, {k: v for k, v in as_written(sc).items() if k != "source"})
    assert again == sc


def test_a_user_tracker_runs_in_the_loop_and_is_scored(tmp_path):
    sc = scenario_from_dict(walkers({"tracker": {"type": "test_assemble:EchoTracker", "shift": [0.5, -0.25]}}))
    assert plain(sc.pipeline.tracker) == {"type": "test_assemble:EchoTracker", "shift": [0.5, -0.25]}
    sim = Simulation(sc)
    tracker = sim.pipeline.tracker
    assert type(tracker).__name__ == "EchoTracker" and tracker.resets == 1
    sim.warm_up()
    frames = list(sim.frames(1.0))
    assert len(frames) == 25 and sum(len(f.detections) for f in frames) > 50
    for f in frames:
        np.testing.assert_array_equal(f.tracks.track_id, f.detections.detection_id + 1)
        np.testing.assert_array_equal(f.tracks.position, f.detections.position[:, :2] + [0.5, -0.25])
    assert score_cycles(frames, sc["evaluation"]["threshold"]).frames == 25
    sim.reset(seed=5)
    assert sim.pipeline.tracker is tracker and tracker.resets == 2  # made once, started over
    # the run writes what it produced, and its scenario.yaml runs it again
    out = run(sc, tmp_path / "A", progress=False)
    tracks = np.loadtxt(tmp_path / "A" / "tracks.csv", delimiter=",", skiprows=1)
    detections = np.loadtxt(tmp_path / "A" / "detections.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(tracks[:, :3], detections[:, :3] + [0, 0, 1])
    np.testing.assert_allclose(tracks[:, 3:5], detections[:, 3:5] + [0.5, -0.25], atol=1e-6)
    assert out["tracking"]["frames"] == sc["duration"] * 25
    again = load_scenario(str(tmp_path / "A" / "scenario.yaml"))
    assert again["pipeline"] == sc["pipeline"]


def test_a_user_class_with_a_schema_gets_its_defaults():
    sc = scenario_from_dict(walkers({"tracker": {"type": "test_assemble:SchemaTracker"}}))
    assert plain(sc.pipeline.tracker) == {"type": "test_assemble:SchemaTracker", "shift": [0.25, 0.0]}
    np.testing.assert_array_equal(Simulation(sc).pipeline.tracker.shift, [0.25, 0.0])


def test_a_user_detector_attached_to_a_laser_by_name_reads_that_lasers_scans():
    sc = scenario_from_dict(walkers({"detectors": {"rear_laser": {"type": "test_assemble:OneAhead"}},
                                     "fusion": {"distance": 0.0}}))  # nothing fused: each detection stays itself
    sim = Simulation(sc)
    detector = sim.pipeline.detectors["rear_laser"]
    assert type(sim.pipeline.detectors["front_laser"]) is SegmentDetector  # `detector` still holds for the other
    sim.warm_up()
    frames = list(sim.frames(0.4))
    assert len(frames) == 10
    assert [s.frame for s in detector.frames] == ["rear_laser"] * 10
    for f, scan in zip(frames, detector.frames):
        assert scan is next(s for s in f.scans if s.frame == "rear_laser")
        # the one detection 2 m along the rear laser's axis, in odom: the laser (-0.25, 0, pi) on the odometry pose
        odom_pose = compose(inverse(f.world_T_odom), f.robot_pose)
        expected = transform_points(compose(odom_pose, np.array([-0.25, 0.0, np.pi])), np.array([[2.0, 0.0]]))
        rows = f.detections.originals["rear_laser"] >= 0
        assert rows.sum() == 1 and (f.detections.originals["front_laser"][rows] == -1).all()
        np.testing.assert_allclose(f.detections.position[rows, :2], expected, atol=1e-12)
        assert (f.detections.originals["front_laser"] >= 0).sum() == len(f.detections) - 1
    sim.reset()
    assert detector.frames == []


def test_a_detector_on_a_camera_reads_its_images_and_its_detections_reach_odom():
    # the parked robot at (2, 2) facing +x; odom is that pose. The front camera at (0.45, 0, 1.45) in base_link,
    # pitched down 0.15: 3 m along its axis is (0.45 + 3 cos 0.15, 0, 1.45 - 3 sin 0.15) in odom. The wall camera at
    # (0.5, 0.5, 3) in the world, yaw 0.6, pitch 0.4: 5 m along its axis is (0.5, 0.5, 3) + 5 (cos 0.4 cos 0.6,
    # cos 0.4 sin 0.6, -sin 0.4) in the world, less (2, 2) in odom
    sensors = {"lasers": LASERS,
               "depth_cameras": [{"name": "front_depth", "preset": "kinect_160", "pitch": 0.15}],
               "wall_cameras": [{"name": "corner_cam", "position": [0.5, 0.5, 3.0], "yaw": 0.6, "pitch": 0.4,
                                 "width": 64, "height": 48, "rgb": False}]}
    pipeline = {"detectors": {"front_depth": {"type": "test_assemble:OneAhead", "distance": 3.0},
                              "corner_cam": {"type": "test_assemble:OneAhead", "distance": 5.0}},
                "fusion": {"distance": 0.0}}
    sim = Simulation(scenario_from_dict(walkers(pipeline, sensors=sensors)))
    sim.warm_up()
    frames = list(sim.frames(0.5))
    expected = {"front_depth": [0.45 + 3 * np.cos(0.15), 0.0, 1.45 - 3 * np.sin(0.15)],
                "corner_cam": [0.5 + 5 * np.cos(0.4) * np.cos(0.6) - 2, 0.5 + 5 * np.cos(0.4) * np.sin(0.6) - 2,
                               3 - 5 * np.sin(0.4)]}
    for name, kind, images in (("front_depth", "DepthFrame", 8), ("corner_cam", "CameraFrame", 5)):
        detector = sim.pipeline.detectors[name]
        assert [(type(d).__name__, d.frame) for d in detector.frames] == [(kind, name)] * images
        seen = [f.detections.position[f.detections.originals[name] >= 0] for f in frames if name in
                f.detections.originals]
        assert len(seen) == images  # each image's detection reaches the next tracking cycle
        np.testing.assert_allclose(np.concatenate(seen), [expected[name]] * images, atol=1e-7)
    # a wall camera's images carry its calibration: K (f = 24 / tan(22.5 deg) for 48 rows at 45 degrees) and the
    # optical frame in odom, which puts 5 m along the axis where the detections went
    for image in sim.pipeline.detectors["corner_cam"].frames:
        np.testing.assert_allclose(image.camera_matrix, [[24 / np.tan(np.radians(22.5)), 0, 32],
                                                         [0, 24 / np.tan(np.radians(22.5)), 24], [0, 0, 1]])
        np.testing.assert_allclose((image.pose @ [0, 0, 5, 1])[:3], expected["corner_cam"], atol=1e-7)


class Seeing:
    """A tracker that keeps the images it is shown and gives no tracks."""

    def __init__(self):
        self.reset()

    def reset(self):
        self.images = []

    def see(self, frames):
        self.images += [(type(f).__name__, f.frame, f.stamp) for f in frames]

    def update(self, stamp, detections):
        return TrackedPersons.empty(stamp, detections.frame)


def test_a_depth_camera_can_start_the_cycles_and_a_sensor_can_go_without_a_detector():
    # the camera at 12.5 Hz (every other 0.04 s tick) starts every cycle; the lasers still scan but have no
    # detector, so each cycle's detections are the camera's one, and the tracker sees each image once, at its cycle
    sensors = {"lasers": LASERS, "depth_cameras": [{"name": "side", "preset": "kinect_160", "rate": 12.5}]}
    pipeline = {"detectors": {"front_laser": None, "rear_laser": None,
                              "side": {"type": "test_assemble:OneAhead", "distance": 3.0}},
                "cycle": "side", "tracker": {"type": "test_assemble:Seeing"}}
    sim = Simulation(scenario_from_dict(walkers(pipeline, sensors=sensors)))
    assert set(sim.pipeline.detectors) == {"side"}
    sim.warm_up()
    frames = list(sim.frames(1.0))
    assert len(frames) == 13 and len(sim.pipeline.detectors["side"].frames) == 13  # 2.04 s to 3.0 s
    np.testing.assert_allclose([f.stamp for f in frames], [2.04, *np.arange(2.08, 3.0, 0.08)], atol=1e-9)
    for f in frames:
        assert list(f.detections.originals) == ["side"] and len(f.detections) == 1
        assert [d.stamp for d in f.depth_frames] == [f.stamp]
    assert sim.pipeline.tracker.images == [("DepthFrame", "side", f.stamp) for f in frames]
    with pytest.raises(ScenarioError, match=r"pipeline\.cycle.*'rear'; expected lasers or a depth camera's name: "
                                            r"lasers, side"):
        scenario_from_dict(walkers({**pipeline, "cycle": "rear"}, sensors=sensors))


def test_a_detectors_named_batches_reach_the_fusion_as_sensor_slash_name():
    # the parked robot at (2, 2) facing +x with odom on it; the front laser at (0.25, 0) in base_link: the near
    # batch's person at x = 1.25, the far one's at 3.25 in odom, each kept apart by the fusion (distance 0)
    pipeline = {"detectors": {"front_laser": {"type": "test_assemble:NearAndFar"}}, "fusion": {"distance": 0.0}}
    sim = Simulation(scenario_from_dict(walkers(pipeline)))
    sim.warm_up()
    frame = next(iter(sim.frames(0.2)))
    assert {"front_laser/near", "front_laser/far"} <= set(frame.detector_outputs)
    fused = frame.detections
    for name, x in (("front_laser/near", 1.25), ("front_laser/far", 3.25)):
        rows = fused.originals[name] >= 0
        np.testing.assert_allclose(fused.position[rows, :2], [[x, 0.0]], atol=1e-9)


# --- errors: one, naming the file and the key --------------------------------------------------------------------

@pytest.mark.parametrize("pipeline, key, words", [
    ({"tracker": {"type": "nn"}}, "pipeline.tracker.type",
     ["expected one of nnt, mht, rjmcmc, rgbd or module.path:ClassName", "'nn'"]),
    ({"tracker": {"gate": 9.0}}, "pipeline.tracker.gate",
     ["unknown key; expected one of: type, motion, association, initiation, deletion, duplicates"]),
    ({"tracker": {"type": "test_assemble:EchoTracker", "gain": 2}}, "pipeline.tracker.gain",
     ["unknown key; expected one of: type, shift (the parameters of test_assemble:EchoTracker)"]),
    ({"tracker": {"type": "test_assemble:NeedsGain"}}, "pipeline.tracker",
     ["test_assemble:NeedsGain cannot be made from these parameters", "'gain'"]),
    ({"tracker": {"type": "test_assemble:SchemaTracker", "shift": [1]}}, "pipeline.tracker.shift",
     ["expected a point [x, y]"]),
    ({"tracker": {"type": "no_such_module:Tracker"}}, "pipeline.tracker.type",
     ["cannot import no_such_module:Tracker (ModuleNotFoundError", "expected module.path:ClassName"]),
    ({"tracker": {"type": "test_assemble:Nothing"}}, "pipeline.tracker.type", ["has no class 'Nothing'"]),
    ({"tracker": {"type": "test_assemble:OneAhead"}}, "pipeline.tracker.type",
     ["test_assemble:OneAhead has no method update; expected a tracker with the methods update, reset"]),
    ({"detector": {"jump": 0.3}}, "pipeline.detector.jump", ["unknown key", "jump_distance"]),
    ({"detectors": {"side_laser": {}}}, "pipeline.detectors.side_laser",
     ["no sensor of this scenario is called so; expected one of: front_laser, rear_laser"]),
    ({"fusion": {"type": "nearest", "distance": -0.1}}, "pipeline.fusion.distance", ["at least 0"]),
    ({"fusion": {"distance": 0.3}, "fusion_distance": 0.5}, "pipeline.fusion_distance",
     ["the old spelling of pipeline.fusion.distance, which is given too; expected only pipeline.fusion.distance"]),
    ({"fusion_distance": -1.0}, "pipeline.fusion_distance", ["at least 0"]),
], ids=["unknown-type", "nnt-key", "user-key", "user-required", "user-schema", "no-module", "no-class",
        "not-a-tracker", "detector-key", "no-such-sensor", "fusion-range", "legacy-twice", "legacy-range"])
def test_a_wrong_part_or_parameter_is_one_error_naming_the_file_and_key(tmp_path, pipeline, key, words):
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(walkers(pipeline), sort_keys=False))
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    message = str(info.value)
    assert (info.value.source, info.value.key) == (str(path), key)
    assert message.startswith(f"{path}: {key}: ") and "\n" not in message, message
    for w in words:
        assert w in message, (w, message)


def test_a_laser_detector_on_a_depth_camera_is_refused(tmp_path):
    data = walkers({"detectors": {"front_depth": {"type": "laser_segments"}}},
                   sensors={"lasers": LASERS, "depth_cameras": [{"name": "front_depth"}]})
    with pytest.raises(ScenarioError) as info:
        load(tmp_path, data)
    assert info.value.key == "pipeline.detectors.front_depth.type"
    assert str(info.value).endswith("laser_segments reads sensors.lasers, and front_depth is one of "
                                    "sensors.depth_cameras; expected a detector for sensors.depth_cameras")
