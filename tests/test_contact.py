"""The stance foot's wrench rows (mpc/contact.py): the segment's contact wrench cone is the
set of wrenches that friction-bounded point forces along the foot can make."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.contact import ContactParams, StanceWrenchRows, foot_wrench_constraints

HALF_M = 0.045
CWC = ContactParams(yaw_moment="cwc")


def _inside(rows: tuple[np.ndarray, np.ndarray, np.ndarray], w: np.ndarray) -> bool:
    c, lo, hi = rows
    v = c @ w
    return bool(np.all(v <= hi + 1e-9) and np.all(v >= lo - 1e-9))


def _point_forces_wrench(rng: np.random.Generator, yaw: float, mu: float) -> np.ndarray:
    """[f; m] about the foot centre of 1-3 point forces on the segment, each inside the
    friction pyramid of the foot's own frame; a third of them all at one end."""
    a = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    lat = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    k = int(rng.integers(1, 4))
    xs = rng.uniform(-HALF_M, HALF_M, k)
    if rng.random() < 0.3:
        xs[:] = HALF_M * rng.choice([-1.0, 1.0])
    fz = rng.uniform(10.0, 100.0, k)
    ft = rng.uniform(-1.0, 1.0, (k, 2)) * mu * fz[:, None]
    f_total, m_total = np.zeros(3), np.zeros(3)
    for x, z, (t_a, t_l) in zip(xs, fz, ft, strict=True):
        f = t_a * a + t_l * lat + np.array([0.0, 0.0, z])
        f_total += f
        m_total += np.cross(x * a, f)
    return np.concatenate([f_total, m_total])


def test_every_wrench_of_point_forces_passes_the_yaw_rows() -> None:
    """Soundness of the closed form: the four cone rows hold for every wrench that point
    forces on the segment make (the rows of the world-frame pyramid are not this test's)."""
    rng = np.random.default_rng(0)
    for _ in range(3000):
        yaw = float(rng.uniform(-3.0, 3.0))
        c, _, hi = foot_wrench_constraints(yaw, CWC, HALF_M, HALF_M)
        v = c[-4:] @ _point_forces_wrench(rng, yaw, CWC.mu_box)
        assert np.all(v <= hi[-4:] + 1e-9)


def test_the_cone_is_tight_where_the_line_bound_is_not() -> None:
    """All the normal force at the toe: the foot holds exactly the yaw moment of its lateral
    force there, ``X f_lat``; 5 % more is refused. The line bound allowed 0.9 mu X f_z."""
    fz, f_lat = 100.0, 0.5 * CWC.mu_box * 100.0
    at_toe = np.array([0.0, f_lat, fz, 0.0, -HALF_M * fz, HALF_M * f_lat])
    rows = foot_wrench_constraints(0.0, CWC, HALF_M, HALF_M)
    assert _inside(rows, at_toe)
    assert not _inside(rows, at_toe * np.array([1, 1, 1, 1, 1, 1.05]))
    spin = np.array([0.0, 0.0, fz, 0.0, -0.999 * HALF_M * fz, 0.9 * CWC.mu_box * HALF_M * fz])
    assert _inside(foot_wrench_constraints(0.0, ContactParams(), HALF_M, HALF_M), spin)
    assert not _inside(rows, spin)


def test_stacked_rows_equal_the_rows_of_each_yaw() -> None:
    yaws = np.random.default_rng(1).uniform(-7.0, 7.0, (10, 2))
    for params in (ContactParams(), CWC):
        for toe in (HALF_M, 0.0):
            c, lo, hi = StanceWrenchRows(params, toe, toe).stack(yaws)
            for idx in np.ndindex(yaws.shape):
                one = foot_wrench_constraints(float(yaws[idx]), params, toe, toe)
                np.testing.assert_array_equal(c[idx], one[0])
                np.testing.assert_array_equal(lo[idx], one[1])
                np.testing.assert_array_equal(hi[idx], one[2])


def test_the_cone_can_span_more_than_the_centre_of_pressure_segment() -> None:
    """``cone_half_m``: the whole foot's cone with the CoP rows' margin; at the CoP limit
    it still holds a yaw moment (the CoP segment's own cone allows only ``X f_lat``)."""
    fz = 100.0
    at_limit = np.array([0.0, 0.0, fz, 0.0, -HALF_M * fz, 0.2 * CWC.mu_box * HALF_M * fz])
    assert not _inside(foot_wrench_constraints(0.0, CWC, HALF_M, HALF_M), at_limit)
    rows = foot_wrench_constraints(0.0, CWC, HALF_M, HALF_M, cone_half_m=0.075)
    assert _inside(rows, at_limit)
    c = StanceWrenchRows(CWC, HALF_M, HALF_M, 0.075).stack(np.zeros((1, 1)))[0]
    np.testing.assert_array_equal(c[0, 0], rows[0])


def test_an_unknown_yaw_moment_model_is_refused() -> None:
    with pytest.raises(ConfigError, match="yaw_moment"):
        ContactParams(yaw_moment="disc")
