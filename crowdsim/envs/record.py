"""A rerun recording of an environment's episodes (``make(..., record="file.rrd")``): per step the room, the people,
the robot with its heading, its goal, the laser points and the tracks when observed, on an ``env_time`` timeline with
the episode number as a second one."""

from __future__ import annotations

import numpy as np
import rerun as rr

from pipeline.frames import compose, transform_points


class EnvRecording:
    def __init__(self, path):
        self.rec = rr.RecordingStream("crowdsim-env")
        self.rec.save(str(path))
        self.episode = -1

    def reset(self, episodes) -> None:
        self.episode += 1
        walls = episodes.worlds.walls
        self.rec.set_time("episode", sequence=self.episode)
        self.rec.log("world/walls", rr.LineStrips2D(list(walls), colors=[90, 90, 100]))
        self.log(episodes)

    def log(self, episodes, k: int = 0) -> None:
        rec, w = self.rec, episodes.worlds
        rec.set_time("episode", sequence=self.episode)
        rec.set_time("env_time", duration=float(w.t[k]))
        rec.log("world/people", rr.Points2D(w.position[k], radii=w.radius[k], colors=[120, 140, 200],
                                            labels=[str(i) for i in range(w.N)]))
        pose = w.robot_pose[k]
        ring = np.linspace(0, 2 * np.pi, 33)
        rec.log("world/robot", rr.LineStrips2D([pose[:2] + w.robot_radius * np.stack([np.cos(ring), np.sin(ring)],
                                                                                     1)], colors=[200, 40, 40]))
        rec.log("world/robot/heading", rr.Arrows2D(origins=[pose[:2]], vectors=[compose(pose, [0.6, 0, 0])[:2]
                                                                                 - pose[:2]], colors=[200, 40, 40]))
        rec.log("world/goal", rr.Points2D([w.goal[k]], radii=0.3, colors=[40, 160, 60]))
        scan = episodes.scans[k]
        if scan is not None:
            laser = episodes.lasers[k]
            points = scan.points()
            points = transform_points(laser.pose_in(pose), points[np.isfinite(points[:, 0])])
            rec.log("world/laser_points", rr.Points2D(points, radii=0.03, colors=[230, 60, 60]))
        tracks = episodes.tracks[k]
        if tracks is not None:
            pos = transform_points(episodes.start[k], tracks.position)  # odom -> world (exact odometry)
            ids = tracks.track_id.astype(int)
            rec.log("world/tracks", rr.Points2D(pos, radii=0.2, class_ids=ids % 256, labels=[f"T{i}" for i in ids]))

    def close(self) -> None:
        self.rec.flush()
