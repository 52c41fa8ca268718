"""Tests of gaitnet_mpc.gait: contact schedule with per-step dt, swing trajectories, footholds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import (
    GaitSchedule,
    GaitScheduleConfig,
    RaibertConfig,
    RaibertHeuristic,
    StepDtLockedError,
    SwingConfig,
    SwingTrajectory,
    obstacle_array,
)
from gaitnet_mpc.gait.swing import swing_profile
from gaitnet_mpc.robots.spec import FEET

TICK_S = 0.001  # 1 kHz control loop


def _run_with_dts(sched: GaitSchedule, dts: list[float], t_end_s: float) -> list[float]:
    """Tick at 1 kHz; at each step start set the next dt from ``dts``; returns start times."""
    starts = [sched.step_start_time_s]
    sched.set_step_dt(dts[0])
    n = round(t_end_s / TICK_S)
    for i in range(1, n + 1):
        if sched.advance_to(i * TICK_S):
            starts.append(sched.step_start_time_s)
            assert sched.at_step_start
            sched.set_step_dt(dts[min(sched.step_index, len(dts) - 1)])
        else:
            assert not sched.at_step_start
    return starts


# ----------------------------------------------------------------------------------------------
# schedule
# ----------------------------------------------------------------------------------------------


def test_step_boundaries_follow_per_step_dt() -> None:
    sched = GaitSchedule()
    dts = [0.045, 0.06, 0.05]
    starts = _run_with_dts(sched, dts, 0.76)
    expected = np.cumsum([0.0, *(5 * d for d in dts)])[:3]  # 0, 0.225, 0.525
    assert np.allclose(starts, expected, atol=1e-12)
    assert sched.step_index == 2
    assert sched.current_step_dt_s == pytest.approx(0.05)
    assert sched.step_durations_s == pytest.approx([0.225, 0.30])
    assert [r.swing_foot for r in sched.step_log] == ["right", "left"]
    # Inside step 2 (starts 0.525, dt 0.05): stage boundaries every 0.05 s.
    assert sched.time_in_step_s == pytest.approx(0.76 - 0.525)
    assert sched.stage_in_step == 4
    assert sched.stage_start_time_s == pytest.approx(0.525 + 4 * 0.05)
    assert sched.first_stage_remaining_s == pytest.approx(0.775 - 0.76)
    assert sched.time_left_in_step_s == pytest.approx(0.775 - 0.76)
    assert sched.phase_in_step == pytest.approx((0.76 - 0.525) / 0.25)


def test_stage_boundaries_inside_a_step() -> None:
    sched = GaitSchedule()
    sched.advance_to(0.225)  # step 1 starts exactly on the boundary
    assert sched.step_index == 1 and sched.at_step_start
    assert sched.swing_foot == "left" and sched.stance_foot == "right"
    sched.set_step_dt(0.06)
    start = sched.step_start_time_s
    for k in range(5):
        sched.advance_to(start + k * 0.06 + 1e-4)
        assert sched.stage_in_step == k
        assert sched.stage_start_time_s == pytest.approx(start + k * 0.06)
        bounds = sched.horizon_stage_boundaries_s()
        assert bounds.shape == (11,)
        assert bounds[0] == pytest.approx(start + k * 0.06)
        assert bounds[5 - k] == pytest.approx(start + 0.30)  # end of this step
        assert sched.first_stage_remaining_s == pytest.approx(0.06 - 1e-4)
        assert 0.0 <= sched.phase_in_step < 1.0
    sched.advance_to(start + 0.30)
    assert sched.step_index == 2 and sched.stage_in_step == 0


def test_horizon_contact_mask_aligned_with_current_stage() -> None:
    sched = GaitSchedule(GaitScheduleConfig(first_swing_foot="left"))
    left, right = FEET.index("left"), FEET.index("right")
    for i in range(1, 700):
        sched.advance_to(i * TICK_S)
        mask = sched.horizon_contact()
        assert mask.shape == (10, 2) and mask.dtype == bool
        assert np.all(mask.sum(axis=1) == 1)  # exactly one stance foot, no double support
        k = sched.stage_in_step
        steps = sched.horizon_step_index()
        assert np.array_equal(steps, (k + np.arange(10)) // 5)
        assert np.array_equal(sched.horizon_stage_in_step(), (k + np.arange(10)) % 5)
        # stage 0 is the current stage; the stance foot swaps exactly at step changes
        assert mask[0, FEET.index(sched.stance_foot)]
        swaps = np.flatnonzero(np.any(mask[1:] != mask[:-1], axis=1)) + 1
        assert np.array_equal(swaps, np.flatnonzero(np.diff(steps)) + 1)
        swing_col = left if sched.step_index % 2 == 0 else right
        assert np.array_equal(mask[:, swing_col], steps % 2 == 1)


def test_horizon_dts_use_next_step_preset() -> None:
    sched = GaitSchedule()
    sched.set_step_dt(0.05)
    sched.advance_to(0.12)  # stage 2 of step 0
    assert sched.stage_in_step == 2
    assert np.allclose(sched.horizon_dts(), [0.05] * 3 + [0.045] * 7)
    sched.set_next_step_dt(0.07)
    assert np.allclose(sched.horizon_dts(), [0.05] * 3 + [0.07] * 7)
    assert sched.horizon().dts_s.shape == (10,)
    sched.advance_to(0.25)  # step 0 ended at 0.25: step 1 starts with the preset
    assert sched.step_index == 1 and sched.current_step_dt_s == pytest.approx(0.07)
    sched.set_next_step_dt(None)
    assert sched.next_step_dt_s == pytest.approx(0.045)


def test_set_step_dt_outside_step_start_raises() -> None:
    sched = GaitSchedule()
    sched.set_step_dt(0.05)
    sched.set_step_dt(0.055)  # repeated setting at the start is fine (Algorithm 1 loop)
    sched.advance_to(0.01)
    assert not sched.at_step_start
    with pytest.raises(StepDtLockedError):
        sched.set_step_dt(0.05)
    sched.advance_to(0.01)  # no time elapsed: still locked, no error
    sched.advance_to(0.275 + 1e-4)
    assert sched.at_step_start
    sched.set_step_dt(0.04)
    assert sched.step_end_time_s == pytest.approx(0.275 + 0.2)


def test_invalid_inputs_raise_config_error() -> None:
    sched = GaitSchedule()
    with pytest.raises(ConfigError) as err:
        sched.set_step_dt(0.5)
    assert err.value.field == "dt_s"
    with pytest.raises(ConfigError, match="dt_s"):
        sched.set_next_step_dt(0.0)
    with pytest.raises(ConfigError, match="dt_s"):
        sched.set_step_dt(float("nan"))
    sched.advance_to(0.1)
    with pytest.raises(ConfigError, match="t_s"):
        sched.advance_to(0.05)
    with pytest.raises(ConfigError) as err:
        GaitScheduleConfig(default_dt_s=0.5)
    assert err.value.field == "default_dt_s"
    with pytest.raises(ConfigError, match="dt_bounds_s"):
        GaitScheduleConfig(dt_bounds_s=(0.1, 0.05))
    with pytest.raises(ConfigError, match="first_swing_foot"):
        GaitScheduleConfig(first_swing_foot="middle")
    with pytest.raises(ConfigError, match="stages_per_step"):
        GaitScheduleConfig(stages_per_step=0)
    assert sched.clip_dt(1.0) == pytest.approx(0.2)
    assert sched.clip_dt(0.0) == pytest.approx(0.03)


def test_advance_crossing_several_steps_and_reset() -> None:
    sched = GaitSchedule(start_time_s=1.0)
    assert sched.advance_to(1.0 + 3 * 0.225 + 0.01) == 3
    assert sched.step_index == 3 and sched.at_step_start
    assert sched.step_durations_s == pytest.approx([0.225] * 3)
    sched.reset(0.0)
    assert sched.step_index == 0 and sched.step_durations_s == [] and sched.time_s == 0.0


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.03, 0.2), min_size=1, max_size=6), st.floats(0.0, 1.0))
def test_schedule_invariants(dts: list[float], frac: float) -> None:
    sched = GaitSchedule()
    sched.set_step_dt(dts[0])
    for dt in dts[1:]:
        sched.advance_to(sched.step_end_time_s)
        sched.set_step_dt(dt)
    t = sched.step_start_time_s + frac * sched.current_step_duration_s * 0.999
    sched.advance_to(t)
    assert sched.step_index == len(dts) - 1
    assert sched.step_durations_s == pytest.approx([5 * d for d in dts[:-1]])
    h = sched.horizon()
    assert h.boundaries_s[0] <= h.time_s + 1e-12 < h.boundaries_s[1] + 1e-9
    assert np.allclose(np.diff(h.boundaries_s), h.dts_s)
    assert 0.0 < h.first_stage_remaining_s <= h.dts_s[0] + 1e-9
    assert np.all(h.contact.sum(axis=1) == 1)


# ----------------------------------------------------------------------------------------------
# swing
# ----------------------------------------------------------------------------------------------

P0 = np.array([0.0, -0.06, 0.0])
P1 = np.array([0.30, -0.08, 0.02])


def test_swing_endpoints_and_apex() -> None:
    tr = SwingTrajectory(P0, P1, 0.225, apex_height_m=0.06)
    assert np.allclose(tr.position(0.0), P0)
    assert np.allclose(tr.position(0.225), P1)
    assert np.allclose(tr.velocity(0.0), 0.0, atol=1e-9)
    assert np.allclose(tr.velocity(0.225), 0.0, atol=1e-9)
    assert tr.apex_z_m == pytest.approx(0.02 + 0.06)
    t = np.linspace(0.0, 0.225, 2001)
    pos = tr.position(t)
    assert pos.shape == (2001, 3) and tr.velocity(t).shape == (2001, 3)
    assert pos[:, 2].max() == pytest.approx(0.08, abs=1e-9)
    assert tr.position(0.1125)[2] == pytest.approx(0.08)  # apex at mid-swing
    assert np.all(pos[:, 2] >= -1e-12)
    # clamped outside [0, T]
    assert np.allclose(tr.position(-1.0), P0) and np.allclose(tr.position(9.0), P1)


def test_swing_velocity_is_derivative_of_position() -> None:
    tr = SwingTrajectory(P0, P1, 0.3, obstacles=[(0.1, 0.15, 0.1)], touchdown_speed_mps=0.2)
    t = np.linspace(0.01, 0.29, 57)
    h = 1e-6
    fd = (tr.position(t + h) - tr.position(t - h)) / (2 * h)
    assert np.allclose(fd, tr.velocity(t), atol=1e-5)
    assert tr.velocity(0.3)[2] == pytest.approx(-0.2)
    assert np.allclose(tr.velocity(0.3)[:2], 0.0, atol=1e-9)


def test_swing_sample_is_position_velocity_acceleration() -> None:
    """The 1 kHz single-time path agrees with the batched evaluation, pieces, ends and
    clamping included (a retarget adds pieces)."""
    tr = SwingTrajectory(P0, P1, 0.3, obstacles=[(0.1, 0.15, 0.1)], touchdown_speed_mps=0.2)
    tr.retarget(np.array([0.33, 0.02, 0.01]), 0.12)
    for t in (-0.1, 0.0, 0.05, 0.12, 0.2, 0.3, 0.4):
        p, v, a = tr.sample(t)
        assert np.allclose(p, tr.position(t), rtol=0, atol=1e-12)
        assert np.allclose(v, tr.velocity(t), rtol=0, atol=1e-10)
        assert np.allclose(a, tr.acceleration(t), rtol=0, atol=1e-8)


@pytest.mark.parametrize("x_range", [(0.12, 0.18), (0.05, 0.10), (0.20, 0.24)])
def test_swing_clears_obstacle_with_margin(x_range: tuple[float, float]) -> None:
    top, clearance, half = 0.10, 0.02, 0.04
    obstacles = [(*x_range, top)]
    tr = SwingTrajectory(
        P0, P1, 0.3, obstacles=obstacles, clearance_m=clearance, foot_half_length_m=half
    )
    assert tr.clearance_ok
    assert tr.apex_z_m > 0.02 + 0.06  # raised above the nominal apex
    t = np.linspace(0.0, 0.3, 20001)
    pos = tr.position(t)
    over = (pos[:, 0] + half >= x_range[0]) & (pos[:, 0] - half <= x_range[1])
    assert over.any()
    assert np.all(pos[over, 2] >= top + clearance - 1e-9)
    # C¹ everywhere, also across the lift/land pauses used near the obstacle
    h = 1e-6
    tm = np.linspace(h, 0.3 - h, 997)
    fd = (tr.position(tm + h) - tr.position(tm - h)) / (2 * h)
    assert np.allclose(fd, tr.velocity(tm), atol=1e-5)
    assert np.allclose(tr.velocity([0.0, 0.3]), 0.0, atol=1e-9)
    assert np.allclose(tr.position(0.3), P1)
    # a low obstacle leaves the nominal apex alone
    low = SwingTrajectory(P0, P1, 0.3, obstacles=[(0.12, 0.18, 0.01)])
    assert low.apex_z_m == pytest.approx(0.08)


def test_swing_accepts_terrain_obstacles_and_flags_infeasible() -> None:
    class Ob:
        x_min, x_max, z_top_m = 0.1, 0.2, 0.05

    assert np.allclose(obstacle_array([Ob()]), [[0.1, 0.2, 0.05]])
    # obstacle under the touchdown point: cannot be cleared
    tr = SwingTrajectory(P0, P1, 0.3, obstacles=[(0.28, 0.35, 0.2)])
    assert not tr.clearance_ok
    with pytest.raises(ConfigError, match="obstacles"):
        obstacle_array([(0.3, 0.1, 0.0)])
    with pytest.raises(ConfigError, match="duration_s"):
        SwingTrajectory(P0, P1, 0.0)
    with pytest.raises(ConfigError, match="p1_world_m"):
        SwingTrajectory(P0, [0.0, 1.0], 0.2)
    with pytest.raises(ConfigError, match="apex_height_m"):
        SwingConfig(apex_height_m=-0.1)


@pytest.mark.parametrize("t_now", [0.03, 0.1125, 0.18])
def test_swing_retarget_is_continuous(t_now: float) -> None:
    tr = SwingConfig(apex_height_m=0.06).trajectory(P0, P1, 0.225)
    before = [tr.position(t_now), tr.velocity(t_now), tr.acceleration(t_now)]
    early = tr.position(0.5 * t_now)
    p1_new = np.array([0.34, -0.12, 0.05])
    assert tr.retarget(p1_new, t_now)
    after = [tr.position(t_now), tr.velocity(t_now), tr.acceleration(t_now)]
    for b, a in zip(before, after, strict=True):
        assert np.allclose(a, b, atol=1e-7)
    eps = 1e-7
    assert np.allclose(tr.position(t_now - eps), tr.position(t_now + eps), atol=1e-6)
    assert np.allclose(tr.velocity(t_now - eps), tr.velocity(t_now + eps), atol=1e-4)
    assert np.allclose(tr.position(0.5 * t_now), early)  # the past is unchanged
    assert np.allclose(tr.position(0.225), p1_new)
    assert np.allclose(tr.velocity(0.225), 0.0, atol=1e-8)
    assert np.allclose(tr.p1_world_m, p1_new)
    assert not tr.retarget(P1, 0.2249999)  # too late: no change
    assert np.allclose(tr.position(0.225), p1_new)


def test_swing_retarget_past_apex_over_new_obstacle() -> None:
    tr = SwingTrajectory(P0, P1, 0.3, foot_half_length_m=0.03)
    assert tr.retarget(np.array([0.45, -0.08, 0.0]), 0.2, obstacles=[(0.33, 0.37, 0.06)])
    assert tr.clearance_ok
    t = np.linspace(0.2, 0.3, 5001)
    pos = tr.position(t)
    over = (pos[:, 0] + 0.03 >= 0.33) & (pos[:, 0] - 0.03 <= 0.37)
    assert over.any() and np.all(pos[over, 2] >= 0.06 + 0.02 - 1e-9)


def test_swing_profile_matches_swing_trajectory() -> None:
    """The vectorised closed form is the obstacle-free SwingTrajectory to rounding."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        p0, p1 = rng.uniform(-0.3, 0.3, 3), rng.uniform(-0.3, 0.3, 3)
        duration = rng.uniform(0.1, 0.5)
        t = np.linspace(0.0, duration, 23)
        traj = SwingTrajectory(p0, p1, duration, 0.05)
        got = swing_profile(np.tile(p0, (23, 1)), np.tile(p1, (23, 1)), t / duration, 0.05)
        np.testing.assert_allclose(got, traj.position(t), atol=1e-12)


# ----------------------------------------------------------------------------------------------
# foothold heuristic
# ----------------------------------------------------------------------------------------------


def _foothold(h: RaibertHeuristic, v: float, v_cmd: float, **kw: object) -> np.ndarray:
    args: dict[str, object] = {
        "p_com_world_m": [0.0, 0.0, 0.5],
        "v_com_world_mps": [v, 0.0, 0.0],
        "cmd_vel_mps": [v_cmd, 0.0],
        "stance_duration_s": 0.225,
        "time_to_touchdown_s": 0.1,
        "p_stance_foot_world_m": [0.0, -0.06, 0.0],
    }
    args.update(kw)
    return h.foothold("left", **args)  # type: ignore[arg-type]


def test_foothold_symmetric_about_hip_at_steady_state() -> None:
    h = RaibertHeuristic()
    v, T, t_td = 0.5, 0.225, 0.1
    p = _foothold(h, v, v)
    hip_td = np.array([v * t_td, 0.06])
    assert p[1] == pytest.approx(0.06) and p[2] == pytest.approx(0.0)
    ahead_at_touchdown = p[0] - hip_td[0]
    behind_at_liftoff = (hip_td[0] + v * T) - p[0]
    assert ahead_at_touchdown == pytest.approx(v * T / 2)
    assert ahead_at_touchdown == pytest.approx(behind_at_liftoff)
    # standing still: the foot lands under the hip
    assert np.allclose(_foothold(h, 0.0, 0.0, time_to_touchdown_s=0.0), [0.0, 0.06, 0.0])


def test_foothold_velocity_feedback_and_clipping() -> None:
    h = RaibertHeuristic()
    base = _foothold(h, 0.5, 0.5)
    faster = _foothold(h, 0.7, 0.5)
    k_v = math.sqrt(0.5 / 9.81)
    assert faster[0] - base[0] == pytest.approx(0.2 * (0.225 / 2 + k_v))
    assert _foothold(h, 0.3, 0.5)[0] < base[0]
    # step length clipped relative to the stance foot
    far = _foothold(h, 3.0, 0.5)
    assert far[0] == pytest.approx(0.35)
    # feet do not cross: a right foot pushed left stays right of the left stance foot
    cfg = RaibertConfig(min_lateral_separation_m=0.1)
    right = RaibertHeuristic(cfg).foothold(
        "right",
        p_com_world_m=[0.0, 0.0, 0.5],
        v_com_world_mps=[0.0, 1.0],
        cmd_vel_mps=[0.0, 0.0],
        stance_duration_s=0.225,
        time_to_touchdown_s=0.1,
        p_stance_foot_world_m=[0.0, 0.06, 0.0],
        ground_z_m=0.05,
    )
    assert right[1] == pytest.approx(0.06 - 0.1)
    assert right[2] == pytest.approx(0.05)


def test_foothold_yaw_and_bad_input() -> None:
    h = RaibertHeuristic(RaibertConfig(velocity_gain_s=0.15))
    yaw = math.pi / 2  # heading along +y: the left hip is at -x
    p = h.foothold(
        "left",
        p_com_world_m=[0.0, 0.0, 0.5],
        v_com_world_mps=[0.0, 0.4],
        cmd_vel_mps=[0.4, 0.0],
        stance_duration_s=0.2,
        time_to_touchdown_s=0.0,
        p_stance_foot_world_m=[0.06, 0.0, 0.0],
        yaw_rad=yaw,
    )
    assert np.allclose(p, [-0.06, 0.4 * 0.1, 0.0])
    with pytest.raises(ConfigError, match="foot"):
        _ = h.hip_world_m("middle", [0.0, 0.0, 0.5])
    with pytest.raises(ConfigError, match="cmd_vel_mps"):
        _foothold(h, 0.0, 0.0, cmd_vel_mps=[0.0])
    with pytest.raises(ConfigError, match="max_lateral_separation_m"):
        RaibertConfig(min_lateral_separation_m=0.5, max_lateral_separation_m=0.2)


def test_step_durations_fixed_and_drawn() -> None:
    from gaitnet_mpc.gait.step_durations import StepDurations

    assert StepDurations(dt_s=0.05).dt_of_step(7) == 0.05
    drawn = StepDurations(duration_range_s=(0.15, 0.40), seed=3)
    dts = np.array([drawn.dt_of_step(i) for i in range(400)])
    assert np.all((dts >= 0.03) & (dts <= 0.08))
    assert dts.std() > 0.01  # really drawn: uniform on [0.03, 0.08] has std 0.0144
    assert drawn.dt_of_step(5) == StepDurations(duration_range_s=(0.15, 0.40), seed=3).dt_of_step(5)
    assert drawn.dt_of_step(5) != StepDurations(duration_range_s=(0.15, 0.40), seed=4).dt_of_step(5)
    with pytest.raises(ConfigError, match="duration_range_s"):
        StepDurations(duration_range_s=(0.4, 0.15))
