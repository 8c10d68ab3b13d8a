"""The wall-camera detector: a foreground person's feet on the floor, through the camera's calibration."""

import numpy as np
import pytest

from pipeline.detectors.wall_camera import WallCameraDetector
from pipeline.fusion import to_frame
from pipeline.types import CameraFrame


def level_camera(height=2.0, f=100.0, size=(160, 120)):
    """A camera ``height`` above the origin looking level along +x (optical z = x, x = -y, y = -z)."""
    K = np.array([[f, 0, size[0] / 2], [0, f, size[1] / 2], [0, 0, 1.0]])
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([[0, -1, 0], [0, 0, -1], [1, 0, 0]])
    pose[:3, 3] = [0, 0, height]
    return K, pose


def image(stamp, person=None, size=(160, 120)):
    rgb = np.full((size[1], size[0], 3), 90, np.uint8)
    if person is not None:
        u0, v0, u1, v1 = person
        rgb[v0:v1, u0:u1] = (200, 40, 40)
    K, pose = level_camera(size=size)
    empty = np.zeros((0, 4))
    return CameraFrame(stamp, "cam", rgb, -np.ones((size[1], size[0]), np.int64), np.zeros(0, np.int64), empty,
                       empty, np.zeros(0), K, pose)


def test_a_foreground_person_stands_where_its_feet_meet_the_floor():
    det = WallCameraDetector(hog=False, bootstrap=3)
    for k in range(3):
        assert len(det.detect(image(0.2 * k))["fseg"].position) == 0  # the background model starts
    # a person box from row 70 to 110 (exclusive), columns 70..85: its feet at (77.5, 110): 50 rows below the
    # horizon (60) at f 100 and 2 m up: 4 m ahead; 2.5 columns left of the centre: 0.1 m to the left
    found = det.detect(image(0.6, (70, 70, 85, 110)))["fseg"]
    assert found.modality == "fseg" and len(found.position) == 1
    K, pose = level_camera()
    odom = to_frame(found, pose, "odom")
    np.testing.assert_allclose(odom.position[0], [4.0, 0.1, 0.0], atol=1e-9)
    np.testing.assert_allclose(odom.covariance[0, :2, :2], 0.09 * np.eye(2), atol=1e-9)


def test_the_robot_is_masked_out():
    det = WallCameraDetector(hog=False, bootstrap=3, robot_radius=0.5)
    for k in range(3):
        det.detect(image(0.2 * k))
    frame = image(0.6, (70, 70, 85, 110))  # feet 4 m ahead, 0.1 m to the left (above)
    frame.robot_position = np.array([4.3, 0.1])  # the robot 0.3 m behind them: what the camera sees is the robot
    assert len(det.detect(frame)["fseg"].position) == 0
    frame.robot_position = np.array([4.6, 0.1])  # 0.6 m off: a person beside the robot
    assert len(det.detect(frame)["fseg"].position) == 1


def test_it_needs_colour_and_calibration():
    frame = image(0.0)
    frame.pose = None
    with pytest.raises(ValueError, match="cam: the wall_people detector needs colour images"):
        WallCameraDetector(hog=False).detect(frame)
