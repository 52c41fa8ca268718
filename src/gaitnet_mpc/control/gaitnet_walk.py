"""``gaitnet``: the kino-dynamic MPC with Gait-Net choosing each step's dt (Algorithm 1).

The same walking controller as ``kd`` (settings :class:`KDWalkConfig`, its presets),
with :class:`~gaitnet_mpc.gaitnet.policy.GaitNetDt` in the dt-policy slot instead of a
fixed dt: at every step start, each sequential iteration asks Gait-Net for the dt given
the measured state and the iterate's touchdown (line 8), and the references are re-made
with it (line 9); during the step the dt stays (Remark 4).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.kd_walk import KDWalkController
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig
from gaitnet_mpc.control.terrain_view import TerrainView
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gaitnet import GaitNet, default_weights_path
from gaitnet_mpc.gaitnet.policy import GaitNetDt, GaitNetPolicyConfig
from gaitnet_mpc.robots import RobotModel


def load_gaitnet(robot: RobotModel, weights_path: str | Path | None) -> GaitNet:
    """The network of ``weights_path``, or the weights shipped for ``robot``."""
    path = Path(weights_path) if weights_path is not None else default_weights_path(robot.name)
    if not path.is_file():
        raise ConfigError(
            "--gaitnet-weights", str(path), "a weights file (gaitnet-mpc train --out DIR)"
        )
    net = GaitNet.load(path)
    if net.spec.robot and net.spec.robot != robot.name:
        raise ConfigError("--gaitnet-weights", str(path), f"weights for {robot.name}")
    return net


class GaitNetWalkController(KDWalkController):
    """``kd`` with Gait-Net choosing each step's dt."""

    name = "gaitnet"

    def __init__(
        self,
        robot: RobotModel,
        terrain: TerrainView,
        command: Command,
        net: GaitNet,
        config: KDWalkConfig | None = None,
        policy: GaitNetPolicyConfig | None = None,
    ) -> None:
        self.policy = GaitNetDt(net, robot.spec.planar, policy)
        super().__init__(robot, terrain, command, dt_policy=self.policy, config=config)
        self.weights_info = {
            "teacher": net.spec.teacher,
            "data_manifest_sha256": net.spec.data_manifest_sha256,
            "features": list(net.feature_names),
            "members": net.spec.members,
        }

    def last_dt_decision(self) -> dict[str, Any] | None:
        return self.policy.decisions[-1].to_dict() if self.policy.decisions else None

    def dt_policy_summary(self) -> dict[str, Any] | None:
        return {**self.policy.summary(), "weights": self.weights_info}
