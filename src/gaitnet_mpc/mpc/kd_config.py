"""Parameters of the CMPC sub-problem (paper Tables VIII and X) and its QP backend.

Backend timing (``qp_form="sparse"``, ``qp_backend="piqp"``)
----------------------------------------------------------
Since 2026-12-05 the QP is condensed by default (``qp_form="condensed"``, DAQP on 62-100
variables, ``benchmarks/results/kd_qp_condensed.md``: 0.8 ms per QP against PIQP's 2.0 ms
in one run); since 2026-12-06 compiled kernels build it straight from the iterate, 0.3 ms
per QP (``docs/design/realtime.md``, decision 10). The sparse form's backends, measured
before that:

QP: n = 33 h + 15 = 345 variables, 15 h + 15 = 165 equality rows (nnz 975), 254
inequality rows (20 x 10 line-foot wrench rows + 54 tie rows, nnz 1308; 8 rows per foot
and stage for point feet), a box on all 345 variables, diagonal P (333 nonzeros).
Solve time of ``QPWorkspace.solve`` (setup/update + solve + conversions) over the 6 QPs of
a sequential solve of a walking problem (h = 10, dt 0.05/0.06 s, single support, converged
to Table X tolerances after 5 iterations), best of 40 repetitions per QP, three runs on a
shared 2-core development VM (load 2-4, so medians are 1.5-3x higher):

* PIQP: 2.5-4.9 ms per QP, 16-25 ms for all 6 (11-13 interior-point iterations each,
  steps reach ~1e-12, so the Table X tolerances are never limited by the solver);
* OSQP: 2.2-2.4 ms per QP once its own warm start is close, 5-16 ms for the first three,
  25-52 ms for all 6 (stalls at ~1e-7 step accuracy);
* Clarabel: 7.3-13 ms per QP, 44-73 ms (fresh setup every solve);
* DAQP (dense active set): 15-21 ms per QP, 91-119 ms.

Best of the three runs, all 6 QPs: PIQP 16.1 ms, OSQP 25.5 ms, Clarabel 44.2 ms, DAQP
90.7 ms. PIQP is the default.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from gaitnet_mpc.config import bounded, check_ranges, weight
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.mpc.contact import ContactParams
from gaitnet_mpc.mpc.qp.registry import BACKENDS

#: Backend settings applied under ``KDConfig.qp_options``. PIQP's relative duality-gap test
#: is measured against the large state-tracking terms of eq. 18 (objective ~1e5), which
#: lets weakly active foothold bounds (gradient ~0.05) end 1e-5 m inside; one more
#: interior-point iteration with these settings reaches the bound to ~1e-9 m.
BACKEND_OPTIONS: Mapping[str, Mapping[str, Any]] = MappingProxyType(
    {"piqp": MappingProxyType({"eps_duality_gap_rel": 1e-12, "eps_duality_gap_abs": 1e-10})}
)

QP_FORMS = ("sparse", "condensed")  # KDConfig.qp_form
WEIGHT_UNITS = ("quantity", "motion")  # KDConfig.weight_units

_FOOT = "the CoP's reach from the foot centre; 0: a point foot; humanoid3d 0.075 m"
_TRUST = "per axis about the iterate; None: off; 1 m is past any step"


def _size(name: str, value: tuple[float, ...], size: int) -> None:
    if np.shape(value) != (size,):
        raise ConfigError(name, value, f"{size} weights, one per axis")


@dataclass(frozen=True)
class KDConfig:
    """Parameters of the CMPC sub-problem (paper Tables VIII and X; units in names).

    Weights are the diagonals of eq. 18's ``L`` matrices (``w_momentum`` is ``L^h`` over
    ``[l_G; k_G]``, ``w_pose`` is ``L^H``). ``reg_*`` weight the proximal term on the
    search directions (:mod:`~gaitnet_mpc.mpc.implicit_kd`). ``trust_region_m`` bounds each
    foot-position tie group per axis around its iterate (``None``: off);
    ``trust_region_com_m`` the same for ``delta p_c`` (off by default, see
    :mod:`~gaitnet_mpc.mpc.implicit_kd`). ``foot_height_from_reference`` fixes the height of
    every free foot-position group to its reference (mean over the group's stance stages)
    unless foothold bounds give it a finite height range. ``qp_options`` are passed to
    :func:`~gaitnet_mpc.mpc.qp.make_workspace` (over :data:`BACKEND_OPTIONS`).

    ``weight_units`` says what ``w_pose`` and ``w_momentum`` weigh
    (``docs/design/paper_weights.md``): ``"quantity"``, ``H = [m p_c; angular pose]`` and
    ``h = [l_G; k_G]`` as they are (kg m, kg m^2, kg m/s, kg m^2/s); ``"motion"``, the same
    quantities per unit of mass on the linear rows and of ``inertia_kgm2`` on the angular
    ones, i.e. CoM position and velocity, attitude and angular velocity (m, rad, m/s,
    rad/s). :attr:`pose_weights` and :attr:`momentum_weights` are the diagonals the QP uses.

    ``mass_kg``: pass ``RobotModel.total_mass_kg``; the walking controller
    (``KDWalkController``) sets it, ``inertia_kgm2``, ``toe_m``, ``heel_m`` and
    ``min_foot_separation_m`` from the robot, and its configuration refuses them changed
    (``KDWalkConfig``, ``ROBOT_FIELDS``).
    """

    horizon: int = bounded(10, "[1, 100]", "an integer", "stages; h = 10 in the paper")
    mass_kg: float = bounded(16.0, "(0, 1000] kg", "a mass", "humanoid3d 16 kg, biped2d 10 kg")
    gravity_mps2: float = bounded(
        GRAVITY_MPS2, "[0, 30] m/s^2", "an acceleration", "0: none; 30 is past Jupiter's 25"
    )
    #: Diagonal of the centroidal inertia at the standing pose [kg m^2] (humanoid3d;
    #: ``RobotModel.standing_inertia_kgm2``); only ``weight_units = "motion"`` reads it.
    inertia_kgm2: tuple[float, float, float] = bounded(
        (0.6419, 0.5757, 0.09415), "(0, 1000] kg m^2", "an inertia", "humanoid3d ~0.6 kg m^2"
    )
    weight_units: str = "quantity"
    w_momentum: tuple[float, ...] = weight((10.0,) * 6)  # L^h
    w_pose: tuple[float, ...] = weight((200.0,) * 6)  # L^H
    w_p_foot: tuple[float, float, float] = weight((0.1, 0.1, 0.1))  # L^{p_f}
    w_p_com: tuple[float, float, float] = weight((100.0, 100.0, 250.0))  # L^{p_c}
    w_force: float = weight(1e-4)  # L^f
    w_moment: float = weight(1e-3)  # L^tau
    reg_force: float = weight(1e-6)
    reg_moment: float = weight(1e-5)
    reg_position: float = weight(1e-2)
    contact: ContactParams = field(default_factory=ContactParams)
    toe_m: float = bounded(0.075, "[0, 0.3] m", "a length", _FOOT)
    heel_m: float = bounded(0.075, "[0, 0.3] m", "a length", _FOOT)
    #: Half length [m] of the segment whose wrench cone bounds the yaw moment with
    #: ``contact.yaw_moment = "cwc"`` (the whole foot; ``toe_m``, ``heel_m`` may be the
    #: centre-of-pressure margin's); None: ``(toe_m + heel_m) / 2``.
    yaw_cone_half_m: float | None = bounded(None, "[0, 0.3] m", "a length", _FOOT)
    foot_height_from_reference: bool = True
    #: Smallest lateral distance [m] between the feet in the stance foot's heading frame
    #: (:mod:`~gaitnet_mpc.mpc.implicit_kd`); None: no such row (the paper has none).
    min_foot_separation_m: float | None = bounded(
        None, "(0, 0.5] m", "a distance", "humanoid3d 0.06 m; 0.5 m is past the legs' reach"
    )
    #: Leg length [m] from the hip pitch joint to the ankle for the reach rows of
    #: :mod:`~gaitnet_mpc.mpc.kinematic_rows` (humanoid3d 0.44 m); None: no such rows (the
    #: paper has none). ``hip_offset_m``: the hips' offsets ``o_i`` there, left then right;
    #: ``reach_tilt_rad``: the tilt ``alpha`` of the rows' faces.
    leg_reach_m: float | None = bounded(None, "(0, 2] m", "a length", "humanoid3d 0.44 m")
    reach_tilt_rad: float = bounded(0.35, "(0, 1.5] rad", "an angle", "humanoid3d 0.35 rad")
    hip_offset_m: tuple[float, ...] = bounded(
        (0.0088, 0.065, -0.1316, 0.0088, -0.065, -0.1316),
        "[-2, 2] m",
        "an offset",
        "humanoid3d's hips sit 0.13 m below the CoM",
    )
    trust_region_m: float | None = bounded(0.1, "(0, 1] m", "a distance", _TRUST)
    trust_region_com_m: float | None = bounded(None, "(0, 1] m", "a distance", _TRUST)
    qp_backend: str = "piqp"  # fastest here, see the module docstring
    qp_options: tuple[tuple[str, Any], ...] = ()
    #: ``"condensed"``: reduced to its free variables and solved by DAQP
    #: (:mod:`~gaitnet_mpc.mpc.kd_condensed`; 2.5x faster than the sparse QP with PIQP,
    #: the same minimiser), with ``qp_backend`` on the sparse QP where DAQP fails;
    #: ``"sparse"``: the QP as built, solved by ``qp_backend``.
    qp_form: str = "condensed"

    def __post_init__(self) -> None:
        if not isinstance(self.horizon, int | np.integer):
            raise ConfigError("horizon", self.horizon, "an integer")
        check_ranges(self)
        _size("w_momentum", self.w_momentum, 6)
        _size("w_pose", self.w_pose, 6)
        _size("w_p_foot", self.w_p_foot, 3)
        _size("w_p_com", self.w_p_com, 3)
        if np.shape(self.hip_offset_m) != (6,):
            raise ConfigError("hip_offset_m", self.hip_offset_m, "6 offsets [m], left then right")
        if self.weight_units not in WEIGHT_UNITS:
            raise ConfigError("weight_units", self.weight_units, f"one of {list(WEIGHT_UNITS)}")
        if np.shape(self.inertia_kgm2) != (3,):
            raise ConfigError("inertia_kgm2", self.inertia_kgm2, "3 inertias [kg m^2]")
        if self.qp_form not in QP_FORMS:
            raise ConfigError("qp_form", self.qp_form, f"one of {list(QP_FORMS)}")
        if self.qp_backend not in BACKENDS:
            raise ConfigError("qp_backend", self.qp_backend, f"one of {sorted(BACKENDS)}")

    def qp_workspace_options(self) -> dict[str, Any]:
        """Options of :func:`~gaitnet_mpc.mpc.qp.make_workspace`: :data:`BACKEND_OPTIONS`
        of ``qp_backend``, overridden by ``qp_options``."""
        return {**BACKEND_OPTIONS.get(self.qp_backend, {}), **dict(self.qp_options)}

    def _unit_scale(self) -> np.ndarray:
        """(6,) what one unit of ``[H; h]``'s rows weighs under ``weight_units``."""
        if self.weight_units == "quantity":
            return np.ones(6)
        return 1.0 / np.concatenate([[self.mass_kg] * 3, self.inertia_kgm2]) ** 2

    @property
    def pose_weights(self) -> np.ndarray:
        """(6,) ``L^H`` on ``H = [m p_c; angular pose]`` as the QP weighs it."""
        return np.asarray(self.w_pose, dtype=float) * self._unit_scale()

    @property
    def momentum_weights(self) -> np.ndarray:
        """(6,) ``L^h`` on ``h = [l_G; k_G]`` as the QP weighs it."""
        return np.asarray(self.w_momentum, dtype=float) * self._unit_scale()

    def stage_weights(self) -> tuple[np.ndarray, np.ndarray]:
        """Eq. 18's diagonal weights ``W`` with the proximal term (the QP's ``P = 2 W``):
        (15,) on a stage's ``x_k = [H; l_G; k_G]`` and ``delta p_c,k`` (``k >= 1``), and
        (3, 3) per axis on ``delta f``, ``delta tau``, ``delta p_f``."""
        w_state = np.concatenate(
            [self.pose_weights, self.momentum_weights, np.asarray(self.w_p_com) + self.reg_position]
        ).astype(float)
        w_input = np.array(
            [[self.w_force + self.reg_force] * 3, [self.w_moment + self.reg_moment] * 3,
             np.asarray(self.w_p_foot) + self.reg_position],
        )  # fmt: skip
        return w_state, w_input


__all__ = ["BACKEND_OPTIONS", "QP_FORMS", "WEIGHT_UNITS", "KDConfig"]
