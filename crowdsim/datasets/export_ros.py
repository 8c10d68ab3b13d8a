"""ROS bags of a dataset, written with rosbags (no ROS needed): per episode one ROS 2 bag (MCAP storage,
``OUT/<split>/<episode>/``, chunks zstd-compressed) or one ROS 1 bag (``OUT/<split>/<episode>.bag``, chunks
LZ4-compressed; both compressions are the formats' own, read transparently, and shrink images 10 to 16 times), on
the SPENCER framework's topics and message types, so that SPENCER's tools and any ROS people tracker can replay an
episode.

Topics (SPENCER's names: spencer_people_tracking ``README.md`` tutorials and ``launch/spencer_people_tracking_launch/
launch/``: ``detectors/laser_detectors.launch``, ``tracking/freiburg_people_tracking.launch``,
``tracking/filter_tracks.launch``; ground truth as ``spencer_tracking_metrics/launch/clearmot_from_logfile.launch``
reads it); our sensors keep their names where SPENCER's robot has laser_front, rgbd_front_top:

* ``/spencer/sensors/<laser>/echo0`` sensor_msgs/LaserScan, frame_id the laser; no return is +Inf (REP 117: beyond
  range_max is +Inf, NaN is an invalid reading), ranges and angles as sensors.h5 and the calibration have them;
* ``/spencer/sensors/<camera>/depth/image_rect`` (32FC1, m, NaN where nothing was measured, REP 118),
  ``.../rgb/image_rect_color`` (rgb8) and a sensor_msgs/CameraInfo with each (``.../depth/camera_info``,
  ``.../rgb/camera_info``: K of the calibration, no distortion, P = [K | 0]), frame_id the camera's optical frame;
  ``/groundtruth/<camera>/segmentation`` (32SC1, person id per pixel, -1 none);
* ``/spencer/sensors/odom`` nav_msgs/Odometry odom -> base_link, the odometry pose; its twist (in base_link, as
  ROS has it) from backward differences of that pose (zero at the first frame); covariances zero (not modelled);
* ``/tf`` tf2_msgs/TFMessage each frame: map -> odom (the dataset's world_T_odom; "map" is the dataset's world
  frame, named as REP 105 names it) and odom -> base_link; ``/tf_static`` once, latched: base_link -> each laser
  and depth camera, map -> each wall camera;
* ``/spencer/perception_internal/detected_persons/<sensor>`` spencer_tracking_msgs/DetectedPersons of each detector
  (one per laser, one per sensor the scenario's ``pipeline.detectors`` names: pipeline/assemble.py) in every frame
  it ran, ``/spencer/perception/detected_persons`` the fused detections (the tracker's input) every frame, both in
  odom; ``/spencer/perception/tracked_persons`` TrackedPersons every frame, in odom;
* ``/groundtruth/tracked_persons`` TrackedPersons of every person every frame, in map (track_id the person's id,
  is_occluded where no laser beam hit them, is_matched false, orientation the heading); ``/groundtruth/
  tracked_groups`` TrackedGroups of the persons' group ids (centre and covariance of the members' positions).

Stamps are simulation time, t s -> ns. Variances of what a message does not carry (z, roll, pitch; a track's or a
detection's orientation; the ground truth has none) are UNSET, as SPENCER's laser detectors set them
(``srl_laser_detectors/src/srl_laser_detectors/ros/ros_interface.cpp``, LARGE_VARIANCE); a track's velocity
variance is not in the dataset and is left 0. Ids the dataset has as -1 (a track matched to no detection) are
2^64 - 1 in the uint64 fields. Not written: SocialRelations and the tracker's own groups (the dataset has none),
the lasers' per-beam person ids.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from scipy.spatial.transform import Rotation

from .layout import FUSED
from .spencer_msgs import typestore

MAP, ODOM, BASE = "map", "odom", "base_link"
UNSET = 999999999.0
NO_ID = 2**64 - 1
BLOCK = 256  # robot rows read at once
PLANAR_COV = np.diag([0.0, 0.0, UNSET, UNSET, UNSET, UNSET]).reshape(36)  # over x, y, z, roll, pitch, yaw
LATCHED = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL, QosTime(0, 0),
              QosTime(0, 0), QosLiveliness.AUTOMATIC, QosTime(0, 0), False)
TRACKED_PERSONS = "/spencer/perception/tracked_persons"
DETECTED_PERSONS = "/spencer/perception/detected_persons"
DETECTOR_TOPIC = "/spencer/perception_internal/detected_persons/{}"
GT_PERSONS, GT_GROUPS = "/groundtruth/tracked_persons", "/groundtruth/tracked_groups"
ODOM_TOPIC = "/spencer/sensors/odom"


def write(episodes, out: Path, ros: int) -> dict:
    """One bag per episode; the message count per topic over all of them."""
    counts: dict[str, int] = {}
    for ep, split in episodes:
        (out / split).mkdir(exist_ok=True)
        bag = Bag(out / split / (f"{ep.folder.name}.bag" if ros == 1 else ep.folder.name), ros)
        try:
            _write_episode(ep, bag)
        finally:
            bag.close()
        for topic, n in bag.counts.items():
            counts[topic] = counts.get(topic, 0) + n
    return {"messages": dict(sorted(counts.items()))}


class Bag:
    """One bag being written: the typestore of its ROS version, a connection per topic (made on first use), the
    message counts, and the builders of the messages' common parts."""

    def __init__(self, path: Path, ros: int):
        self.ros, self.store = ros, typestore(ros)
        self.T = self.store.types
        if ros == 1:
            self.writer = Writer1(path)
            self.writer.set_compression(Writer1.CompressionFormat.LZ4)
        else:
            self.writer = Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP)
            self.writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)  # MCAP's chunk compression
        self.writer.open()
        self.connections: dict = {}
        self.counts: dict[str, int] = {}
        self.serialize = self.store.serialize_ros1 if ros == 1 else self.store.serialize_cdr

    def close(self) -> None:
        self.writer.close()

    def write(self, topic: str, msg, ns: int) -> None:
        if topic not in self.connections:
            latched = topic == "/tf_static"
            if self.ros == 1:
                kw = {"latching": 1} if latched else {}
            else:
                kw = {"offered_qos_profiles": [LATCHED] if latched else []}
            self.connections[topic] = self.writer.add_connection(topic, msg.__msgtype__, typestore=self.store, **kw)
        self.writer.write(self.connections[topic], ns, self.serialize(msg, msg.__msgtype__))
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def header(self, topic: str, ns: int, frame_id: str):
        stamp = self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        seq = {"seq": self.counts.get(topic, 0)} if self.ros == 1 else {}
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id, **seq)

    def duration(self, seconds: float):
        ns = int(round(seconds * 1e9))
        return self.T["builtin_interfaces/msg/Duration"](sec=ns // 10**9, nanosec=ns % 10**9)

    def vector(self, x=0.0, y=0.0, z=0.0):
        return self.T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def quaternion(self, q):
        return self.T["geometry_msgs/msg/Quaternion"](x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))

    def transform(self, ns: int, parent: str, child: str, xyz, q):
        return self.T["geometry_msgs/msg/TransformStamped"](
            header=self.header("/tf", ns, parent), child_frame_id=child,
            transform=self.T["geometry_msgs/msg/Transform"](translation=self.vector(*xyz), rotation=self.quaternion(q)))

    def pose(self, x, y, z, yaw, cov_xx=0.0, cov_xy=0.0, cov_yy=0.0, var_yaw=UNSET):
        """PoseWithCovariance at (x, y, z) facing ``yaw``, with the given x, y and yaw (co)variances, the others
        UNSET."""
        cov = PLANAR_COV.copy()
        cov[[0, 1, 6, 7, 35]] = cov_xx, cov_xy, cov_xy, cov_yy, var_yaw
        point = self.T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z))
        return self.T["geometry_msgs/msg/PoseWithCovariance"](
            pose=self.T["geometry_msgs/msg/Pose"](position=point, orientation=self.quaternion(_yaw_q(yaw))),
            covariance=cov)

    def twist(self, vx, vy):
        """TwistWithCovariance in the plane: x, y velocity variances 0 (not in the dataset), the others UNSET."""
        return self.T["geometry_msgs/msg/TwistWithCovariance"](
            twist=self.T["geometry_msgs/msg/Twist"](linear=self.vector(vx, vy), angular=self.vector()),
            covariance=PLANAR_COV)


def _yaw_q(yaw: float) -> tuple[float, float, float, float]:
    return 0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)


def _ns(t: float) -> int:
    return int(round(float(t) * 1e9))


def _write_episode(ep, bag: Bag) -> None:
    """Frame by frame: the transforms and odometry, each sensor's samples of the frame, the detections, tracks and
    ground truth; the tables one row group at a time, the sensors a sample at a time."""
    cal = ep.meta["calibration"]
    groups = {name: dict(ep.sensor(name).items()) for name in [*ep.lasers, *ep.cameras]}  # name -> h5 datasets
    sample_frames = {name: g["frame"][()] for name, g in groups.items()}
    sample_ns = {name: np.round(g["stamp"][()] * 1e9).astype(np.int64) for name, g in groups.items()}
    detectors = {*ep.lasers, *ep.meta["scenario"]["pipeline"].get("detectors", {})}
    persons = ep.iter_frames("persons", ["id", "group_id", "x", "y", "vx", "vy", "heading",
                                         *[f"{name}.beams" for name in ep.lasers]])
    detections = ep.iter_frames("detections", ["detector", "modality", "id", "x", "y", "z", "confidence",
                                               "cov_xx", "cov_xy", "cov_yy"])
    tracks = ep.iter_frames("tracks")
    first_seen: dict[tuple[str, int], float] = {}  # ("person" | "group", id) -> t
    previous = None
    for (f, stamp, odom, world_T_odom), (_, p), (_, d), (_, tr) in zip(_robot_rows(ep), persons, detections, tracks):
        ns = _ns(stamp)
        if f == 0:
            _static_transforms(bag, cal, ns)
        bag.write("/tf", bag.T["tf2_msgs/msg/TFMessage"](transforms=[
            bag.transform(ns, MAP, ODOM, (*world_T_odom[:2], 0.0), _yaw_q(world_T_odom[2])),
            bag.transform(ns, ODOM, BASE, (*odom[:2], 0.0), _yaw_q(odom[2]))]), ns)
        _odometry(bag, ns, odom, previous)
        previous = (stamp, odom)
        for name, g in groups.items():
            rows = range(*np.searchsorted(sample_frames[name], [f, f + 1]))
            for k in rows:
                _sensor_sample(bag, name, g, k, int(sample_ns[name][k]), cal)
            if name in detectors and len(rows):
                _detected(bag, DETECTOR_TOPIC.format(name), int(sample_ns[name][rows[-1]]), d, d["detector"] == name)
        _detected(bag, DETECTED_PERSONS, ns, d, d["detector"] == FUSED)
        _tracked(bag, ns, tr)
        _groundtruth(bag, ns, stamp, p, [f"{name}.beams" for name in ep.lasers], first_seen)


def _robot_rows(ep):
    """(frame, stamp, odom pose, world_T_odom) per frame, read a block at a time."""
    robot = ep.h5["robot"]
    for a in range(0, ep.frames, BLOCK):
        stamp, odom, w = (robot[name][a:a + BLOCK] for name in ("stamp", "odom", "world_T_odom"))
        for k in range(len(stamp)):
            yield a + k, float(stamp[k]), odom[k], w[k]


def _static_transforms(bag: Bag, cal: dict, ns: int) -> None:
    transforms = [bag.transform(ns, BASE, name, (c["x"], c["y"], c["z"]), _yaw_q(c["yaw"]))
                  for name, c in cal["lasers"].items()]
    for kind, parent in (("depth_cameras", BASE), ("wall_cameras", MAP)):
        transforms += [bag.transform(ns, parent, name, c["position"], Rotation.from_matrix(c["rotation"])
                                     .as_quat()) for name, c in cal[kind].items()]  # the optical frame
    bag.write("/tf_static", bag.T["tf2_msgs/msg/TFMessage"](transforms=transforms), ns)


def _odometry(bag: Bag, ns: int, odom: np.ndarray, previous) -> None:
    v = np.zeros(2)
    omega = 0.0
    if previous is not None and ns > _ns(previous[0]):
        dt = ns / 1e9 - previous[0]
        c, s = np.cos(odom[2]), np.sin(odom[2])
        d = odom[:2] - previous[1][:2]
        v = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]]) / dt
        omega = float(np.angle(np.exp(1j * (odom[2] - previous[1][2])))) / dt
    zero = np.zeros(36)
    pose = bag.T["geometry_msgs/msg/Pose"](
        position=bag.T["geometry_msgs/msg/Point"](x=float(odom[0]), y=float(odom[1]), z=0.0),
        orientation=bag.quaternion(_yaw_q(odom[2])))
    twist = bag.T["geometry_msgs/msg/Twist"](linear=bag.vector(*v), angular=bag.vector(z=omega))
    bag.write(ODOM_TOPIC, bag.T["nav_msgs/msg/Odometry"](
        header=bag.header(ODOM_TOPIC, ns, ODOM), child_frame_id=BASE,
        pose=bag.T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=zero),
        twist=bag.T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=zero)), ns)


def _sensor_sample(bag: Bag, name: str, g: dict, k: int, ns: int, cal: dict) -> None:
    if name in cal["lasers"]:
        c = cal["lasers"][name]
        topic = f"/spencer/sensors/{name}/echo0"
        ranges = g["ranges"][k].astype(np.float32)
        ranges[np.isnan(ranges)] = np.inf
        bag.write(topic, bag.T["sensor_msgs/msg/LaserScan"](
            header=bag.header(topic, ns, name), angle_min=c["angle_min"], angle_max=c["angle_max"],
            angle_increment=c["angle_increment"], time_increment=0.0, scan_time=1 / c["rate_hz"],
            range_min=c["range_min"], range_max=c["range_max"], ranges=ranges,
            intensities=np.zeros(0, np.float32)), ns)
        return
    c = cal["depth_cameras"].get(name) or cal["wall_cameras"][name]
    for key, image, encoding in (("depth", "image_rect", "32FC1"), ("rgb", "image_rect_color", "rgb8")):
        if key in g:
            _image(bag, f"/spencer/sensors/{name}/{key}/{image}", ns, name, g[key][k], encoding)
            _camera_info(bag, f"/spencer/sensors/{name}/{key}/camera_info", ns, name, c)
    _image(bag, f"/groundtruth/{name}/segmentation", ns, name, g["segmentation"][k], "32SC1")


def _image(bag: Bag, topic: str, ns: int, frame_id: str, data: np.ndarray, encoding: str) -> None:
    data = np.ascontiguousarray(data, data.dtype.newbyteorder("<"))
    h, w = data.shape[:2]
    bag.write(topic, bag.T["sensor_msgs/msg/Image"](
        header=bag.header(topic, ns, frame_id), height=h, width=w, encoding=encoding, is_bigendian=0,
        step=data.nbytes // h, data=data.view(np.uint8).reshape(-1)), ns)


def _camera_info(bag: Bag, topic: str, ns: int, frame_id: str, c: dict) -> None:
    k = np.array(c["K"], float)
    matrices = {"d": np.zeros(5), "k": k.reshape(9), "r": np.eye(3).reshape(9),
                "p": np.hstack([k, np.zeros((3, 1))]).reshape(12)}
    if bag.ros == 1:  # ROS 1's CameraInfo names them D, K, R, P
        matrices = {key.upper(): value for key, value in matrices.items()}
    roi = bag.T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    bag.write(topic, bag.T["sensor_msgs/msg/CameraInfo"](
        header=bag.header(topic, ns, frame_id), height=c["height"], width=c["width"], distortion_model="plumb_bob",
        binning_x=0, binning_y=0, roi=roi, **matrices), ns)


def _detected(bag: Bag, topic: str, ns: int, d: dict, rows: np.ndarray) -> None:
    person = bag.T["spencer_tracking_msgs/msg/DetectedPerson"]
    detections = [person(detection_id=int(i) & NO_ID, confidence=float(conf), modality=str(modality),
                         pose=bag.pose(x, y, z, 0.0, xx, xy, yy))
                  for i, conf, modality, x, y, z, xx, xy, yy in zip(
                      *(d[c][rows] for c in ("id", "confidence", "modality", "x", "y", "z", "cov_xx", "cov_xy",
                                             "cov_yy")))]
    bag.write(topic, bag.T["spencer_tracking_msgs/msg/DetectedPersons"](
        header=bag.header(topic, ns, ODOM), detections=detections), ns)


def _tracked(bag: Bag, ns: int, tr: dict) -> None:
    person = bag.T["spencer_tracking_msgs/msg/TrackedPerson"]
    tracks = [person(track_id=int(i) & NO_ID, is_occluded=bool(occluded), is_matched=bool(matched),
                     detection_id=int(det) & NO_ID, age=bag.duration(age),
                     pose=bag.pose(x, y, 0.0, np.arctan2(vy, vx), xx, xy, yy), twist=bag.twist(vx, vy))
              for i, occluded, matched, det, age, x, y, vx, vy, xx, xy, yy in zip(
                  *(tr[c] for c in ("id", "is_occluded", "is_matched", "detection_id", "age", "x", "y", "vx", "vy",
                                    "cov_xx", "cov_xy", "cov_yy")))]
    bag.write(TRACKED_PERSONS, bag.T["spencer_tracking_msgs/msg/TrackedPersons"](
        header=bag.header(TRACKED_PERSONS, ns, ODOM), tracks=tracks), ns)


def _groundtruth(bag: Bag, ns: int, t: float, p: dict, beams: list[str], first_seen: dict) -> None:
    """Every person as a TrackedPerson, and the groups, in map; ages from each id's first frame."""
    seen = np.zeros(len(p["id"]), bool)
    for column in beams:
        seen |= p[column] > 0
    person = bag.T["spencer_tracking_msgs/msg/TrackedPerson"]
    tracks = [person(track_id=int(i), is_occluded=not s, is_matched=False, detection_id=NO_ID,
                     age=bag.duration(t - first_seen.setdefault(("person", int(i)), t)),
                     pose=bag.pose(x, y, 0.0, heading, var_yaw=0.0), twist=bag.twist(vx, vy))
              for i, s, x, y, vx, vy, heading in zip(p["id"], seen, p["x"], p["y"], p["vx"], p["vy"], p["heading"])]
    bag.write(GT_PERSONS, bag.T["spencer_tracking_msgs/msg/TrackedPersons"](
        header=bag.header(GT_PERSONS, ns, MAP), tracks=tracks), ns)
    group = bag.T["spencer_tracking_msgs/msg/TrackedGroup"]
    groups = []
    for g in np.unique(p["group_id"][p["group_id"] >= 0]):
        members = p["group_id"] == g
        xy = np.column_stack([p["x"][members], p["y"][members]])
        cov = np.cov(xy.T, bias=True).reshape(2, 2)
        groups.append(group(group_id=int(g), age=bag.duration(t - first_seen.setdefault(("group", int(g)), t)),
                            centerOfGravity=bag.pose(*xy.mean(axis=0), 0.0, 0.0, cov[0, 0], cov[0, 1], cov[1, 1]),
                            track_ids=p["id"][members].astype(np.uint64)))
    bag.write(GT_GROUPS, bag.T["spencer_tracking_msgs/msg/TrackedGroups"](
        header=bag.header(GT_GROUPS, ns, MAP), groups=groups), ns)
