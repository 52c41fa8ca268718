"""The reach rows of the CMPC QP (:mod:`gaitnet_mpc.mpc.kinematic_rows`): the humanoid's
leg geometry, and a sequential solve whose foothold reference lies beyond the leg ends
with the touchdown within reach of the hip, in both QP forms."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.control.kd_walk_config import KDWalkConfig, robot_kd_config
from gaitnet_mpc.mpc.centroidal_model import NX
from gaitnet_mpc.mpc.implicit_kd import KDConfig, KDIterate, KDSubproblem
from gaitnet_mpc.mpc.kinematic_rows import reach_geometry
from gaitnet_mpc.robots import load_robot

H = 10
MASS = 16.0
HIPS = ((0.009, 0.065, -0.13), (0.009, -0.065, -0.13))


def test_reach_geometry_of_the_humanoid() -> None:
    hips, leg_m, tilt_rad = reach_geometry(load_robot("humanoid3d"))
    assert leg_m == pytest.approx(0.44)  # thigh 0.22 + shank 0.22
    assert tilt_rad == pytest.approx(np.arccos(0.413 / 0.44), abs=0.01)  # standing hip
    left, right = np.reshape(hips, (2, 3))
    np.testing.assert_allclose(left, HIPS[0], atol=0.005)
    np.testing.assert_allclose(right, HIPS[1], atol=0.005)
    config = robot_kd_config(KDWalkConfig(), load_robot("humanoid3d"))  # on by default
    assert config.leg_reach_m == pytest.approx(0.44)
    off = robot_kd_config(KDWalkConfig(keep_feet_in_reach=False), load_robot("humanoid3d"))
    assert off.leg_reach_m is None


def test_the_planar_biped_has_no_reach_rows() -> None:
    assert robot_kd_config(KDWalkConfig(), load_robot("biped2d")).leg_reach_m is None


def _far_step(sub: KDSubproblem, n_iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """A sequential solve (no reference update) of a right step whose reference is
    0.6 m ahead of a standing CoM: the final right foothold and CoM path."""
    contact = np.ones((H, 2), dtype=bool)
    contact[:3, 1] = False  # the right foot swings, then lands at stage 3
    p_com = np.tile([0.0, 0.0, 0.55], (H + 1, 1))
    p_foot = np.zeros((H, 2, 3))
    p_foot[:, 0, 1], p_foot[:, 1, 1] = 0.065, -0.065
    p_foot_ref = p_foot.copy()
    p_foot_ref[:, 1, 0] = 0.6
    it = KDIterate.initial(p_com[0], p_com, p_foot, contact, MASS)
    x0 = np.zeros(NX)
    x0[:3] = MASS * p_com[0]
    pose_ref = np.zeros((H + 1, 6))
    pose_ref[:, :3] = MASS * p_com
    inputs = sub.inputs(
        it, x0, np.zeros((H + 1, 6)), pose_ref, p_foot_ref, p_com, np.full(H, 0.05),
        contact, np.zeros((H, 2)), None, p_foot[0],
    )  # fmt: skip
    for _ in range(n_iterations):
        step = sub.solve(it, inputs)
        it = it.apply(step, 1.0)
    return it.p_foot[3:, 1], it.p_com[3:H]


@pytest.mark.parametrize("qp_form", ["sparse", "condensed"])
def test_a_touchdown_beyond_the_leg_is_pulled_within_reach(qp_form: str) -> None:
    common = {"mass_kg": MASS, "horizon": H, "qp_form": qp_form, "w_p_foot": (1e3,) * 3}
    hips = sum(HIPS, ())
    free = KDSubproblem(KDConfig(**common))
    reach = KDSubproblem(
        KDConfig(**common, leg_reach_m=0.44, hip_offset_m=hips, reach_tilt_rad=0.35)
    )
    foot_free, _ = _far_step(free, 12)
    assert foot_free[0, 0] > 0.5  # nothing stops the QP from following the reference
    foot, com = _far_step(reach, 6)
    d = foot[0] - com[0] - np.array(HIPS[1])  # hip to foot at touchdown
    face = np.array([np.sin(0.35), 0.0, -np.cos(0.35)])  # the forward face
    assert face @ d == pytest.approx(0.44, abs=1e-6)  # binds: the foot goes as far as it may
    assert 0.1 < foot[0, 0] < 0.3  # ahead of the CoM, well short of the reference


def test_the_compiled_rows_are_the_module_docstrings_rows() -> None:
    """``qp_reach_rows`` (a compiled loop over the touchdowns) against the rows written out
    with NumPy on random iterates, yaws and foot bounds."""
    from types import SimpleNamespace

    from gaitnet_mpc.mpc.kinematic_rows import qp_reach_rows

    rng = np.random.default_rng(3)
    config = KDConfig(leg_reach_m=0.44, hip_offset_m=sum(HIPS, ()), reach_tilt_rad=0.35)
    contact = np.ones((H, 2), dtype=bool)
    contact[:3, 1] = contact[5:8, 0] = False  # touchdowns: right at 3, left at 8
    yaw = rng.uniform(-0.5, 0.5, (H, 2))
    it = SimpleNamespace(p_foot=rng.normal(0, 0.2, (H, 2, 3)), p_com=rng.normal(0, 0.2, (H + 1, 3)))
    lo = it.p_foot - rng.uniform(0, 0.3, (H, 2, 3))
    hi = it.p_foot + rng.uniform(0, 0.3, (H, 2, 3))
    lo[0, 0, 2] = -np.inf  # an unbounded axis
    active, normal, bound = qp_reach_rows(
        config, it, SimpleNamespace(contact=contact, foot_yaw_rad=yaw), lo, hi
    )  # type: ignore[arg-type]
    assert active.sum() == 2 and active[3, 1] and active[8, 0]
    for k, i in zip(*np.nonzero(active), strict=True):
        c, s = np.cos(yaw[k, i]), np.sin(yaw[k, i])
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        hip = rot @ np.array(HIPS[i])
        d = it.p_foot[k, i] - it.p_com[k] - hip
        for m, (sx, sy) in enumerate([(1, 0), (-1, 0), (0, 1), (0, -1)]):
            n = rot @ np.array([sx * np.sin(0.35), sy * np.sin(0.35), -np.cos(0.35)])
            np.testing.assert_allclose(normal[k, i, m], n, atol=1e-12)
            step = np.where(n > 0, lo[k, i] - it.p_foot[k, i], hi[k, i] - it.p_foot[k, i])
            closest = float(np.sum(np.where(n == 0, 0.0, step * n)))
            assert bound[k, i, m] == pytest.approx(max(0.44 - n @ d, closest), abs=1e-12)
    assert not normal[~active].any() and not bound[~active].any()
