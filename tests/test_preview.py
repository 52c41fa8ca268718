"""Multi-step LIP footstep preview (gait/preview.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.preview import PreviewConfig, plan_preview
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.terrain import Course, Patch, load_course

Z_C_M = 0.555
MARGINS_M = (0.08, 0.03)


def _steady(x0: float, dt: float, v: float = 0.75) -> dict:
    """Arguments of a steady LIP gait at speed v, stance left foot at x0, step start."""
    w = math.sqrt(GRAVITY_MPS2 / Z_C_M)
    T = 5 * dt
    L = v * T
    v0 = w * math.sinh(w * T) * (-L / 2) / (1 - math.cosh(w * T))
    return dict(
        com_m=np.array([x0 - L / 2, 0.0]),
        com_v_mps=np.array([v0, 0.0]),
        com_height_m=Z_C_M,
        stance_foot="left",
        stance_m=np.array([x0, 0.065]),
        liftoff_m=np.array([x0 - L, -0.065]),
        time_left_s=T,
        dt_s=dt,
        v_cmd_mps=v,
        y_path_m=0.0,
        margin_m=MARGINS_M,
    )


@pytest.fixture(scope="module")
def stones_plan():
    course = load_course("stepping-stones")
    plan = plan_preview(course, PreviewConfig(n_steps=8), **_steady(0.75, 0.045))
    assert plan is not None
    return course, plan


def test_plan_puts_every_foot_on_a_stone_it_may_use(stones_plan) -> None:
    course, plan = stones_plan
    assert plan.max_violation_m < 1e-6
    assert plan.foothold_m[-1, 0] > 1.4  # the plan reaches into the one-foot stones
    kinds = set()
    for foot, p, j in zip(plan.feet[1:], plan.foothold_m[1:], plan.patch[1:], strict=True):
        patch = course.patches[j]
        assert patch.allows(foot)
        lo, hi = patch.foothold_box(*MARGINS_M)
        assert np.all(p >= lo[:2] - 1e-6) and np.all(p <= hi[:2] + 1e-6), (foot, p, lo, hi)
        kinds.add(patch.feet)
    assert {"left", "right"} <= kinds


def test_plan_holds_its_step_bounds(stones_plan) -> None:
    _, plan = stones_plan
    cfg = PreviewConfig()
    x = plan.foothold_m[:, 0]
    assert np.all(np.diff(x) >= -cfg.back_m - 1e-9)
    assert np.all(np.diff(x) <= cfg.max_advance_m + 1e-9)
    stride = cfg.max_swing_speed_mps * 5 * 0.045
    assert np.all(x[2:] - x[:-2] <= stride + 1e-9)
    y = plan.foothold_m[:, 1]
    side = np.array([1.0 if f == "left" else -1.0 for f in plan.feet])
    width = side[1:] * (y[1:] - y[:-1])
    assert np.all(width >= cfg.min_width_m - 1e-9)
    assert np.all(np.abs(plan.cop_offset_m) <= cfg.cop_m + 1e-9)


def test_plan_com_path_is_the_lip_of_its_footholds(stones_plan) -> None:
    """Integrating x'' = w^2 (x - cop) numerically through the plan's stages reproduces its
    CoM states, and the CoM stays within reach of each later stance foot."""
    _, plan = stones_plan
    w2 = GRAVITY_MPS2 / Z_C_M
    state = np.array(
        [plan.com_m[0, 0], plan.com_v_mps[0, 0], plan.com_m[0, 1], plan.com_v_mps[0, 1]]
    )
    for k in range(plan.cop_offset_m.size):
        i = _step_of(plan, k)
        cop = np.array([plan.foothold_m[i, 0] + plan.cop_offset_m[k], plan.foothold_m[i, 1]])

        def rhs(_t, s, cop=cop):
            return [s[1], w2 * (s[0] - cop[0]), s[3], w2 * (s[2] - cop[1])]

        t0, t1 = plan.times_s[k], plan.times_s[k + 1]
        state = solve_ivp(rhs, (t0, t1), state, rtol=1e-10, atol=1e-12).y[:, -1]
        np.testing.assert_allclose(state[[0, 2]], plan.com_m[k + 1], atol=1e-6)
        np.testing.assert_allclose(state[[1, 3]], plan.com_v_mps[k + 1], atol=1e-6)
        if i > 0:
            assert (
                abs(plan.com_m[k + 1, 0] - plan.foothold_m[i, 0]) <= PreviewConfig().reach_m + 1e-6
            )


def _step_of(plan, k: int) -> int:
    """Index of the step that stage k belongs to (5 stages per later step)."""
    n0 = plan.cop_offset_m.size - 5 * (len(plan.feet) - 1)
    return 0 if k < n0 else 1 + (k - n0) // 5


def test_flat_ground_plan_is_a_steady_gait() -> None:
    plan = plan_preview(load_course("flat"), PreviewConfig(), **_steady(0.0, 0.055))
    assert plan is not None and plan.max_violation_m < 1e-6
    step = np.diff(plan.foothold_m[:, 0])
    np.testing.assert_allclose(step, 0.75 * 5 * 0.055, atol=0.02)
    pos, vel = plan.com_at(np.array([0.5]))
    assert abs(vel[0, 0] - 0.75) < 0.1 and pos.shape == (1, 2)


def test_first_patch_is_kept() -> None:
    """Two patches in a row: either can be forced for the next touchdown."""
    course = Course("two", (Patch(-1.0, 0.30, -0.5, 0.5, 0.0), Patch(0.30, 5.0, -0.5, 0.5, 0.0)))
    free = plan_preview(course, PreviewConfig(n_steps=4), **_steady(0.1, 0.065))
    assert free is not None
    for j in (0, 1):
        kept = plan_preview(course, PreviewConfig(n_steps=4), **_steady(0.1, 0.065), first_patch=j)
        assert kept is not None and kept.patch[1] == j
        lo, hi = course.patches[j].foothold_box(*MARGINS_M)
        assert lo[0] - 1e-6 <= kept.foothold_m[1, 0] <= hi[0] + 1e-6


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ({"stance_foot": "middle"}, "stance_foot"),
        ({"dt_s": 0.0}, "dt_s"),
        ({"time_left_s": float("nan")}, "time_left_s"),
        ({"com_height_m": -0.5}, "com_height_m"),
    ],
)
def test_bad_arguments_name_the_field(override: dict, field: str) -> None:
    args = {**_steady(0.0, 0.045), **override}
    with pytest.raises(ConfigError, match=field):
        plan_preview(load_course("flat"), PreviewConfig(), **args)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"n_steps": 0}, "n_steps"),
        ({"reach_m": 0.0}, "reach_m"),
        ({"cop_m": -0.01}, "cop_m"),
        ({"v_min_mps": 2.0}, "v_min_mps"),
    ],
)
def test_bad_config_names_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(ConfigError, match=field):
        PreviewConfig(**kwargs)


def test_plan_keeps_footholds_off_an_obstacle_with_the_landing_areas() -> None:
    """On the built-in obstacle course (a box at x 1.45-1.55 m across the walkway) the plan
    made on the landing areas puts no foot centre within the box's footprint widened by
    the clearance and the x margin; on the whole patches the same plan does."""
    course = load_course("obstacle")
    box = course.obstacles[0]
    keep_off = 0.02 + MARGINS_M[0] - 1e-6  # the plan may sit on the widened box's edge

    def over_box(plan) -> bool:
        x = plan.foothold_m[1:, 0]
        return bool(np.any((x > box.x_min - keep_off) & (x < box.x_max + keep_off)))

    args = _steady(1.2, 0.045, v=0.5)
    whole = plan_preview(course, PreviewConfig(n_steps=6), **args)
    cut = plan_preview(course, PreviewConfig(n_steps=6), **args, obstacle_clearance_m=0.02)
    assert whole is not None and cut is not None
    assert over_box(whole)
    assert not over_box(cut)
    assert cut.foothold_m[-1, 0] > box.x_max  # it still walks past the box
