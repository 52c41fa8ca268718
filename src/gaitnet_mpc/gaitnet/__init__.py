"""Gait-Net (paper Sec. IV-A): the network that gives each step its MPC dt.

``data`` reads a collected data set, ``features`` selects inputs by PCA (Fig. 4),
``train`` fits an ensemble with PyTorch (optional extra), ``model`` runs it in NumPy from
a plain ``.npz``, ``fit`` and ``table1`` drive training and paper Table I.
"""

from __future__ import annotations

from pathlib import Path

from gaitnet_mpc.gaitnet.model import WEIGHTS_FILE, GaitNet, GaitNetWeights

#: Weights shipped with the package, one file per robot.
WEIGHTS_DIR = Path(__file__).parent / "weights"


def default_weights_path(robot: str) -> Path:
    """The shipped weights of ``robot`` (``humanoid3d`` or ``biped2d``)."""
    return WEIGHTS_DIR / f"{robot}.npz"


__all__ = ["WEIGHTS_DIR", "WEIGHTS_FILE", "GaitNet", "GaitNetWeights", "default_weights_path"]
