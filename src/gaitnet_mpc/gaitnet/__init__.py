"""Gait-Net (paper Sec. IV-A): the network that gives each step its MPC dt.

``data`` reads a collected data set, ``features`` selects inputs by PCA (Fig. 4),
``train`` fits an ensemble with PyTorch (optional extra), ``model`` runs it in NumPy from
a plain ``.npz``, ``fit`` and ``table1`` drive training and paper Table I.
"""

from __future__ import annotations

from pathlib import Path

from gaitnet_mpc.gaitnet.model import WEIGHTS_FILE, GaitNet, GaitNetWeights

#: Weights shipped with the package (``NAME.npz``, selectable by NAME).
WEIGHTS_DIR = Path(__file__).parent / "weights"

#: Each robot's default weights. humanoid3d: the ``kd``-taught net retrained with two rounds
#: of rollout-oracle DAgger rows (docs/design/gaitnet_recovery.md); ``humanoid3d-kd`` is
#: that net before them, the default until 2026-12-06.
DEFAULT_WEIGHTS = {"humanoid3d": "humanoid3d-dagger", "biped2d": "biped2d"}


def default_weights_path(robot: str) -> Path:
    """The default shipped weights of ``robot`` (``humanoid3d`` or ``biped2d``)."""
    return WEIGHTS_DIR / f"{DEFAULT_WEIGHTS.get(robot, robot)}.npz"


__all__ = [
    "DEFAULT_WEIGHTS",
    "WEIGHTS_DIR",
    "WEIGHTS_FILE",
    "GaitNet",
    "GaitNetWeights",
    "default_weights_path",
]
