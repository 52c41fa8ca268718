"""The compiled CoM and centroidal momentum (kinematics/rigid_body_kernel.py) against
Pinocchio's, at random configurations and velocities of the humanoid."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from gaitnet_mpc.kinematics.rigid_body_kernel import tree_of
from gaitnet_mpc.robots import load_robot


def test_com_and_momentum_match_pinocchio() -> None:
    model = load_robot("humanoid3d").pin_model
    data = model.createData()
    tree = tree_of(model)
    assert tree is not None
    rng = np.random.default_rng(0)
    q = np.array(
        [
            pin.randomConfiguration(model, -2 * np.ones(model.nq), 2 * np.ones(model.nq))
            for _ in range(20)
        ]
    )
    v = rng.normal(scale=2.0, size=(20, model.nv))
    h, com = tree.momentum(q, v)
    com_only = tree.com(q)
    for k in range(q.shape[0]):
        expected = pin.computeCentroidalMomentum(model, data, q[k], v[k]).vector
        np.testing.assert_allclose(h[k], expected, atol=1e-11)
        np.testing.assert_allclose(com[k], data.com[0], atol=1e-13)
        np.testing.assert_allclose(com_only[k], data.com[0], atol=1e-13)


def test_planar_root_keeps_pinocchio() -> None:
    """The biped's composite planar root is not a kernel joint: no tree, Pinocchio."""
    assert tree_of(load_robot("biped2d").pin_model) is None
