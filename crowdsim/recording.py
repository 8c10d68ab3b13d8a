"""A rerun recording of a run on a sim-time timeline: walls, ground-truth people, laser points, detections, tracks.

Everything is logged in the world frame (tracks and detections are moved there with the true odom transform) so
the scene reads as one picture. The robot shows as its footprint with its frames: base_link, each laser's and depth
camera's frame (x axes, labelled), and odom; the wall cameras stand where they are, looking along their x axes.
Camera images go under ``cameras/``, the wall cameras' with each person's visible box.
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from pipeline.frames import compose, rotate, rotate_covariances, rotation, transform_points

from .loop import Frame


def covariance_ellipses(centres: np.ndarray, covs: np.ndarray, sigma: float = 2.0, n: int = 24) -> np.ndarray:
    """Outlines [k, n, 2] of the ``sigma`` ellipses of 2x2 covariances, for drawing."""
    vals, vecs = np.linalg.eigh(covs)
    t = np.linspace(0, 2 * np.pi, n)
    circle = np.stack([np.cos(t), np.sin(t)], 0)  # [2, n]
    axes = vecs * (sigma * np.sqrt(np.maximum(vals, 0)))[:, None, :]
    return centres[:, None, :] + np.einsum("kij,jn->kni", axes, circle)


def _axes(poses: np.ndarray, length: float) -> dict:
    """Origins and x-axis arrows of 2D poses [n, 3] (x, y, yaw), as rerun's Arrows2D takes them."""
    return {"origins": poses[:, :2], "vectors": length * np.stack([np.cos(poses[:, 2]), np.sin(poses[:, 2])], 1)}


class Recording:
    def __init__(self, path, walls: np.ndarray, sim):
        self.rec = rr.RecordingStream("crowdsim")
        self.rec.save(str(path))
        self.lasers = sim.lasers
        self.radius = sim.robot.radius
        # the depth cameras' mounts on base_link as 2D poses (x, y, yaw)
        self.depth_mounts = np.array([[*c.position[:2], c.yaw] for c in sim.depth_cameras]).reshape(-1, 3)
        self.sensor_names = [laser.name for laser in sim.lasers] + [c.name for c in sim.depth_cameras]
        self.rec.log("world/walls", rr.LineStrips2D(list(walls), colors=[90, 90, 100]), static=True)
        for camera in (*sim.depth_cameras, *sim.wall_cameras):
            # the camera's intrinsics, in the optical frame (x right, y down, z forward): a 3D view shows its depth
            # image as a point cloud
            k = camera.intrinsics
            self.rec.log(f"cameras/{camera.name}", rr.Pinhole(focal_length=float(k.f), width=k.width, height=k.height,
                                                             camera_xyz=rr.ViewCoordinates.RDF), static=True)
        if sim.wall_cameras:
            poses = np.array([[*c.position[:2], c.yaw] for c in sim.wall_cameras])
            self.rec.log("world/wall_cameras", rr.Arrows2D(**_axes(poses, 1.0), colors=[0, 160, 160],
                                                           labels=[c.name for c in sim.wall_cameras]), static=True)

    def log(self, frame: Frame) -> None:
        rec = self.rec
        rec.set_time("sim_time", duration=frame.stamp)
        a = frame.agents
        rec.log("world/people", rr.Points2D(a.position, radii=a.radius, colors=[150, 150, 150],
                                            labels=[str(i) for i in a.id]))
        pose = frame.robot_pose
        ring = np.linspace(0, 2 * np.pi, 33)
        rec.log("world/robot", rr.LineStrips2D([pose[:2] + self.radius * np.stack([np.cos(ring), np.sin(ring)], 1)],
                                               colors=[40, 70, 200]))
        rec.log("world/robot/base_link", rr.Arrows2D(
            origins=[pose[:2]] * 2, vectors=[compose(pose, [0.6, 0, 0])[:2] - pose[:2],
                                            compose(pose, [0, 0.6, 0])[:2] - pose[:2]],
            colors=[[255, 0, 0], [0, 255, 0]], labels=["base_link", ""]))
        mounts = np.array([laser.pose_in(pose) for laser in self.lasers]
                          + [compose(pose, m) for m in self.depth_mounts]).reshape(-1, 3)
        rec.log("world/robot/sensors", rr.Arrows2D(**_axes(mounts, 0.3), colors=[200, 100, 0],
                                                   labels=self.sensor_names))
        points, by_name = [], {laser.name: laser for laser in self.lasers}
        for scan in frame.scans:  # the lasers that scanned at this cycle (those of other rates wait for theirs)
            p = scan.points()
            points.append(transform_points(by_name[scan.frame].pose_in(pose), p[np.isfinite(p[:, 0])]))
        if points:
            rec.log("world/laser_points", rr.Points2D(np.concatenate(points), radii=0.03, colors=[230, 60, 60]))
        w = frame.world_T_odom
        det = transform_points(w, frame.detections.position[:, :2])
        rec.log("world/detections", rr.Points2D(det, radii=0.12, colors=[255, 200, 0]))
        tr = frame.tracks
        pos = transform_points(w, tr.position)
        vel = rotate(w, tr.velocity)
        cov = rotate_covariances(rotation(w), tr.position_covariance)
        ids = tr.track_id.astype(int)
        rec.log("world/tracks", rr.Points2D(pos, radii=0.2, class_ids=ids % 256, labels=[f"T{i}" for i in ids]))
        rec.log("world/tracks/velocity", rr.Arrows2D(origins=pos, vectors=vel, class_ids=ids % 256))
        rec.log("world/tracks/covariance", rr.LineStrips2D(list(covariance_ellipses(pos, cov)), class_ids=ids % 256))
        g = frame.groups
        centroid = transform_points(w, g.centroid)
        members = pos[np.argsort(ids)][np.searchsorted(np.sort(ids), g.member_track)]
        at = np.searchsorted(g.group_id, g.member_group, sorter=np.argsort(g.group_id))
        hub = centroid[np.argsort(g.group_id)[at]] if len(g.group_id) else np.zeros((0, 2))
        rec.log("world/groups", rr.LineStrips2D(list(np.stack([hub, members], axis=1)),
                                                class_ids=g.member_group % 256, radii=0.04))
        rec.log("world/groups/id", rr.Points2D(centroid, radii=0.08, class_ids=g.group_id % 256,
                                               labels=[f"G{i} ({a:.0f} s)" for i, a in zip(g.group_id, g.age)]))
        rec.log("world/odom", rr.Arrows2D(origins=[w[:2]] * 2, vectors=[compose(w, [1, 0, 0])[:2] - w[:2],
                                                                       compose(w, [0, 1, 0])[:2] - w[:2]],
                                          colors=[[255, 0, 0], [0, 255, 0]]))

    def log_images(self, frame: Frame) -> None:
        """The robot's depth images (and colour) and the wall cameras' images, each with its people's segmentation
        (id + 1 modulo 256), the wall cameras' with each person's visible box."""
        rec = self.rec
        for image in frame.depth_frames:
            rec.set_time("sim_time", duration=image.stamp)
            rec.log(f"cameras/{image.frame}/depth", rr.DepthImage(np.nan_to_num(image.depth, nan=0.0), meter=1.0))
            rec.log(f"cameras/{image.frame}/people", rr.SegmentationImage(np.maximum(image.person_id + 1, 0) % 256))
            if image.rgb is not None:
                rec.log(f"cameras/{image.frame}/rgb", rr.Image(image.rgb))
        for image in frame.camera_frames:
            rec.set_time("sim_time", duration=image.stamp)
            if image.rgb is not None:
                rec.log(f"cameras/{image.frame}/rgb", rr.Image(image.rgb))
            rec.log(f"cameras/{image.frame}/segmentation",
                    rr.SegmentationImage(np.maximum(image.person_id + 1, 0) % 256))
            rec.log(f"cameras/{image.frame}/rgb/people", rr.Boxes2D(
                array=image.boxes, array_format=rr.Box2DFormat.XYXY, class_ids=image.ids % 256,
                labels=[f"{i} ({100 * f:.0f}% visible)" for i, f in zip(image.ids, image.visible_fraction)]))

    def close(self) -> None:
        self.rec.flush()
