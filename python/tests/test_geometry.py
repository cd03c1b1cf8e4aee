"""Rotation conventions, exterior orientation, the collinearity projection and the camera models
(python/src/geometry.cc), against formulas written out here in numpy."""

import math

import numpy as np
import pytest

import photopose as pp


def rx(a):
    return np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])


def ry(a):
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])


def rz(a):
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


ANGLES = np.array([0.1, -0.2, 0.3])
# Rotations composed of three elementary ones agree to a few ulps of 1.
TOLERANCE = 1e-14


def test_seed_convention_is_rx_ry_rz():
    R = pp.rotation_from_angles(ANGLES, "rxryrz")
    np.testing.assert_allclose(R, rx(0.1) @ ry(-0.2) @ rz(0.3), atol=TOLERANCE)
    # "seed" is the alias the tables accept.
    np.testing.assert_allclose(pp.rotation_from_angles(ANGLES, "seed"), R, atol=0)


def test_opk_is_the_transpose_for_the_same_numbers():
    np.testing.assert_allclose(pp.rotation_from_angles(ANGLES, "opk"),
                               pp.rotation_from_angles(ANGLES, "rxryrz").T, atol=TOLERANCE)


@pytest.mark.parametrize("convention", ["rxryrz", "opk", "pok"])
def test_angles_round_trip(convention):
    R = pp.rotation_from_angles(ANGLES, convention)
    np.testing.assert_allclose(pp.angles_from_rotation(R, convention), ANGLES, atol=1e-13)
    seed = pp.seed_angles_from_convention(ANGLES, convention)
    np.testing.assert_allclose(pp.convention_angles_from_seed(seed, convention), ANGLES, atol=1e-12)
    np.testing.assert_allclose(pp.rotation_from_angles(seed, "rxryrz"), R, atol=TOLERANCE)


def test_unknown_convention_names_the_accepted_ones():
    with pytest.raises(ValueError, match=r"unknown name 'xyz': expected rxryrz \(alias seed\), opk or pok"):
        pp.rotation_from_angles(ANGLES, "xyz")


def test_exterior_orientation_matrices():
    center = np.array([500000.0, 4100000.0, 150.0])
    eo = pp.ExteriorOrientation(center, ANGLES)
    np.testing.assert_array_equal(eo.center_in_ground, center)
    np.testing.assert_array_equal(eo.parameters, np.r_[center, ANGLES])
    T = eo.T_camera_from_ground
    assert T.shape == (4, 4)
    np.testing.assert_allclose(T[:3, :3], eo.R_camera_from_ground, atol=0)
    np.testing.assert_allclose(T @ np.r_[center, 1.0], [0, 0, 0, 1], atol=1e-9)
    for pose in (T, T[:3]):
        back = pp.ExteriorOrientation.from_pose_matrix(pose)
        np.testing.assert_allclose(back.parameters, eo.parameters, rtol=1e-12, atol=1e-12)
    back = pp.ExteriorOrientation.from_matrix(eo.R_camera_from_ground, center)
    np.testing.assert_allclose(back.angles_seed_rad, ANGLES, atol=1e-14)
    # Angles given in another convention are stored as seed angles of the same rotation.
    opk = pp.ExteriorOrientation(center, ANGLES, convention="opk")
    np.testing.assert_allclose(opk.R_camera_from_ground, pp.rotation_from_angles(ANGLES, "opk"), atol=TOLERANCE)
    np.testing.assert_allclose(opk.angles_rad("opk"), ANGLES, atol=1e-13)
    np.testing.assert_allclose(opk.angles_deg("opk"), np.degrees(ANGLES), atol=1e-11)
    assert "angles_rxryrz_deg" in repr(eo)


def test_not_a_rotation_raises_photopose_error():
    with pytest.raises(pp.Error) as raised:
        pp.ExteriorOrientation.from_matrix(np.diag([1.0, 1.0, -1.0]), [0, 0, 0])
    assert isinstance(raised.value, ValueError)
    assert str(raised.value)


def test_collinearity_equations_4_5():
    eo = pp.ExteriorOrientation([10.0, 20.0, 100.0], ANGLES)
    points = np.array([[12.0, 18.0, 0.0], [0.0, 30.0, 5.0], [10.0, 20.0, 200.0]])
    focal = 24000.0
    xy = pp.project_to_image_plane(eo, points, focal)
    uvw = (points - eo.center_in_ground) @ eo.R_camera_from_ground.T
    expected = -focal * uvw[:, :2] / uvw[:, 2:3]
    np.testing.assert_allclose(xy[:2], expected[:2], rtol=1e-13)
    # The third point lies above the camera (w > 0): not in front, NaN.
    assert np.isnan(xy[2]).all()
    ab = pp.project_to_normalized(eo, points)
    np.testing.assert_allclose(ab[:2] * focal, xy[:2], rtol=1e-13)


def test_camera_model_projection_and_its_inverse():
    camera = pp.Camera("OPENCV", [3000.0, 3010.0, 2000.0, 1500.0, -0.05, 0.01, 1e-4, -2e-4], "cv", 4000, 3000)
    assert camera.observation_unit == "px"
    assert camera.param_names == ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"]
    eo = pp.ExteriorOrientation([0.0, 0.0, 50.0], [0.02, -0.01, 0.5])
    rng = np.random.default_rng(1)
    points = np.c_[rng.uniform(-20, 20, (20, 2)), rng.uniform(0, 5, 20)]
    pixels = camera.project(eo, points)
    rays = camera.normalized_from_observations(pixels)
    np.testing.assert_allclose(rays, pp.project_to_normalized(eo, points), atol=1e-11)
    # COLMAP's camera: y down, so the seed's (a, b) is (u, -v); pixel = f (a, -b) + c without distortion.
    pinhole = pp.Camera("PINHOLE", [3000.0, 3010.0, 2000.0, 1500.0])
    ab = pp.project_to_normalized(eo, points)
    np.testing.assert_allclose(pinhole.project(eo, points),
                               np.c_[3000.0 * ab[:, 0] + 2000.0, -3010.0 * ab[:, 1] + 1500.0], rtol=1e-13)


def test_frame_camera_projects_through_film_to_pixels():
    fc = pp.FrameCamera(camera_id="uav", focal_length_um=8800.0, pixel_size_um=2.41, n_rows=3648,
                        n_columns=5472, principal_x_um=12.0, principal_y_um=-7.0)
    camera = pp.Camera.from_frame_camera(fc)
    assert camera.model == "FRAME" and camera.observation_unit == "um"
    eo = pp.ExteriorOrientation([0.0, 0.0, 100.0], [0.01, 0.02, 0.03])
    points = np.array([[5.0, -3.0, 0.0], [-20.0, 10.0, 2.0]])
    film = camera.project(eo, points)
    np.testing.assert_allclose(fc.film_from_pixel(fc.project(eo, points)), film, atol=1e-6)
    np.testing.assert_allclose(fc.pixel_from_film(fc.film_from_pixel([[100.0, 200.0]])), [[100.0, 200.0]], atol=1e-9)
    assert "FrameCamera(" in repr(fc) and "focal_length_um=8800.0" in repr(fc)


def test_wrong_parameter_count_names_the_model():
    with pytest.raises(ValueError, match=r"model PINHOLE takes 4 parameters \(fx, fy, cx, cy\), got 3"):
        pp.Camera("PINHOLE", [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="unknown name 'FISHEYE'"):
        pp.Camera("FISHEYE", [1.0])


@pytest.mark.parametrize("points, message", [
    (np.zeros((4, 2)), r"points_in_ground: expected an N x 3 array, got shape \(4, 2\)"),
    (np.zeros((2, 3, 3)), r"points_in_ground: expected an N x 3 array, got shape \(2, 3, 3\)"),
    (np.array([["a", "b", "c"]]), r"points_in_ground: expected an N x 3 array of numbers, got dtype <U1"),
    (None, r"points_in_ground: expected an N x 3 array, got None"),
    ("text", r"points_in_ground: expected an N x 3 array of numbers, got dtype <U4"),
    (object(), r"points_in_ground: expected an N x 3 array of numbers, got dtype object"),
])
def test_shape_and_dtype_errors_are_clear(points, message):
    eo = pp.ExteriorOrientation()
    with pytest.raises(ValueError, match=message):
        pp.project_to_normalized(eo, points)


def test_empty_and_other_dtypes_are_accepted():
    eo = pp.ExteriorOrientation([0.0, 0.0, 10.0], [0.0, 0.0, 0.0])
    assert pp.project_to_normalized(eo, np.empty((0, 3))).shape == (0, 2)
    assert pp.project_to_normalized(eo, []).shape == (0, 2)
    as_int = pp.project_to_normalized(eo, np.array([[1, 2, 0]], dtype=np.int32))
    as_f32 = pp.project_to_normalized(eo, np.array([[1, 2, 0]], dtype=np.float32))
    np.testing.assert_array_equal(as_int, as_f32)
    # A Fortran-ordered or strided view is read as the values it shows.
    points = np.asfortranarray(np.array([[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]]))
    np.testing.assert_array_equal(pp.project_to_normalized(eo, points),
                                  pp.project_to_normalized(eo, np.ascontiguousarray(points)))
    np.testing.assert_array_equal(pp.project_to_normalized(eo, points[::-1]),
                                  pp.project_to_normalized(eo, points)[::-1])
