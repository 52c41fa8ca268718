"""SRBM MPC: time-varying condensing and wrench constraints."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.control.srbm_walk import centroidal_inertia_body
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.mpc.srbm import NU, NX, SRBMMPC
from gaitnet_mpc.robots import RobotModel, load_robot


@pytest.fixture(scope="module")
def mpc(humanoid: RobotModel) -> SRBMMPC:
    return SRBMMPC(humanoid.total_mass_kg, centroidal_inertia_body(humanoid), 0.075, 0.075)


def _horizon(h: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    x0 = np.zeros(NX)
    x0[5], x0[12] = 0.55, 1.0
    x_ref = np.tile(x0, (h + 1, 1))
    x_ref[:, 9] = 0.5
    dts = np.array([0.045] * 5 + [0.065] * 5)[:h]  # two steps with different dt
    contact = np.zeros((h, 2), dtype=bool)
    contact[:5, 0] = True
    contact[5:, 1] = True
    feet = np.zeros((h, 2, 3))
    feet[:, 0] = [0.0, 0.065, 0.0]
    feet[:, 1] = [0.12, -0.065, 0.0]
    return x0, x_ref, dts, contact, feet


def test_condensed_prediction_equals_stagewise_rollout(mpc: SRBMMPC) -> None:
    """Su/Sx use the true products of per-stage A_k (each stage has its own dt)."""
    h = mpc.config.horizon
    x0, x_ref, dts, _, feet = _horizon(h)
    rng = np.random.default_rng(0)
    u = rng.normal(scale=20.0, size=h * NU)
    sx, su = mpc.condense(x0, x_ref[:h], dts, feet)
    pred = (sx @ x0 + su @ u).reshape(h, NX)
    x = x0.copy()
    for k in range(h):
        a_k, b_k = mpc.stage_matrices(x_ref[k], feet[k], dts[k])
        x = a_k @ x + b_k @ u[NU * k : NU * k + NU]
        np.testing.assert_allclose(pred[k], x, atol=1e-10)


def test_free_fall_without_forces(mpc: SRBMMPC) -> None:
    h = mpc.config.horizon
    x0, x_ref, dts, _, feet = _horizon(h)
    sx, _ = mpc.condense(x0, x_ref[:h], dts, feet)
    vz = (sx @ x0).reshape(h, NX)[:, 11]
    np.testing.assert_allclose(vz, -9.81 * np.cumsum(dts))


def test_solution_respects_contact_schedule_and_friction(mpc: SRBMMPC) -> None:
    h = mpc.config.horizon
    x0, x_ref, dts, contact, feet = _horizon(h)
    plan = mpc.solve(x0, x_ref, dts, contact, feet, np.zeros((h, 2)))
    w = plan.wrenches
    mu_box = mpc.config.contact.mu_box
    for k in range(h):
        for i in range(2):
            f, m = w[k, i, :3], w[k, i, 3:]
            if not contact[k, i]:
                np.testing.assert_allclose(w[k, i], 0.0, atol=1e-6)
                continue
            assert 10.0 - 1e-6 <= f[2] <= 500.0 + 1e-6
            assert abs(f[0]) <= mu_box * f[2] + 1e-6
            assert abs(f[1]) <= mu_box * f[2] + 1e-6
            assert abs(m[0]) < 1e-6  # line foot along x: no moment about its axis
            assert -0.075 * f[2] - 1e-6 <= m[1] <= 0.075 * f[2] + 1e-6
    # it supports the weight on average
    mean_fz = np.mean(w[:, :, 2].sum(axis=1))
    assert mean_fz == pytest.approx(16.0 * 9.81, rel=0.15)


@pytest.mark.slow
def test_humanoid_walks_forward_with_srbm_mpc() -> None:
    """Closed loop, 3 s at 0.25 m/s on flat ground: progress, no fall, allowed footholds."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.srbm_walk import SRBMWalkController
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    robot = load_robot("humanoid3d")
    course = load_course("flat")
    sim = Simulator(robot, course)
    command = Command(vx_mps=0.25)
    summary = run_episode(
        sim, SRBMWalkController(robot, TerrainView(course), command), command, 3.0, progress=False
    )
    assert not summary["fell"]
    assert summary["distance_m"] > 0.5
    assert abs(summary["lateral_drift_m"]) < 0.2
    assert len(summary["footholds"]) >= 10
    assert summary["foothold_violations"] == 0
    assert summary["mpc"]["solves"] >= 250


def test_regularisation_about_weight_keeps_full_support(mpc: SRBMMPC) -> None:
    """Standing still on one foot under the CoM, the plan carries m g on every stage (a
    force regulariser about zero would plan less and let the CoM sag)."""
    h = mpc.config.horizon
    x0, x_ref, dts, contact, feet = _horizon(h)
    x_ref[:, 9] = 0.0
    contact[:] = [True, False]
    feet[:, 0] = [0.0, 0.0, 0.0]
    plan = mpc.solve(x0, x_ref, dts, contact, feet, np.zeros((h, 2)))
    np.testing.assert_allclose(plan.wrenches[:, 0, 2], 16.0 * 9.81, rtol=1e-3)
    np.testing.assert_allclose(plan.states[:, 5], 0.55, atol=1e-4)


def test_stage_weight_is_in_the_heading_frame(mpc: SRBMMPC) -> None:
    """Forward/lateral CoM weights follow the reference heading."""
    c = mpc.config
    q0, q90 = mpc.stage_weight(0.0), mpc.stage_weight(np.pi / 2)
    assert q0[3, 3] == pytest.approx(c.w_pos_m[0])
    assert q0[4, 4] == pytest.approx(c.w_pos_m[1])
    assert q90[3, 3] == pytest.approx(c.w_pos_m[1])  # world x is lateral when facing +y
    assert q90[4, 4] == pytest.approx(c.w_pos_m[0])
    assert q90[10, 10] == pytest.approx(c.w_vel[0])
    np.testing.assert_allclose(q90, q90.T)


def test_lip_foothold_gains_are_deadbeat_with_the_sway_orbit() -> None:
    """On the LIP, the Raibert law with the LIP gains cancels a velocity error in one step
    and its lateral fixed point is the sway orbit with the requested half-width."""
    from gaitnet_mpc.gait.lip import lip_gains

    z0, step, d = 0.52, 0.225, 0.07
    omega, k_v, offset, _ = lip_gains(z0, step, d)
    ch, sh = np.cosh(omega * step), np.sinh(omega * step)
    gain = 0.5 * step + k_v  # foothold per unit velocity

    def stance(v_td: float, side: float) -> float:
        """Lateral CoM velocity at the end of a stance on the foot placed by the law."""
        r = side * offset + gain * v_td  # foot relative to the CoM at touchdown
        return -r * omega * sh + v_td * ch

    v, side = 0.4, 1.0  # a large disturbance
    v = stance(v, side)
    side = -side
    for _ in range(6):  # after one step the velocity is on the orbit: +-V alternating
        v_next = stance(v, side)
        assert v_next == pytest.approx(-v, abs=1e-9)
        v, side = v_next, -side
    r = offset + gain * abs(v)
    assert r == pytest.approx(d)


def _walk(robot_name: str, vx: float, duration_s: float, pushes: tuple = ()) -> dict:
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.srbm_walk import SRBMWalkController
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.simulator import SimConfig, Simulator
    from gaitnet_mpc.terrain import load_course

    robot = load_robot(robot_name)
    course = load_course("flat")
    sim = Simulator(robot, course, SimConfig(pushes=pushes))
    command = Command(vx_mps=vx)
    controller = SRBMWalkController(robot, TerrainView(course), command)
    return run_episode(sim, controller, command, duration_s, progress=False)


@pytest.mark.slow
def test_humanoid_walks_at_half_a_metre_per_second() -> None:
    """Closed loop, 3 s at 0.5 m/s: tracks the speed and walks straight."""
    summary = _walk("humanoid3d", 0.5, 3.0)
    assert not summary["fell"]
    assert summary["distance_m"] > 1.1  # 1.25 m commanded after the 0.5 s ramp
    assert summary["speed_rmse_mps"] < 0.1
    assert abs(summary["lateral_drift_m"]) < 0.1
    assert summary["foothold_violations"] == 0


@pytest.mark.slow
def test_humanoid_recovers_from_a_sideways_push() -> None:
    """10 N s sideways (towards the stance foot, so the swinging foot cannot catch it)."""
    from gaitnet_mpc.sim.disturbances import Push

    push = Push.parse("t=1.5,fx=0,fy=50,dur=0.2")
    summary = _walk("humanoid3d", 0.5, 3.5, (push,))
    assert not summary["fell"]
    assert summary["lateral_drift_m"] > 0.1  # it was pushed, and caught itself
    assert summary["distance_m"] > 1.2


@pytest.mark.slow
def test_planar_biped_walks_with_srbm_mpc() -> None:
    """The planar reduction of the same MPC walks the point-foot biped at 0.5 m/s."""
    summary = _walk("biped2d", 0.5, 3.0)
    assert not summary["fell"]
    assert summary["distance_m"] > 1.0
    assert summary["speed_rmse_mps"] < 0.15
