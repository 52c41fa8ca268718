"""A centroidal-momentum disturbance observer: the external wrench no model accounts for.

The centroidal dynamics (eq. 10, the MPC's eqs. 14-15) say what the measured feet do to the
momentum ``h = [l_G; k_G]`` about the CoM::

    d l_G / dt = m g + sum_i f_i                         + f_ext
    d k_G / dt = sum_i (p_i - c) x f_i + tau_i           + tau_ext

with ``[f_i; tau_i]`` the ground wrench on foot ``i`` about its centre ``p_i`` (a robot's
ankle force/torque sensor; :attr:`RobotState.foot_wrench_world`), ``c`` the CoM and ``m``
the robot's *modelled* mass. Whatever else acts, an unknown payload on the trunk (its weight
and inertia), a push, a modelling error, appears as ``w_ext = [f_ext; tau_ext]``. The
generalised-momentum observer (De Luca et al., 2003, applied to the centroidal momentum)
estimates it as a first-order low pass of that residual, without differentiating ``h``::

    r(t) = K [ h(t) - h(0) - int_0^t (m g + sum_i w_i + r) ds ]     =>   dr/dt = K (w_ext - r)

``K`` = ``bandwidth_radps``: a step of ``w_ext`` is followed with the time constant ``1/K``.
Everything it reads is what a robot measures: joint positions and velocities, the trunk's
pose and twist, and the feet's wrenches; ``h`` and ``c`` come from the robot's model
(Pinocchio), which knows nothing of the payload.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.state import RobotState


@dataclass(frozen=True)
class DisturbanceObserverConfig:
    """Settings of :class:`MomentumObserver` (``KDWalkConfig.disturbance_observer``)."""

    # 1/K = 0.2 s: a payload's weight is taken up within a step or two, while a 0.2 s push
    # reaches only 1 - e^-1 = 63 % of its force before it ends.
    bandwidth_radps: float = bounded(
        5.0, "(0, 100] rad/s", "a bandwidth", "100 rad/s follows 1 kHz tick noise"
    )
    # The estimate is clipped to these magnitudes (each of f_ext and tau_ext).
    max_force_n: float = bounded(
        80.0, "[0, 500] N", "a force", "80 N: half the humanoid's weight, 8 kg of payload"
    )
    max_torque_nm: float = bounded(20.0, "[0, 200] N m", "a torque", "80 N at 0.25 m")
    # Whether tau_ext enters the MPC (it is estimated and logged either way). Off: in
    # undisturbed walking the torque channel reads a steady -0.1 N m about y, a model
    # error (0.6 mm of CoM offset under the robot's weight), not a disturbance
    # (docs/design/disturbance_observer.md).
    torque_to_mpc: bool = False
    # The MPC plans with f_ext only once its magnitude exceeds this (below: zero). In
    # undisturbed walking the estimate stays under 1.1 N (flat, seeded stones), and
    # planning with that noise changed which stone layouts were crossed; with the dead
    # band an undisturbed run is bitwise the run without the observer.
    dead_band_n: float = bounded(
        3.0, "[0, 50] N", "a force", "3 N: 2 % of the humanoid's weight, 0.3 kg"
    )

    def __post_init__(self) -> None:
        check_ranges(self)


class MomentumObserver:
    """The estimate of the external wrench ``[f_ext (N); tau_ext about the CoM (N m)]``.

    Made with the first state (a zero estimate), then :meth:`update` with each later one;
    the estimate :attr:`wrench` is world-aligned, and the MPC holds it over its horizon (an
    affine term of eqs. 14-15, :meth:`mpc_wrench`).
    """

    def __init__(
        self, robot: RobotModel, config: DisturbanceObserverConfig, state: RobotState
    ) -> None:
        self.robot = robot
        self.config = config
        self._data = robot.pin_model.createData()
        self._weight = np.array([0.0, 0.0, -robot.total_mass_kg * GRAVITY_MPS2])
        self._limit = np.array([config.max_force_n] * 3 + [config.max_torque_nm] * 3)
        self.wrench = np.zeros(6)
        self._h0 = self._momentum(state)[0]
        self._integral = np.zeros(6)
        self._t_s = state.t_s

    def _momentum(self, state: RobotState) -> tuple[np.ndarray, np.ndarray]:
        """The modelled centroidal momentum ``[l_G; k_G]`` (6,) and CoM (3,) of ``state``."""
        q, v = self.robot.mj_to_pin(state.qpos, state.qvel)
        hg = pin.computeCentroidalMomentum(self.robot.pin_model, self._data, q, v)
        return np.concatenate([hg.linear, hg.angular]), self._data.com[0]

    def update(self, state: RobotState) -> np.ndarray:
        """Take in ``state`` (its feet's wrenches act over the interval since the last one)
        and return the new estimate (6,)."""
        dt = state.t_s - self._t_s
        self._t_s = state.t_s
        h, com = self._momentum(state)
        modelled = np.zeros(6)
        modelled[:3] = self._weight
        for foot in FEET:
            w = state.foot_wrench_world[foot]
            arm = state.foot_pos_world_m[foot] - com
            modelled[:3] += w[:3]
            # (p_i - c) x f_i + tau_i, written out: np.cross costs 14 us a call, this 2
            modelled[3] += (arm[1] * w[2] - arm[2] * w[1]) + w[3]
            modelled[4] += (arm[2] * w[0] - arm[0] * w[2]) + w[4]
            modelled[5] += (arm[0] * w[1] - arm[1] * w[0]) + w[5]
        self._integral += dt * (modelled + self.wrench)
        r = self.config.bandwidth_radps * (h - self._h0 - self._integral)
        self.wrench = np.minimum(np.maximum(r, -self._limit), self._limit)  # a new array
        return self.wrench

    def mpc_wrench(self) -> np.ndarray:
        """The estimate the MPC plans with (6,): :attr:`wrench`, zero while its force is
        within ``config.dead_band_n``; its torque zeroed unless ``config.torque_to_mpc``."""
        c = self.config
        if np.linalg.norm(self.wrench[:3]) <= c.dead_band_n:
            return np.zeros(6)
        out = self.wrench.copy()
        if not c.torque_to_mpc:
            out[3:] = 0.0
        return out


__all__ = ["DisturbanceObserverConfig", "MomentumObserver"]
