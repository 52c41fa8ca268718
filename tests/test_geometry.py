"""Tests of the shared geometry helpers."""

import math

import numpy as np
import pytest

from gaitnet_mpc.geometry import (
    heading_axes,
    rot2,
    rotate2,
    skew,
    to_heading2,
    unwrap_angles,
    wrap_angle,
)


def test_skew_is_the_cross_product() -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(skew(a) @ b, np.cross(a, b), atol=1e-12)
    np.testing.assert_allclose(skew(a), -skew(a).T)


@pytest.mark.parametrize("yaw", [-3.0, -0.4, 0.0, 1.2, 2.9])
def test_planar_rotation_and_heading_axes_agree(yaw: float) -> None:
    r = rot2(yaw)
    e_x, e_y = heading_axes(yaw)
    np.testing.assert_allclose(r[:, 0], e_x)
    np.testing.assert_allclose(r[:, 1], e_y)
    np.testing.assert_allclose(r @ r.T, np.eye(2), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    # e_y is the left of e_x: their cross product points up.
    assert e_x[0] * e_y[1] - e_x[1] * e_y[0] == pytest.approx(1.0)


def test_wrap_angle_maps_into_minus_pi_pi() -> None:
    a = np.array([0.0, math.pi + 0.1, -math.pi - 0.1, 7.0, -7.0, 4 * math.pi])
    w = wrap_angle(a)
    assert np.all(w <= math.pi) and np.all(w > -math.pi)
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    np.testing.assert_allclose(np.sin(w), np.sin(a), atol=1e-12)
    assert float(wrap_angle(math.pi + 0.1)) == pytest.approx(-math.pi + 0.1)


@pytest.mark.parametrize(
    "angles", [[0.3], [0.1, 0.4, -0.2], [3.0, -3.0, 3.1], [-3.1, 3.1], [0.0, math.pi, 0.0]]
)
def test_unwrap_angles_is_numpys_unwrap(angles: list[float]) -> None:
    np.testing.assert_array_equal(unwrap_angles(angles), np.unwrap(np.array(angles)))


def test_rotate2_and_to_heading2_are_inverse_rotations() -> None:
    rng = np.random.default_rng(1)
    for yaw in rng.uniform(-4.0, 4.0, 10):
        v = rng.normal(size=2)
        np.testing.assert_allclose(rotate2(yaw, v), rot2(yaw) @ v, atol=1e-12)
        np.testing.assert_allclose(to_heading2(yaw, rotate2(yaw, v)), v, atol=1e-12)
    # the heading's forward axis, seen from the heading frame, is (1, 0)
    np.testing.assert_allclose(to_heading2(0.7, heading_axes(0.7)[0]), [1.0, 0.0], atol=1e-12)
