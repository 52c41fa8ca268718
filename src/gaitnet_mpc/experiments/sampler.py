"""Turn a walking episode into data-set rows: one per step, finished at the next step start.

A step is seen starting when the controller's list of started steps grows (every walking
controller appends a step's duration when it starts it). Its row is completed at the next
step start, when the swing foot's touchdown is known (where it stands then). A step that
is still open when the robot falls is dropped and counted; one still open when the set's
time runs out is not a sample either (counted apart, as ``incomplete``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gaitnet_mpc.control.base import Controller
from gaitnet_mpc.dataset.schema import COLUMNS, FEATURE_NAMES
from gaitnet_mpc.dataset.step_features import step_features
from gaitnet_mpc.state import RobotState


@dataclass
class _OpenStep:
    state: RobotState
    step_index: int
    dt_s: float
    stance_foot: str
    swing_foot: str
    set_t_s: float
    push_phase: bool
    pushed: bool = False


@dataclass
class StepSampler:
    """Collects the rows of one set, over its episodes (segments).

    Attributes:
        set_id: the set's index.
        vx_cmd_mps: the set's forward command [m/s].
        heading_rad: heading of the feature frame [rad].
        rows: finished rows, column name -> value (:data:`~gaitnet_mpc.dataset.schema.COLUMNS`).
        dropped_fall: steps dropped because the robot fell before they ended.
        incomplete: steps still open when an episode ran out of time.
    """

    set_id: int
    vx_cmd_mps: float
    heading_rad: float = 0.0
    rows: list[dict[str, object]] = field(default_factory=list)
    dropped_fall: int = 0
    incomplete: int = 0
    _open: _OpenStep | None = None
    _steps_seen: int = 0
    _segment: int = 0

    def start_segment(self, segment: int) -> None:
        """A new episode (from standing) begins."""
        self._segment, self._open, self._steps_seen = segment, None, 0

    def observe(
        self,
        state: RobotState,
        controller: Controller,
        set_t_s: float,
        push_phase: bool,
        push_active: bool,
    ) -> None:
        """Call once per control tick, after ``controller.compute(state)``."""
        if self._open is not None and push_active:
            self._open.pushed = True
        n = len(controller.step_durations_s)
        if n <= self._steps_seen:
            return
        self._steps_seen = n
        telemetry = controller.telemetry()
        if telemetry is None:
            return
        if self._open is not None:
            self.rows.append(self._row(self._open, state))
        self._open = _OpenStep(
            state=state,
            step_index=n - 1,
            dt_s=telemetry.step_dt_s,
            stance_foot=telemetry.stance_foot,
            swing_foot=telemetry.swing_foot,
            set_t_s=set_t_s,
            push_phase=push_phase,
            pushed=push_active,
        )

    def end_segment(self, fell: bool) -> None:
        """The episode ended: by a fall (the open step is dropped) or by running out of time."""
        if self._open is not None:
            if fell:
                self.dropped_fall += 1
            else:
                self.incomplete += 1
        self._open = None

    def _row(self, step: _OpenStep, now: RobotState) -> dict[str, object]:
        """The row of ``step``, finished at the next step start ``now``."""
        s = step.state
        com = s.com_world_m
        stance = s.foot_pos_world_m[step.stance_foot]
        liftoff = s.foot_pos_world_m[step.swing_foot]
        touchdown = now.foot_pos_world_m[step.swing_foot]
        features = step_features(s, step.stance_foot, step.swing_foot, touchdown, self.heading_rad)
        row: dict[str, object] = {
            "set_id": self.set_id,
            "segment": self._segment,
            "step_index": step.step_index,
            "t_s": s.t_s,
            "set_t_s": step.set_t_s,
            "vx_cmd_mps": self.vx_cmd_mps,
            "step_duration_s": now.t_s - s.t_s,
            "push_phase": step.push_phase,
            "pushed": step.pushed,
            "stance_foot": step.stance_foot,
            "heading_rad": self.heading_rad,
            "com_world_x_m": com[0],
            "com_world_y_m": com[1],
            "com_world_z_m": com[2],
            "stance_world_x_m": stance[0],
            "stance_world_y_m": stance[1],
            "stance_world_z_m": stance[2],
            "liftoff_world_x_m": liftoff[0],
            "liftoff_world_y_m": liftoff[1],
            "touchdown_world_x_m": touchdown[0],
            "touchdown_world_y_m": touchdown[1],
            "touchdown_world_z_m": touchdown[2],
            **dict(zip(FEATURE_NAMES, features, strict=True)),
            "dt_s": step.dt_s,
        }
        assert set(row) == {c.name for c in COLUMNS}, "row and schema disagree"
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in row.items()}
