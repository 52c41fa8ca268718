"""Robot registry: name -> :class:`RobotSpec`, and :func:`load_robot`."""

from __future__ import annotations

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import biped2d, humanoid3d
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET, RobotSpec

ROBOTS: dict[str, RobotSpec] = {
    humanoid3d.SPEC.name: humanoid3d.SPEC,
    biped2d.SPEC.name: biped2d.SPEC,
}


def load_robot(name: str) -> RobotModel:
    """Load a registered robot by name (``humanoid3d`` or ``biped2d``)."""
    if name not in ROBOTS:
        raise ConfigError("robot", name, f"one of {sorted(ROBOTS)}")
    return RobotModel(ROBOTS[name])


__all__ = ["FEET", "ROBOTS", "RobotModel", "RobotSpec", "load_robot"]
