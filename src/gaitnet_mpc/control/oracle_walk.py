"""``oracle``: the kino-dynamic MPC with a grid search choosing each step's dt.

The same walking controller as ``kd`` and ``gaitnet`` (settings :class:`KDWalkConfig`,
its presets), with :class:`~gaitnet_mpc.mpc.dt_oracle.OracleDt` in the dt-policy slot: at
every step start it solves the step once per dt of a grid over the paper's bounds
([0.045, 0.07] s in 3-D, [0.03, 0.06] s in 2-D, in 5 ms steps) and keeps the converged
plan of lowest eq. 18 cost. Slow (one full solve per grid point per step); it is the
reference Gait-Net's choices are measured against.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.gaitnet.policy import PAPER_DT_BOUNDS_S
from gaitnet_mpc.mpc.dt_oracle import OracleConfig, OracleDt
from gaitnet_mpc.robots import RobotModel

GRID_STEP_S = 0.005


def paper_grid_s(planar: bool) -> tuple[float, ...]:
    """The paper's dt bounds of the robot in steps of :data:`GRID_STEP_S` [s]."""
    lo, hi = PAPER_DT_BOUNDS_S[planar]
    n = round((hi - lo) / GRID_STEP_S) + 1
    return tuple(float(round(d, 6)) for d in np.linspace(lo, hi, n))


class OracleWalkController(KDWalkController):
    """``kd`` with the grid-search oracle choosing each step's dt."""

    name = "oracle"

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        config: KDWalkConfig | None = None,
        oracle: OracleConfig | None = None,
    ) -> None:
        grid = paper_grid_s(robot.spec.planar)
        self.policy = OracleDt(oracle or OracleConfig(dts_s=grid, nominal_dt_s=grid[0]))
        super().__init__(robot, terrain, command, dt_policy=self.policy, config=config)
        self.policy.attach(self.mpc)

    def last_dt_decision(self) -> dict[str, Any] | None:
        return self.policy.decisions[-1].to_dict() if self.policy.decisions else None

    def dt_policy_summary(self) -> dict[str, Any] | None:
        return self.policy.summary()
