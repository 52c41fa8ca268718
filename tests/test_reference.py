"""Reference trajectories f_ref / f_IK (Algorithm 1 lines 2-3 and 9, eqs. 11-12, 30)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import GaitSchedule, GaitScheduleConfig, SwingTrajectory
from gaitnet_mpc.kinematics.reference import (
    CentroidalReference,
    ReferenceConfig,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    update_reference,
)
from gaitnet_mpc.robots import FEET, RobotModel, load_robot

DT_S = 0.045
STEP_S = 5 * DT_S
ROBOTS = ["humanoid3d", "biped2d"]


@dataclass
class Setup:
    robot: RobotModel
    ws: ReferenceWorkspace
    q: np.ndarray  # (nq,) nominal standing configuration
    feet: dict[str, np.ndarray]  # foot -> (3,) foot-centre positions at q


def _setup(name: str, config: ReferenceConfig | None = None) -> Setup:
    robot = load_robot(name)
    ws = ReferenceWorkspace(robot, config)
    q, _ = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
    data = robot.pin_model.createData()
    pin.framesForwardKinematics(robot.pin_model, data, q)
    feet = {f: data.oMf[robot.pin_foot_frame_ids[f]].translation.copy() for f in FEET}
    return Setup(robot, ws, q, feet)


@pytest.fixture(scope="module", params=ROBOTS)
def setup(request: pytest.FixtureRequest) -> Setup:
    return _setup(request.param)


@pytest.fixture(scope="module")
def humanoid() -> Setup:
    return _setup("humanoid3d")


def _schedule(t_s: float = 0.0) -> GaitSchedule:
    sched = GaitSchedule(GaitScheduleConfig(default_dt_s=DT_S))
    sched.advance_to(t_s)
    return sched


def _walk(
    s: Setup, vx: float, t_s: float = 0.0, yaw_rate: float = 0.0, **kw: object
) -> tuple[CentroidalReference, dict[str, np.ndarray], GaitSchedule]:
    """Walking reference with explicit neutral footholds (CoM at touchdown + v T / 2)."""
    sched = _schedule(t_s)
    timing = ReferenceTiming.from_horizon(sched.horizon())
    swing, stance = sched.swing_foot, sched.stance_foot
    c0 = float(pin.centerOfMass(s.robot.pin_model, s.robot.pin_model.createData(), s.q)[0])
    t_td = STEP_S - t_s  # touchdown of the swing foot
    footholds = {swing: s.feet[swing].copy()[None], stance: s.feet[stance].copy()[None]}
    footholds[swing][0, 0] = c0 + vx * (t_td + 0.5 * STEP_S)
    footholds[stance][0, 0] = c0 + vx * (t_td + 1.5 * STEP_S)
    ref = make_reference(
        s.robot,
        s.q,
        timing,
        (vx, 0.0, yaw_rate),
        footholds,
        p_liftoff_m={swing: s.feet[swing]},
        workspace=s.ws,
        **kw,  # type: ignore[arg-type]
    )
    return ref, footholds, sched


def _foot_fk(s: Setup, q: np.ndarray) -> np.ndarray:
    """(N, 2, 3) foot-centre positions of configurations q (N, nq)."""
    data = s.robot.pin_model.createData()
    out = np.empty((q.shape[0], 2, 3))
    for k in range(q.shape[0]):
        pin.framesForwardKinematics(s.robot.pin_model, data, q[k])
        for i, f in enumerate(FEET):
            out[k, i] = data.oMf[s.robot.pin_foot_frame_ids[f]].translation
    return out


# ------------------------------------------------------------------------ standing
def test_standing_double_support_has_zero_momentum(setup: Setup) -> None:
    """Zero command, both feet down over the whole horizon: the reference stands still."""
    timing = ReferenceTiming(np.full(10, DT_S), np.ones((10, 2), dtype=bool))
    ref = make_reference(setup.robot, setup.q, timing, (0.0, 0.0, 0.0), workspace=setup.ws)
    assert ref.q_ref.shape == (11, setup.robot.pin_model.nq)
    assert ref.v_ref.shape == (11, setup.robot.nv)
    assert ref.h_ref.shape == ref.H_ref.shape == (11, 6)
    assert ref.p_foot_ref.shape == (11, 2, 3) and ref.reachable.all()
    np.testing.assert_allclose(ref.h_ref, 0.0, atol=1e-9)
    np.testing.assert_allclose(ref.v_ref, 0.0, atol=1e-9)
    np.testing.assert_allclose(ref.p_com_ref, np.tile(ref.p_com_ref[0], (11, 1)), atol=1e-12)
    # the nominal pose is reproduced: same CoM height, feet where they are
    com_now = pin.centerOfMass(setup.robot.pin_model, setup.ws.data, setup.q)
    np.testing.assert_allclose(ref.p_com_ref[0], com_now, atol=2e-4)
    for i, f in enumerate(FEET):
        np.testing.assert_allclose(ref.p_foot_ref[:, i], np.tile(setup.feet[f], (11, 1)))


def test_standing_single_stance_has_zero_momentum() -> None:
    """Single-stance horizon (one step): with the swing foot's target at its current
    position and no apex the swing foot does not move, so the momentum is zero."""
    s = _setup("humanoid3d", ReferenceConfig(swing_apex_height_m=0.0))
    contact = np.tile([True, False], (5, 1))
    timing = ReferenceTiming(np.full(5, DT_S), contact)
    ref = make_reference(
        s.robot, s.q, timing, (0, 0, 0), {"right": s.feet["right"]}, workspace=s.ws
    )
    np.testing.assert_allclose(ref.h_ref, 0.0, atol=1e-9)
    np.testing.assert_allclose(ref.p_com_ref, np.tile(ref.p_com_ref[0], (6, 1)), atol=1e-12)


# ------------------------------------------------------------------- forward walking
def test_forward_command_moves_com_at_commanded_speed(setup: Setup) -> None:
    """p_com_ref advances by v t and l_x = m v.

    Tolerances: p_com_ref is the exact CoM of q_ref, which the one-step fixed point puts on
    the commanded path up to a residual eps (< 1 mm, checked). l = m J_c(q) v_ref with
    v_ref the 3-point derivative D q of the configuration path, i.e. m D p_com up to
    O(dt^2) curvature terms (2 % of m v allowed), and D p_com = v + D eps (D is exact on
    the straight path), |D eps| <= ||D||_inf max|eps|.
    """
    vx = 0.3
    ref, _, _ = _walk(setup, vx)
    assert ref.all_reachable
    m = setup.ws.mass_kg
    eps = ref.p_com_ref[:, 0] - (ref.p_com_ref[0, 0] + vx * ref.times_s)
    assert np.abs(eps).max() < 1e-3
    ground_z = ref.p_foot_ref[0, 0, 2] - setup.robot.spec.foot_contact_radius_m
    np.testing.assert_allclose(ref.p_com_ref[:, 2], ground_z + setup.ws.com_height_m, atol=1e-3)
    d_norm = np.abs(ref.timing.derivative_matrix).sum(axis=1).max()  # ||D||_inf = 4 / dt
    tol = m * d_norm * np.abs(eps).max() + 0.02 * m * vx
    np.testing.assert_allclose(ref.h_ref[:, 0], m * vx, atol=tol)
    assert tol < 0.15 * m * vx  # the bound is meaningful
    np.testing.assert_allclose(ref.h_ref[:, 0].mean(), m * vx, rtol=0.02)


def test_com_iterations_tighten_the_com_path() -> None:
    s = _setup("humanoid3d", ReferenceConfig(com_iterations=2))
    vx = 0.3
    ref, _, _ = _walk(s, vx)
    eps = ref.p_com_ref[:, 0] - (ref.p_com_ref[0, 0] + vx * ref.times_s)
    assert np.abs(eps).max() < 5e-5
    np.testing.assert_allclose(ref.h_ref[:, 0], s.ws.mass_kg * vx, rtol=0.01)


def test_stance_feet_fixed_and_swing_reaches_target(setup: Setup) -> None:
    ref, footholds, sched = _walk(setup, 0.3)
    swing, stance = sched.swing_foot, sched.stance_foot
    i_sw, i_st = FEET.index(swing), FEET.index(stance)
    contact = ref.timing.contact
    # stance foot: fixed through step 0 (stages 0..4 and boundary 5)
    assert contact[:5, i_st].all()
    np.testing.assert_array_equal(ref.p_foot_ref[:6, i_st], np.tile(setup.feet[stance], (6, 1)))
    # swing foot lands on its target at the end of its step and stays there
    np.testing.assert_array_equal(ref.p_foot_ref[5:, i_sw], np.tile(footholds[swing][0], (6, 1)))
    # the stance foot lifts off at boundary 5 toward its next target (touchdown beyond h)
    assert ref.p_foot_ref[7, i_st, 2] > setup.feet[stance][2] + 0.03
    # swing path = SwingTrajectory (obstacle-free) at the boundary times
    traj = SwingTrajectory(setup.feet[swing], footholds[swing][0], STEP_S, 0.06)
    np.testing.assert_allclose(ref.p_foot_ref[:6, i_sw], traj.position(ref.times_s[:6]), atol=1e-12)
    # IK reaches every target exactly
    np.testing.assert_allclose(_foot_fk(setup, ref.q_ref), ref.p_foot_ref, atol=1e-8)


def test_partial_first_stage_mid_swing(humanoid: Setup) -> None:
    """0.06 s into step 0: boundary 0 = now, the swing phase continues from lift-off."""
    s = humanoid
    ref, footholds, sched = _walk(s, 0.3, t_s=0.06)
    hz = sched.horizon()
    np.testing.assert_allclose(ref.dts_s[0], hz.first_stage_remaining_s)
    np.testing.assert_allclose(ref.timing.time_in_step_s, 0.06)
    i_sw = FEET.index(sched.swing_foot)
    traj = SwingTrajectory(s.feet[sched.swing_foot], footholds[sched.swing_foot][0], STEP_S)
    # boundary 4 is the touchdown (0.06 s + 4 stages = one step); the foot then stands
    np.testing.assert_allclose(
        ref.p_foot_ref[:5, i_sw], traj.position(0.06 + ref.times_s[:5]), atol=1e-12
    )
    target = footholds[sched.swing_foot][0]
    np.testing.assert_array_equal(ref.p_foot_ref[4:10, i_sw], np.tile(target, (6, 1)))
    np.testing.assert_allclose(ref.swing_phase[0, i_sw], 0.06 / STEP_S)
    # step 2 starts inside the horizon: the first swing foot lifts off again toward a
    # neutral-point fallback target, and everything stays reachable
    assert ref.footholds_m[sched.swing_foot].shape == (3, 3)
    assert ref.all_reachable


def test_configuration_and_velocity_conventions(humanoid: Setup) -> None:
    """q_ref's trunk is (p_base_ref, rot_base_ref); v_ref is Pinocchio's local velocity of
    the path."""
    s = humanoid
    ref, _, sched = _walk(s, 0.3, yaw_rate=0.5)
    assert ref.all_reachable
    quat = np.array([pin.Quaternion(r).coeffs() for r in ref.rot_base_ref])  # (h+1, 4) xyzw
    quat_sign = np.sign(np.sum(quat * ref.q_ref[:, 3:7], axis=1))[:, None]
    np.testing.assert_allclose(quat * quat_sign, ref.q_ref[:, 3:7], atol=1e-12)
    np.testing.assert_allclose(ref.p_base_ref, ref.q_ref[:, :3])
    np.testing.assert_allclose(ref.p_base_ref, ref.q_ref[:, :3])
    # yaw rate: body angular velocity (0, 0, 0.5) for an upright trunk
    np.testing.assert_allclose(ref.v_ref[:, 3:6], np.tile([0, 0, 0.5], (11, 1)), atol=1e-9)
    np.testing.assert_allclose(np.diff(ref.yaw_ref_rad), 0.5 * ref.dts_s)
    # v_ref agrees with Pinocchio's central difference on the manifold to O(dt^2)
    m = s.robot.pin_model
    for k in range(1, 10):
        fwd = pin.difference(m, ref.q_ref[k], ref.q_ref[k + 1])
        bwd = pin.difference(m, ref.q_ref[k], ref.q_ref[k - 1])
        v_fd = (fwd - bwd) / (ref.times_s[k + 1] - ref.times_s[k - 1])
        np.testing.assert_allclose(ref.v_ref[k, :6], v_fd[:6], atol=2e-3)
    # the stance foot keeps its position and heading while the trunk turns
    np.testing.assert_allclose(_foot_fk(s, ref.q_ref), ref.p_foot_ref, atol=1e-8)
    data = s.robot.pin_model.createData()
    i_st = FEET.index(sched.stance_foot)
    for k in range(6):
        pin.framesForwardKinematics(s.robot.pin_model, data, ref.q_ref[k])
        rot = data.oMf[s.robot.pin_foot_frame_ids[sched.stance_foot]].rotation
        assert abs(np.arctan2(rot[1, 0], rot[0, 0])) < 1e-9
        assert abs(ref.foot_yaw_ref_rad[k, i_st]) < 1e-12
    # the swing foot lands facing the trunk heading at touchdown
    np.testing.assert_allclose(ref.foot_yaw_ref_rad[5:, 1 - i_st], 0.5 * ref.times_s[5])


# ------------------------------------------------------------------- centroidal pose
def test_h_ref_is_eq11_and_H_ref_is_riemann(setup: Setup) -> None:
    ref, _, _ = _walk(setup, 0.3)
    m = setup.ws.mass_kg
    data = setup.robot.pin_model.createData()
    for k in range(ref.horizon + 1):
        a_g = pin.computeCentroidalMap(setup.robot.pin_model, data, ref.q_ref[k])
        np.testing.assert_allclose(ref.h_ref[k], a_g @ ref.v_ref[k], atol=1e-10)
        np.testing.assert_allclose(  # the compiled forward pass against Pinocchio's
            ref.p_com_ref[k],
            pin.centerOfMass(setup.robot.pin_model, data, ref.q_ref[k]),
            atol=1e-12,
        )
    np.testing.assert_allclose(ref.H_ref[:, :3], m * ref.p_com_ref, atol=1e-12)
    np.testing.assert_allclose(
        np.diff(ref.H_ref[:, 3:], axis=0), ref.h_ref[:-1, 3:] * ref.dts_s[:, None], atol=1e-12
    )
    np.testing.assert_allclose(ref.H_ref[0, 3:], 0.0)
    # the linear Riemann sum of l agrees with m p_com to O(dt)
    riemann_lin = m * ref.p_com_ref[0] + np.cumsum(ref.h_ref[:-1, :3] * ref.dts_s[:, None], 0)
    np.testing.assert_allclose(riemann_lin, ref.H_ref[1:, :3], atol=m * 0.01 * 0.3 * 0.5)


def test_pose0_angular_offsets_H(humanoid: Setup) -> None:
    ref0, _, _ = _walk(humanoid, 0.3)
    ref1, _, _ = _walk(humanoid, 0.3, pose0_angular_kgm2=np.array([1.0, -2.0, 3.0]))
    np.testing.assert_allclose(ref1.H_ref[:, 3:] - ref0.H_ref[:, 3:], [[1.0, -2.0, 3.0]] * 11)


def _eq30_vs_riemann(name: str, refine: int) -> np.ndarray:
    """max |H_eq30 - H_riemann| (6,) over the same continuous motion sampled with
    ``dt = DT_S / refine`` (two steps of 5 * refine stages)."""
    out = []
    for method in ("riemann", "eq30"):
        s = _setup(name, ReferenceConfig(pose_method=method))
        n = 5 * refine
        contact = np.zeros((2 * n, 2), dtype=bool)
        contact[:n, 0] = contact[n:, 1] = True  # right swings first
        timing = ReferenceTiming(np.full(2 * n, DT_S / refine), contact, stages_per_step=n)
        footholds = {"right": s.feet["right"] + [0.1, 0, 0], "left": s.feet["left"] + [0.2, 0, 0]}
        ref = make_reference(s.robot, s.q, timing, (0.4, 0, 0), footholds, workspace=s.ws)
        out.append(ref.H_ref[::refine])
    return np.abs(out[1] - out[0]).max(axis=0)


@pytest.mark.parametrize("name", ROBOTS)
def test_eq30_agrees_with_riemann_to_first_order(name: str) -> None:
    coarse = _eq30_vs_riemann(name, 1)
    fine = _eq30_vs_riemann(name, 2)
    # O(dt): halving dt roughly halves the gap (both are left Riemann sums of h)
    assert np.max(fine) < 0.7 * np.max(coarse)
    assert np.max(coarse) < 0.2  # kg m / kg m^2 over 0.45 s of 0.4 m/s walking


# ------------------------------------------------------------------------------ f_IK
def test_update_moves_com_and_footholds(setup: Setup) -> None:
    ref, _, sched = _walk(setup, 0.3)
    shift = np.array([0.02, 0.0, 0.0])
    new = update_reference(setup.robot, ref, ref.p_foot_ref + shift, ref.p_com_ref + shift)
    np.testing.assert_allclose(new.p_com_ref - ref.p_com_ref, np.tile(shift, (11, 1)), atol=1e-3)
    # every foothold a foot stands on inside the horizon moves with the iterate; the swing
    # foot's past lift-off point and the stance foot's next target (touchdown after the
    # horizon: no row in contact) keep their values
    swing, stance = sched.swing_foot, sched.stance_foot
    i_sw, i_st = FEET.index(swing), FEET.index(stance)
    np.testing.assert_allclose(new.p_foot_ref[5:, i_sw], ref.p_foot_ref[5:, i_sw] + shift)
    np.testing.assert_allclose(new.p_foot_ref[:6, i_st], ref.p_foot_ref[:6, i_st] + shift)
    fh_sw, fh_st = ref.footholds_m[swing], ref.footholds_m[stance]
    np.testing.assert_allclose(new.footholds_m[swing], [fh_sw[0], fh_sw[1] + shift])
    np.testing.assert_allclose(new.footholds_m[stance], [fh_st[0] + shift, fh_st[1]])
    # swings are re-interpolated between the new end points with the same shape
    traj = SwingTrajectory(fh_sw[0], fh_sw[1] + shift, STEP_S)
    np.testing.assert_allclose(new.p_foot_ref[:6, i_sw], traj.position(ref.times_s[:6]), atol=1e-12)
    traj = SwingTrajectory(fh_st[0] + shift, fh_st[1], STEP_S)
    np.testing.assert_allclose(
        new.p_foot_ref[5:, i_st], traj.position(ref.times_s[5:] - STEP_S), atol=1e-12
    )
    assert new.all_reachable
    np.testing.assert_allclose(_foot_fk(setup, new.q_ref), new.p_foot_ref, atol=1e-8)
    np.testing.assert_allclose(new.H_ref[:, :3], setup.ws.mass_kg * new.p_com_ref, atol=1e-12)
    # the momentum is that of a shifted motion: unchanged to the fixed-point residual
    np.testing.assert_allclose(new.h_ref[:, :3], ref.h_ref[:, :3], atol=0.1)
    # ref is not modified; a None update reproduces it
    same = update_reference(setup.robot, ref, None, None)
    np.testing.assert_allclose(same.q_ref, ref.q_ref, atol=1e-6)


def test_update_with_stage_iterates_and_mapping(humanoid: Setup) -> None:
    s = humanoid
    ref, footholds, sched = _walk(s, 0.3)
    swing = sched.swing_foot
    i_sw = FEET.index(swing)
    # per-stage iterates; a swinging foot's rows are ignored (garbage there)
    stage_iter = ref.p_foot_ref[:-1].copy()
    stage_iter[~ref.timing.contact] = 99.0
    stage_iter[5:, i_sw] += [0.03, 0.01, 0.0]  # new touchdown of the swing foot
    new = update_reference(s.robot, ref, stage_iter, None)
    target = footholds[swing][0] + [0.03, 0.01, 0.0]
    np.testing.assert_allclose(new.footholds_m[swing][1], target)
    np.testing.assert_allclose(new.p_foot_ref[5:, i_sw], np.tile(target, (6, 1)))
    np.testing.assert_allclose(new.p_foot_ref[0, i_sw], ref.p_foot_ref[0, i_sw])  # lift-off
    # the swing is interpolated toward the new touchdown with the same shape
    traj = SwingTrajectory(s.feet[swing], target, STEP_S, 0.06)
    np.testing.assert_allclose(new.p_foot_ref[:6, i_sw], traj.position(ref.times_s[:6]), atol=1e-12)
    # the same through the mapping form
    by_map = update_reference(s.robot, ref, {swing: [target]}, None)
    np.testing.assert_allclose(by_map.p_foot_ref, new.p_foot_ref, atol=1e-12)
    np.testing.assert_allclose(by_map.q_ref, new.q_ref, atol=1e-12)


def test_update_with_new_dt_rescales_velocity(humanoid: Setup) -> None:
    s = humanoid
    ref, _, _ = _walk(s, 0.3)
    new = update_reference(s.robot, ref, None, None, ref.dts_s * 2.0)
    np.testing.assert_allclose(new.times_s, 2.0 * ref.times_s)
    np.testing.assert_allclose(new.swing_phase, ref.swing_phase)  # step starts at k = 0
    np.testing.assert_allclose(new.q_ref, ref.q_ref, atol=1e-6)
    np.testing.assert_allclose(new.v_ref, 0.5 * ref.v_ref, atol=1e-4)
    np.testing.assert_allclose(new.h_ref, 0.5 * ref.h_ref, atol=2e-3)


def test_unreachable_foothold_is_flagged(setup: Setup) -> None:
    sched = _schedule()
    timing = ReferenceTiming.from_horizon(sched.horizon())
    swing = sched.swing_foot
    far = setup.feet[swing] + [1.0, 0.0, 0.0]
    ref = make_reference(setup.robot, setup.q, timing, (0, 0, 0), {swing: far}, workspace=setup.ws)
    assert ref.reachable[0]
    assert not ref.reachable[5:].any()  # standing on the far foothold
    assert np.all(np.isfinite(ref.q_ref)) and np.all(np.isfinite(ref.h_ref))
    np.testing.assert_allclose(ref.p_foot_ref[5, FEET.index(swing)], far)
    # f_IK flags it too, and a foothold moved back in reach clears the flag
    back = update_reference(setup.robot, ref, {swing: setup.feet[swing]}, None)
    assert back.all_reachable


def test_biped_ignores_lateral_iterates() -> None:
    s = _setup("biped2d")
    ref, _, _ = _walk(s, 0.3)
    shift = np.array([0.02, 0.5, 0.0])  # the y entry is ignored by the planar robot
    new = update_reference(s.robot, ref, ref.p_foot_ref + shift, ref.p_com_ref + shift)
    np.testing.assert_allclose(new.p_com_ref[:, 0] - ref.p_com_ref[:, 0], 0.02, atol=1e-3)
    np.testing.assert_allclose(new.p_com_ref[:, 1], ref.p_com_ref[:, 1])
    np.testing.assert_allclose(new.p_foot_ref[:, :, 1], ref.p_foot_ref[:, :, 1])
    np.testing.assert_allclose(ref.h_ref[:, 1], 0.0, atol=1e-12)  # no lateral motion
    assert new.all_reachable


# --------------------------------------------------------------------------- inputs
def test_timing_from_horizon() -> None:
    sched = _schedule(0.1)  # stage 2 of step 0, 0.01 s into it
    hz = sched.horizon()
    t = ReferenceTiming.from_horizon(hz)
    np.testing.assert_allclose(t.time_in_step_s, 0.1)
    np.testing.assert_allclose(t.dts_s[0], 3 * DT_S - 0.1)
    np.testing.assert_allclose(t.dts_s[1:], hz.dts_s[1:])
    np.testing.assert_array_equal(t.contact, hz.contact)
    full = ReferenceTiming.from_horizon(hz, partial_first_stage=False)
    np.testing.assert_allclose(full.time_in_step_s, 2 * DT_S)
    np.testing.assert_allclose(full.dts_s, hz.dts_s)
    d = t.derivative_matrix
    x = np.sin(t.times_s)
    np.testing.assert_allclose(d @ x, np.gradient(x, t.times_s, edge_order=2), atol=1e-12)


def test_command_object_and_horizon_are_accepted(humanoid: Setup) -> None:
    s = humanoid
    hz = _schedule().horizon()
    a = make_reference(s.robot, s.q, hz, Command(vx_mps=0.3), workspace=s.ws)
    b = make_reference(
        s.robot, s.q, ReferenceTiming.from_horizon(hz), (0.3, 0, 0), {}, workspace=s.ws
    )
    np.testing.assert_array_equal(a.q_ref, b.q_ref)
    assert a.all_reachable  # neutral-point fallback footholds


def test_invalid_inputs_raise(humanoid: Setup) -> None:
    s = humanoid
    timing = ReferenceTiming.from_horizon(_schedule().horizon())
    with pytest.raises(ConfigError):
        ReferenceTiming(np.array([0.1, -0.1]), np.ones((2, 2), dtype=bool))
    with pytest.raises(ConfigError):
        ReferenceTiming(np.array([0.1, 0.1]), np.ones((3, 2), dtype=bool))
    with pytest.raises(ConfigError):
        ReferenceConfig(com_iterations=-1)
    with pytest.raises(ConfigError):
        ReferenceConfig(pose_method="trapezoid")  # type: ignore[arg-type]
    with pytest.raises(ConfigError):
        make_reference(s.robot, s.q[:5], timing, (0, 0, 0), workspace=s.ws)
    with pytest.raises(ConfigError):
        make_reference(s.robot, s.q, timing, (0, 0), workspace=s.ws)
    with pytest.raises(ConfigError):
        make_reference(s.robot, s.q, timing, (0, 0, 0), {"left": [[0, 0]]}, workspace=s.ws)
    ref = make_reference(s.robot, s.q, timing, (0, 0, 0), workspace=s.ws)
    with pytest.raises(ConfigError):
        update_reference(s.robot, ref, np.zeros((4, 2, 3)), None)
    with pytest.raises(ConfigError):
        update_reference(s.robot, ref, None, np.zeros((3, 3)))
    with pytest.raises(ConfigError):
        update_reference(s.robot, ref, None, None, np.ones(3))
    with pytest.raises(ConfigError):
        update_reference(load_robot("humanoid3d"), ref, None, None)


@pytest.mark.parametrize("yaw_rate", [0.0, 0.8])
def test_compiled_trunk_placement_is_the_python_loop(humanoid: Setup, yaw_rate: float) -> None:
    """``ReferenceWorkspace.place_trunk`` (one compiled call) gives bitwise the
    configurations, trunk positions and reachability of the Python fixed point, with and
    without foot headings that differ from the trunk's (a turning walk), and with
    unreachable targets."""
    from dataclasses import replace

    import gaitnet_mpc.kinematics.reference as reference

    s = humanoid
    ref, _, _ = _walk(s, 0.6, yaw_rate=yaw_rate)
    rng = np.random.default_rng(3)
    targets = ref.p_com_ref + rng.normal(scale=0.03, size=ref.p_com_ref.shape)
    feet = ref.p_foot_ref.copy()
    feet[-1, 0, 0] += 0.5  # out of the leg's reach
    plan = reference.foot_plan(
        ref.foothold_index, ref.swing_phase, ref.footholds_m, ref.foothold_yaw_rad,
        ref.time_in_swing_s, s.ws.config.swing_apex_height_m, False,
    )  # fmt: skip
    for p_foot in (plan.p_foot_m, feet):
        plan = replace(plan, p_foot_m=p_foot)
        args = (s.ws, plan, targets, ref.p_base_ref, ref.yaw_ref_rad)
        compiled = reference._place_trunk(*args)
        legs, s.ws._leg_arrays = s.ws._leg_arrays, None  # the Python loop
        try:
            python = reference._place_trunk(*args)
        finally:
            s.ws._leg_arrays = legs
        for a, b in zip(compiled, python, strict=True):
            np.testing.assert_array_equal(a, b)
    assert not python[3][-1] and python[3].any()  # the last boundary is out of reach
