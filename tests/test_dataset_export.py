"""``export_dataset``: a tiny dataset exported as DROW v2, MOTChallenge and ROS 2 / ROS 1 bags, each read back the
way the target tools read it (DROW's layout parsed as DR-SPAAM's loader parses it, bags with rosbags' AnyReader)
and compared with the dataset's own files; and the refusals. A small open room, a few people, 0.6 s episodes."""

import json
import re

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation

from crowdsim.datasets.export import export_dataset
from crowdsim.datasets.generate import generate
from crowdsim.datasets.layout import DatasetError
from crowdsim.datasets.reader import Dataset
from scenarios import load_scenario

ROOM = {
    "name": "export_room", "seed": 4, "warmup": 3.0, "duration": 0.6,
    # open to the north, so that some beams find nothing
    "map": {"walls": [[[0, 10], [0, 0], [14, 0], [14, 10]]]},
    "waypoints": {"east": {"position": [12, 5], "radius": 1.0}},
    "routes": {"across": {"waypoints": ["east"]}},
    "sources": [{"position": [2, 5], "size": [1, 4], "rate": 2.0, "routes": {"across": 1.0}}],
    "standing": [{"position": [7, 8], "count": 3}],
    "robot": {"start": [6, 2, 1.5708], "route": [[6, 6], [9, 6]]},
    # the first laser is not on DROW's grid: the export must pick the second
    "sensors": {"lasers": [{"name": "rear_laser", "mount": [-0.25, 0, 3.14159]},
                           {"name": "leg_laser", "mount": [0.3, 0, 0], "preset": "sick_s300"}],
                "depth_cameras": [{"name": "front_depth", "preset": "kinect_160", "width": 32, "height": 24,
                                   "rate": 15.0, "rgb": True}],
                "wall_cameras": [{"name": "corner_cam", "position": [0.3, 0.3, 2.8], "yaw": 0.6, "pitch": 0.45,
                                  "width": 32, "height": 24}]},
}
EPISODES = {"episode_00000": "train", "episode_00001": "val"}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    path = root / "export_room.yaml"
    path.write_text(yaml.safe_dump(ROOM))
    generate([load_scenario(path)], [str(path)], root / "ds", 2, seed=3, progress=False)
    return root / "ds"


@pytest.fixture(scope="module")
def exported(dataset, tmp_path_factory):
    """Every format exported once: format -> (OUT, the summary)."""
    root = tmp_path_factory.mktemp("out")
    return {fmt: (root / fmt, export_dataset(dataset, fmt, root / fmt))
            for fmt in ("drow", "motchallenge", "rosbag2", "rosbag1")}


# ---- DROW, read as DR-SPAAM's drow_handle.py reads it ----

DROW_PHI = np.radians(0.5) * (np.arange(450) - 224.5)  # DROW's beam angles: 450 at 0.5 deg, centred on 0


def read_labels(path):
    seqs, dets = [], []
    with open(path) as f:
        for line in f:
            seq, tail = line.split(",", 1)
            seqs.append(int(seq))
            dets.append(json.loads(tail))
    return seqs, dets


def test_drow_scans_are_the_lasers_ranges_with_no_return_at_29_96(dataset, exported):
    out, summary = exported["drow"]
    assert summary["laser"] == ["leg_laser"] and summary["scans"] == 30 and summary["episodes"] == 2
    ds = Dataset(dataset)
    nan_beams = 0
    for episode, split in EPISODES.items():
        data = np.genfromtxt(out / "DROWv2-data" / split / f"{episode}.csv", delimiter=",")
        g = ds.episode(episode).sensor("leg_laser")
        assert data.shape == (15, 452)
        np.testing.assert_array_equal(data[:, 0], g["frame"][()])
        np.testing.assert_allclose(data[:, 1], g["stamp"][()], atol=1e-6)
        ranges = g["ranges"][()]
        nan_beams += np.isnan(ranges).sum()
        expected = np.where(np.isnan(ranges), 29.96, ranges)
        np.testing.assert_allclose(data[:, 2:], expected, atol=5e-4 + 1e-9)  # written in mm
        odom = np.loadtxt(out / "DROWv2-data" / split / f"{episode}.odom2", delimiter=",", ndmin=2)
        assert odom.shape == (15, 5) and (odom[:, 0] == data[:, 0]).all()
    assert nan_beams > 1000  # the open side: the mapping was exercised


def test_drow_labels_are_the_persons_the_scan_hits_at_their_polar_position(dataset, exported):
    out, summary = exported["drow"]
    ds = Dataset(dataset)
    labels = 0
    for episode, split in EPISODES.items():
        stem = out / "DROWv2-data" / split / episode
        (s_wc, wcs), (s_wa, was), (s_wp, wps) = (read_labels(f"{stem}.{ext}") for ext in ("wc", "wa", "wp"))
        g = ds.episode(episode).sensor("leg_laser")
        assert s_wc == s_wa == s_wp == list(g["frame"][()])
        assert all(d == [] for d in wcs + was)  # persons only in our crowd
        for k, dets in enumerate(wps):
            ranges, ids = g["ranges"][k], g["person_id"][k]
            seen = np.unique(ids[ids >= 0])
            assert len(dets) == len(seen) > 0  # one label per person with at least one beam
            dets = np.array(dets)
            label_xy = dets[:, :1] * np.column_stack([np.cos(dets[:, 1]), np.sin(dets[:, 1])])
            for person in seen:
                beams = ids == person
                hit_xy = ranges[beams, None] * np.column_stack([np.cos(DROW_PHI[beams]), np.sin(DROW_PHI[beams])])
                # the label nearest the person's beams is behind them (the centre), within a body's radius
                nearest = np.argmin(np.linalg.norm(label_xy - hit_xy.mean(axis=0), axis=1))
                assert np.linalg.norm(hit_xy - label_xy[nearest], axis=1).max() < 0.45, (episode, k, person)
                assert DROW_PHI[beams].min() - 0.05 < dets[nearest, 1] < DROW_PHI[beams].max() + 0.05
            labels += len(dets)
    assert labels == summary["labels"] == 210


# ---- MOTChallenge ----

def test_motchallenge_rows_are_the_tables_rows(dataset, exported):
    out, summary = exported["motchallenge"]
    rows_gt = 0
    for episode, split in EPISODES.items():
        seq = out / split / episode
        persons = pq.read_table(dataset / episode / "persons.parquet")
        gt = np.loadtxt(seq / "gt" / "gt.txt", delimiter=",", ndmin=2)
        assert gt.shape == (persons.num_rows, 10)
        rows_gt += persons.num_rows
        np.testing.assert_array_equal(gt[:, 0], persons.column("frame").to_numpy() + 1)  # 1-based
        np.testing.assert_array_equal(gt[:, 1], persons.column("id").to_numpy())
        assert (gt[:, 2:6] == -1).all() and (gt[:, 9] == 0).all()
        np.testing.assert_allclose(gt[:, 7], persons.column("x").to_numpy(), atol=5e-5)
        seen = (persons.column("leg_laser.beams").to_numpy() > 0) | (persons.column("rear_laser.beams").to_numpy() > 0)
        np.testing.assert_array_equal(gt[:, 6], seen)
        tracks = pq.read_table(dataset / episode / "tracks.parquet")
        rows = np.loadtxt(seq / "tracks.txt", delimiter=",", ndmin=2)
        assert len(rows) == tracks.num_rows > 0
        np.testing.assert_allclose(rows[:, 7], tracks.column("world_x").to_numpy(), atol=5e-5)
        fused = pq.read_table(dataset / episode / "detections.parquet").column("detector").to_numpy(
            zero_copy_only=False) == "fusion"
        assert len(np.loadtxt(seq / "det" / "det.txt", delimiter=",", ndmin=2)) == fused.sum()
        assert (seq / "seqinfo.ini").read_text() == f"[Sequence]\nname={episode}\nframeRate=25\nseqLength=15\n"
    assert summary["rows"]["gt"] == rows_gt == 90 + 120  # 6 and 8 persons over 15 frames


# ---- ROS bags, read back with AnyReader ----

def bag_path(out, fmt, episode):
    return out / EPISODES[episode] / (f"{episode}.bag" if fmt == "rosbag1" else episode)


@pytest.mark.parametrize("fmt", ["rosbag2", "rosbag1"])
def test_bags_hold_every_topic_once_per_sample(dataset, exported, fmt):
    out, summary = exported[fmt]
    ep = Dataset(dataset).episode("episode_00000")
    scans = {name: ep.sensor(name)["stamp"].shape[0] for name in ("leg_laser", "rear_laser")}
    images = {name: ep.sensor(name)["stamp"].shape[0] for name in ("front_depth", "corner_cam")}
    assert scans == {"leg_laser": 15, "rear_laser": 15} and images == {"front_depth": 10, "corner_cam": 7}
    expected = {"/tf": 15, "/tf_static": 1, "/spencer/sensors/odom": 15,
                "/spencer/sensors/leg_laser/echo0": 15, "/spencer/sensors/rear_laser/echo0": 15,
                "/spencer/perception_internal/detected_persons/leg_laser": 15,
                "/spencer/perception_internal/detected_persons/rear_laser": 15,
                "/spencer/perception/detected_persons": 15, "/spencer/perception/tracked_persons": 15,
                "/groundtruth/tracked_persons": 15, "/groundtruth/tracked_groups": 15}
    for cam, kinds in (("front_depth", ("depth", "rgb")), ("corner_cam", ("rgb",))):
        expected[f"/groundtruth/{cam}/segmentation"] = images[cam]
        for kind in kinds:
            expected[f"/spencer/sensors/{cam}/{kind}/camera_info"] = images[cam]
            expected[f"/spencer/sensors/{cam}/{kind}/{'image_rect' if kind == 'depth' else 'image_rect_color'}"] = \
                images[cam]
    with AnyReader([bag_path(out, fmt, "episode_00000")]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
        digests = {c.topic: c.digest for c in reader.connections}
    assert counts == expected
    assert types["/spencer/perception/tracked_persons"] == "spencer_tracking_msgs/msg/TrackedPersons"
    assert types["/groundtruth/tracked_groups"] == "spencer_tracking_msgs/msg/TrackedGroups"
    if fmt == "rosbag1":  # genmsg's md5 sums, as ROS 1 subscribers check them
        assert digests["/spencer/perception/tracked_persons"] == "21c0b1a57c4933e68f39aa3802861828"
        assert digests["/spencer/perception/detected_persons"] == "38e416cebb5dfd7363bde91113e7f3bd"
        assert digests["/tf"] == "94810edda583a504dfda3829e70d7eec"
    assert summary["messages"]["/spencer/perception/tracked_persons"] == 30


def messages(path, topic):
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages(connections=conns)]


@pytest.mark.parametrize("fmt", ["rosbag2", "rosbag1"])
def test_bag_messages_carry_the_datasets_values(dataset, exported, fmt):
    out, _ = exported[fmt]
    ep = Dataset(dataset).episode("episode_00000")
    path = bag_path(out, fmt, "episode_00000")
    g, cal = ep.sensor("leg_laser"), ep.meta["calibration"]["lasers"]["leg_laser"]
    t, scan = messages(path, "/spencer/sensors/leg_laser/echo0")[7]
    assert t == round(g["stamp"][7] * 1e9) and scan.header.frame_id == "leg_laser"
    assert scan.angle_min == pytest.approx(-np.radians(112.25)) and len(scan.ranges) == 450
    np.testing.assert_array_equal(scan.ranges, np.where(np.isnan(g["ranges"][7]), np.inf, g["ranges"][7]))
    assert (scan.range_max, scan.angle_increment) == (30.0, pytest.approx(cal["angle_increment"]))

    tracks = ep.table("tracks", frames=(9, 10))
    _, msg = messages(path, "/spencer/perception/tracked_persons")[9]
    assert msg.header.frame_id == "odom" and len(msg.tracks) == tracks.num_rows > 0
    assert [m.track_id for m in msg.tracks] == tracks.column("id").to_pylist()
    np.testing.assert_array_equal([[m.pose.pose.position.x, m.pose.pose.position.y] for m in msg.tracks],
                                  np.column_stack([tracks.column("x").to_numpy(), tracks.column("y").to_numpy()]))
    assert [m.pose.covariance[0] for m in msg.tracks] == tracks.column("cov_xx").to_pylist()

    persons = ep.table("persons", frames=(9, 10))
    _, gt = messages(path, "/groundtruth/tracked_persons")[9]
    assert gt.header.frame_id == "map"
    np.testing.assert_array_equal([m.pose.pose.position.x for m in gt.tracks], persons.column("x").to_numpy())
    _, groups = messages(path, "/groundtruth/tracked_groups")[9]
    assert [(m.group_id, sorted(m.track_ids)) for m in groups.groups] == [
        (1, sorted(persons.filter(persons.column("group_id").to_numpy() == 1).column("id").to_pylist()))]

    robot = ep.robot()
    _, odom = messages(path, "/spencer/sensors/odom")[9]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    assert [odom.pose.pose.position.x, odom.pose.pose.position.y] == list(robot["odom"][9, :2])
    _, tf = messages(path, "/tf")[9]
    assert [(x.header.frame_id, x.child_frame_id) for x in tf.transforms] == [("map", "odom"), ("odom", "base_link")]
    assert tf.transforms[0].transform.translation.x == robot["world_T_odom"][9, 0]
    (_, static), = messages(path, "/tf_static")
    mounts = {x.child_frame_id: (x.header.frame_id, x.transform) for x in static.transforms}
    assert sorted(mounts) == ["corner_cam", "front_depth", "leg_laser", "rear_laser"]
    parent, camera = mounts["front_depth"]
    q = camera.rotation
    cal_depth = ep.meta["calibration"]["depth_cameras"]["front_depth"]
    np.testing.assert_allclose(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), cal_depth["rotation"], atol=1e-12)
    assert parent == "base_link" and mounts["corner_cam"][0] == "map"
    assert (mounts["leg_laser"][1].translation.x, mounts["leg_laser"][1].translation.z) == (0.3, 0.37)

    depth = ep.sensor("front_depth")
    _, image = messages(path, "/spencer/sensors/front_depth/depth/image_rect")[2]
    assert (image.encoding, image.height, image.width, image.step) == ("32FC1", 24, 32, 128)
    np.testing.assert_array_equal(image.data.view(np.float32).reshape(24, 32), depth["depth"][2])
    _, info = messages(path, "/spencer/sensors/front_depth/depth/camera_info")[2]
    k = info.K if fmt == "rosbag1" else info.k
    np.testing.assert_array_equal(k, np.ravel(ep.meta["calibration"]["depth_cameras"]["front_depth"]["K"]))


# ---- refusals ----

def test_an_unknown_format_is_refused(dataset, tmp_path):
    with pytest.raises(DatasetError, match=r"--format kitti: expected one of drow, motchallenge, rosbag2, rosbag1"):
        export_dataset(dataset, "kitti", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_non_empty_out_is_refused_and_left_alone(dataset, tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "keep.txt").write_text("mine")
    with pytest.raises(DatasetError, match=re.escape(f"--out {tmp_path / 'out'}: already exists and is not empty")):
        export_dataset(dataset, "motchallenge", tmp_path / "out")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["keep.txt"]


def test_drow_refuses_a_laser_off_its_beam_grid(dataset, tmp_path):
    with pytest.raises(DatasetError, match=r"laser rear_laser on DROW's beam grid; expected 450 beams"):
        export_dataset(dataset, "drow", tmp_path / "out", laser="rear_laser")
    assert not (tmp_path / "out").exists() and list(tmp_path.iterdir()) == []


def test_a_split_exports_its_episodes_only(dataset, tmp_path):
    summary = export_dataset(dataset, "drow", tmp_path / "out", split="val")
    assert summary["episodes"] == 1 and summary["scans"] == 15
    assert sorted(p.name for p in (tmp_path / "out" / "DROWv2-data").iterdir()) == ["val"]
