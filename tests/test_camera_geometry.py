"""The floor homography of a calibrated camera, by hand."""

import numpy as np

from pipeline.camera_geometry import floor_homography, image_to_floor


def level_camera(height=2.0, f=500.0, centre=(320.0, 240.0)):
    """A camera ``height`` above the origin looking level along +x: optical z = x, optical x = -y, optical y = -z."""
    K = np.array([[f, 0, centre[0]], [0, f, centre[1]], [0, 0, 1.0]])
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([[0, -1, 0], [0, 0, -1], [1, 0, 0]])
    pose[:3, 3] = [0, 0, height]
    return K, pose


def test_a_floor_point_ahead_projects_below_the_horizon_by_f_height_over_distance():
    K, pose = level_camera()
    h = floor_homography(K, pose)
    # (4, 0) is 4 m ahead and 2 m down: v = 240 + 500 x 2 / 4 = 490; (4, 1) is 1 m to the left: u = 320 - 125
    p = np.array([[4.0, 0.0, 1.0], [4.0, 1.0, 1.0]]) @ h.T
    np.testing.assert_allclose(p[:, :2] / p[:, 2:], [[320.0, 490.0], [195.0, 490.0]])
    np.testing.assert_allclose(image_to_floor(K, pose, [[320.0, 490.0], [195.0, 490.0]]), [[4.0, 0.0], [4.0, 1.0]])
    # above the horizon (v < 240) no floor point lies in front of the camera; just below it, one far away
    assert np.isnan(image_to_floor(K, pose, [[320.0, 239.9], [320.0, 100.0]])).all()
    np.testing.assert_allclose(image_to_floor(K, pose, [[320.0, 240.1]]), [[10000.0, 0.0]], rtol=1e-6)
