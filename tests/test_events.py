"""Foot events (``events.csv``): touchdowns, lift-offs, slips, pivots and scuffs."""

from __future__ import annotations

import csv
import io
import itertools
import math

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.events import COLUMNS, EventConfig, EventRecorder
from gaitnet_mpc.state import RobotState

TICK_S = 0.001


def _state(
    t_s: float,
    contact: dict[str, bool],
    pos: dict[str, tuple[float, float, float]] | None = None,
    yaw: dict[str, float] | None = None,
) -> RobotState:
    """A state with only the foot fields meaningful."""
    pos = pos or {"left": (0.0, 0.1, 0.0), "right": (0.0, -0.1, 0.0)}
    yaw = yaw or {"left": 0.0, "right": 0.0}
    z3 = np.zeros(3)
    return RobotState(
        t_s=t_s,
        qpos=np.zeros(7),
        qvel=np.zeros(6),
        base_pos_world_m=z3,
        base_rot_world=np.eye(3),
        base_lin_vel_world_mps=z3,
        base_ang_vel_world_radps=z3,
        joint_pos_rad=np.zeros(0),
        joint_vel_radps=np.zeros(0),
        com_world_m=z3,
        com_vel_world_mps=z3,
        h_measured=np.zeros(6),
        foot_pos_world_m={f: np.array(p, dtype=float) for f, p in pos.items()},
        foot_yaw_rad=dict(yaw),
        foot_contact=dict(contact),
        foot_wrench_world={f: np.zeros(6) for f in pos},
    )


def _rows(rec: EventRecorder) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(rec.to_csv())))


def _walk_left(rec: EventRecorder, t0_s: float, t1_s: float, contact, x_of_t, yaw_of_t=None):
    """Ticks from t0 to t1 (excluded): the left foot's contact and x follow the callables,
    the right foot stands still."""
    for k in range(round((t1_s - t0_s) / TICK_S)):
        t = t0_s + k * TICK_S
        rec.update(
            _state(
                t,
                {"left": contact(t), "right": True},
                {"left": (x_of_t(t), 0.1, 0.0), "right": (0.0, -0.1, 0.0)},
                {"left": 0.0 if yaw_of_t is None else yaw_of_t(t), "right": 0.0},
            )
        )


def test_feet_standing_at_the_start_give_no_event() -> None:
    rec = EventRecorder()
    _walk_left(rec, 0.0, 0.5, lambda t: True, lambda t: 0.0)
    assert rec.events == []
    assert rec.to_csv() == ",".join(COLUMNS) + "\n"


def test_a_swing_gives_one_liftoff_and_one_touchdown_with_the_impact_speed() -> None:
    """Left foot: stands to 0.2 s, swings at 1 m/s to 0.5 s, stands again to 1 s."""
    rec = EventRecorder()
    x = lambda t: float(np.clip(t - 0.2, 0.0, 0.3))  # noqa: E731
    _walk_left(rec, 0.0, 1.0, lambda t: not 0.2 <= t < 0.5, x)
    ev = rec.events
    assert [e.event for e in ev] == ["liftoff", "touchdown"]
    lift, down = ev
    assert lift.foot == down.foot == "left"
    assert lift.t_s == pytest.approx(0.199)  # the last tick in contact
    assert lift.quantity == "stance_s" and lift.value == pytest.approx(0.199)
    assert down.t_s == pytest.approx(0.5)
    assert down.pos_world_m == pytest.approx((0.3, 0.1, 0.0))
    assert down.quantity == "impact_speed_mps" and down.value == pytest.approx(1.0, rel=1e-6)
    rows = _rows(rec)
    assert list(rows[0]) == list(COLUMNS)
    assert rows[1]["event"] == "touchdown" and float(rows[1]["x_m"]) == pytest.approx(0.3)


def test_contact_chatter_shorter_than_min_air_does_not_split_a_stance() -> None:
    rec = EventRecorder(EventConfig(min_air_s=0.03))
    gaps = [(0.3, 0.31), (0.5, 0.52)]  # 10 and 20 ms off the terrain
    _walk_left(rec, 0.0, 1.0, lambda t: not any(a <= t < b for a, b in gaps), lambda t: 0.0)
    assert rec.events == []


def test_a_short_contact_in_the_air_is_a_scuff_not_a_touchdown() -> None:
    """The left foot swings from 0.1 s to 0.6 s and brushes the terrain for 20 ms."""
    rec = EventRecorder()
    brush = (0.3, 0.32)
    _walk_left(
        rec,
        0.0,
        0.8,
        lambda t: t < 0.1 or brush[0] <= t < brush[1] or t >= 0.6,
        lambda t: float(np.clip(t - 0.1, 0.0, 0.5)),
    )
    assert [e.event for e in rec.events] == ["liftoff", "scuff", "touchdown"]
    scuff = rec.events[1]
    assert scuff.t_s == pytest.approx(0.3)
    assert scuff.quantity == "contact_s" and scuff.value == pytest.approx(0.019)
    assert scuff.pos_world_m[0] == pytest.approx(0.2)


def test_a_contact_before_the_planned_touchdown_is_an_early_scuff() -> None:
    """With the plan given, a swing foot that lands 0.1 s early is reported as a scuff
    (early_s) and, as it stays down, as a touchdown too."""
    rec = EventRecorder()
    for k in range(600):
        t = k * TICK_S
        touching = t < 0.1 or t >= 0.3
        rec.update(
            _state(t, {"left": touching, "right": True}),
            swing_until_s={"left": 0.4} if 0.1 <= t < 0.4 else {},
        )
    assert [e.event for e in rec.events] == ["liftoff", "scuff", "touchdown"]
    scuff = rec.events[1]
    assert scuff.quantity == "early_s" and scuff.value == pytest.approx(0.1)
    assert rec.events[2].t_s == pytest.approx(0.3)


def test_a_contact_at_the_planned_touchdown_is_no_scuff() -> None:
    rec = EventRecorder(EventConfig(scuff_lead_s=0.05))
    for k in range(600):
        t = k * TICK_S
        touching = t < 0.1 or t >= 0.37  # 30 ms before the plan
        rec.update(_state(t, {"left": touching, "right": True}), {"left": 0.4})
    assert [e.event for e in rec.events] == ["liftoff", "touchdown"]


def test_a_sliding_and_turning_stance_foot_gives_one_slip_and_one_pivot_row() -> None:
    """After touchdown at 0.3 s the left foot slides 3 cm and turns 0.2 rad, then lifts off;
    slip and pivot count from where it stood 0.05 s after touchdown."""
    rec = EventRecorder(EventConfig(slip_m=0.01, pivot_rad=0.1))

    def x(t: float) -> float:
        return 0.0 if t < 0.3 else 0.1 * min(t - 0.3, 0.3)  # 0.1 m/s for 0.3 s

    def yaw(t: float) -> float:
        return 0.0 if t < 0.3 else float(np.clip(2.0 * (t - 0.5), 0.0, 0.2))

    _walk_left(rec, 0.0, 0.9, lambda t: not 0.1 <= t < 0.3 and t < 0.8, x, yaw)
    kinds = [e.event for e in rec.events]
    assert kinds == ["liftoff", "touchdown", "slip", "pivot", "liftoff"]
    slip, pivot = rec.events[2], rec.events[3]
    assert slip.t_s == pytest.approx(0.451, abs=2e-3)  # 1 cm beyond x(0.35 s) = 0.005 m
    assert slip.value == pytest.approx(0.025, abs=1e-4)  # the largest travel
    assert slip.pos_world_m[0] == pytest.approx(0.03, abs=1e-4)  # where the stance ended
    assert pivot.t_s == pytest.approx(0.551, abs=2e-3)
    assert pivot.value == pytest.approx(0.2)


def test_a_stance_open_at_the_end_keeps_its_touchdown_without_a_liftoff() -> None:
    rec = EventRecorder()
    _walk_left(rec, 0.0, 0.4, lambda t: not 0.1 <= t < 0.3, lambda t: 0.0)
    assert [e.event for e in rec.events] == ["liftoff", "touchdown"]
    # a contact shorter than min_stance_s at the end is not reported yet
    rec2 = EventRecorder()
    _walk_left(rec2, 0.0, 0.32, lambda t: not 0.1 <= t < 0.3, lambda t: 0.0)
    assert [e.event for e in rec2.events] == ["liftoff"]


@pytest.mark.parametrize("name", ["min_air_s", "min_stance_s", "slip_m", "pivot_rad"])
def test_thresholds_must_be_positive(name: str) -> None:
    with pytest.raises(ConfigError):
        EventConfig(**{name: 0.0})
    with pytest.raises(ConfigError):
        EventConfig(**{name: math.nan})


def test_walking_episode_touchdowns_match_the_simulators_footholds() -> None:
    """1.2 s of srbm walking on flat ground: each touchdown row is one of the simulator's
    footholds, feet alternate, and nothing scuffs or slips."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.srbm_walk import SRBMWalkController
    from gaitnet_mpc.control.terrain_view import TerrainView
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    robot, course, command = load_robot("humanoid3d"), load_course("flat"), Command(0.5)
    sim = Simulator(robot, course)
    ctrl = SRBMWalkController(robot, TerrainView(course), command)
    state = sim.state()
    ctrl.reset(state)
    rec = EventRecorder()
    while state.t_s < 1.2:
        tau = ctrl.compute(state)
        s = ctrl.schedule
        rec.update(state, {s.swing_foot: s.step_start_time_s + s.current_step_duration_s})
        sim.step(tau)
        state = sim.state()
    assert not sim.fall.fell
    ev = rec.events
    downs = [e for e in ev if e.event == "touchdown"]
    assert len(downs) >= 3
    assert all(a.foot != b.foot for a, b in itertools.pairwise(downs))
    assert not [e for e in ev if e.event in ("scuff", "slip")]
    footholds = {(f.foot, round(f.t_s, 3)) for f in sim.footholds}
    assert {(e.foot, round(e.t_s, 3)) for e in downs} <= footholds
    lifts = [e for e in ev if e.event == "liftoff"]
    assert lifts and all(e.quantity == "stance_s" and e.value > 0.1 for e in lifts[1:])
