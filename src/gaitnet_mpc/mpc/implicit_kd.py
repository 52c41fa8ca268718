"""Convex MPC sub-problem (CMPC) of the implicit kino-dynamic MPC (paper Sec. IV-B).

One sequential iteration ``j -> j + 1`` of Algorithm 1: given the previous total solution
(the *iterate* ``j``: contact forces ``f``, contact moments ``tau``, foot positions ``p_f``
per foot and stage, CoM positions ``p_c``), solve a QP for the search directions
``delta f, delta tau, delta p_f, delta p_c`` (eq. 17) and the centroidal states
``x_k = [H_k (6); h_k (6)]`` (eq. 16), ``h = [l_G (3); k_G (3)]``.

Sparse formulation
------------------
States are decision variables (no condensing), so every stage has its own sampling time
``dt_k`` for free. Variable layout (``n = 33 h + 15``)::

    z = [x_0, dpc_0, df_0 (2x3), dtau_0 (2x3), dpf_0 (2x3),  ...,  x_h, dpc_h]
         12    3      6           6             6

Dynamics, equality rows, ``k = 0 .. h-1`` (``r_i = p_f,i^j - p_c,k^j``, ``g = (0, 0, -g)``)::

    H_{k+1} = H_k + h_k dt_k                                         (centroidal pose)
    l_{k+1} = l_k + (sum_i (f_i^j + df_i) + m g) dt_k                (eqs. 14, 19)
    k_{k+1} = k_k + sum_i [dtau_i - f_i^j x (dpf_i - dpc_k) + r_i x df_i
                           + r_i x f_i^j + tau_i^j] dt_k             (eqs. 15, 19)
    p_c,k+1^j + dpc_{k+1} = p_c,k^j + dpc_k + l_k / m dt_k          (eq. 20)

with ``x_0`` fixed to the measurement and ``dpc_0 = 0`` (the iterate's ``p_c[0]`` is the
measured CoM). The product of two search directions ``(dpf - dpc) x df`` is dropped
(Assumption 2), so the residual of the linear model against eq. 10 is exactly that term,
second order in the step. The centroidal pose integrates the momentum (``dH/dt = h``,
explicit Euler, the same rule as eq. 12 / Appendix A uses to build ``H_ref``).

Cost (eq. 18, ``||v||_L^2 = v^T diag(L) v``; Table VIII weights by default)::

    sum_{k=1}^{h} ||h_k - h_ref||_Lh^2 + ||H_k - H_ref||_LH^2 + ||p_c,k^j + dpc_k - ref||_Lpc^2
  + sum_{k=0}^{h-1} sum_i ||p_f,i^j + dpf_i - ref||_Lpf^2 + ||f^j + df||_Lf^2
                          + ||tau^j + dtau||_Ltau^2
  + proximal term  sum (reg_force |df|^2 + reg_moment |dtau|^2 + reg_position (|dpf|^2+|dpc|^2))

The state and CoM terms run over ``k = 1 .. h`` rather than the paper's ``0 .. h-1``: ``x_0``
and ``p_c,0`` are fixed, so their terms are constants, and the last stage's inputs would
otherwise only be regularised. The proximal term vanishes at ``delta = 0``, so a fixed point
of the iteration (zero step) satisfies the KKT conditions of the un-regularised QP and hence
of the original bilinear problem (the linearisation is exact at ``delta = 0``); it damps the
sequential iteration (a Levenberg-Marquardt-like step for the dropped bilinear curvature)
and makes the QP strictly convex in every search direction.

Constraints (inequality rows ``l <= A z <= u`` and box ``lb <= z <= ub``)
-------------------------------------------------------------------------
* Wrench rows: :func:`~gaitnet_mpc.control.contact.foot_wrench_constraints` (friction
  pyramid eqs. 21-22, eq. 23 normal-force limits, line-foot CoP and yaw-moment limits)
  applied to ``w^j + dw`` (bounds shifted by ``C w^j``). The *stance* rows are always
  present; in swing every row becomes ``C (w^j + dw) = 0``, which forces the whole wrench to
  zero (eq. 23 with ``sigma = 0``) because the stance rows have full column rank. Only the
  bounds change between swing and stance, so the sparsity pattern is fixed.
* Foot ties, per foot and ``k = 0 .. h-2``: ``p_f,k+1 = p_f,k`` unless the foot lifts off
  between ``k`` and ``k+1`` (then the row stays, with bounds ``+-1 km``). So a stance foot is
  stationary over its contact phase, and the stages of a swing are tied to the stance phase
  that follows it: ``p_f`` during swing *is* the next touchdown location (the dynamics do not
  use a swing foot's ``p_f``, as its wrench is zero). ``p_foot_ref`` of swing stages should
  therefore hold the planned foothold.
* Measured stance foot: a foot in stance at stage 0 is fixed (box ``lb = ub``) to its
  measured position over its current contact phase.
* Foothold bounds (eq. 24, one-step preview): ``p_min <= p_f^j + dpf <= p_max`` on the
  stages of a per-foot mask, by default the foot's next touchdown group
  (:func:`next_touchdown_mask`). Not applied to the measured stance group (the foot is
  already there).
* Lateral foot separation (``min_foot_separation_m``, beside eq. 24; not in the paper):
  at every stage ``n_y(psi_k)^T (p_f,left,k - p_f,right,k) >= d_min + l |sin(psi_L,k -
  psi_R,k)|`` (``l``: the longer of toe and heel; a foot yawed against the other sweeps
  that far sideways) with ``n_y`` the
  lateral (leftward) axis of the heading ``psi_k`` planned for the foot in swing at stage
  ``k`` (fixed within a solve, so the row is linear). Not the stance foot's measured yaw:
  a stance foot yawed by 0.1 rad would shift a 0.35 m step's lateral bound by 3.5 cm.
  During a swing the swing foot's ``p_f`` is its next touchdown, so each touchdown lands
  at least ``d_min`` on its own side of the foot it lands beside, and the legs cannot
  cross. One row per stage, upper bound ``+1 km``.
* Foot height: unless foothold bounds give a group a finite height range, its height is
  fixed to the reference (``foot_height_from_reference``, default on). Without this the
  bilinear problem is unbounded in practice: lowering a foot below the ground lengthens
  the lever arm of the horizontal forces, so the moment cost ``L^tau`` can be traded for
  the tiny ``L^{p_f}`` and the sequential iteration drifts or oscillates.
* Trust region: each tie group of ``p_f`` stays within ``trust_region_m`` (per axis) of the
  mean of its iterate positions; the axis is left free where this box misses the foothold
  bounds. ``delta p_c`` is only trust-bounded if ``trust_region_com_m`` is set: eq. 20 pins
  ``dpc`` to the momentum, so a box on it can make the QP infeasible after a new
  measurement.

Backend timing (default ``qp_backend="piqp"``)
----------------------------------------------
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

PIQP is the default. See :data:`BACKEND_TIMINGS_MS`.

Assembly cost
-------------
Building the QP takes 0.3-0.6 ms (input checks included; it took 1.4-3 ms with per-stage
Python loops): the sparsity pattern is laid out once (:class:`_Pattern`, one group of
dense blocks per kind of entry over all stages and feet), so a build fills the value
arrays with one NumPy operation per kind, gathers them into CSC order through a
precomputed permutation and copies a template matrix. The QP data are bitwise those of
the former stage-by-stage assembly (checked on the 472 QPs of a recorded walk), and
``tests/test_perf_kd_fast_paths.py`` checks them against a dense stage-by-stage one.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.control.contact import ContactParams, foot_wrench_constraints
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp import QPProblem, QPSolution, QPWorkspace, make_workspace
from gaitnet_mpc.mpc.srbm import GRAVITY_MPS2, skew
from gaitnet_mpc.robots.spec import FEET

NX = 12  # [H (6); l_G (3); k_G (3)]
N_FEET = 2
_NU_STAGE = 3 + 3 * 3 * N_FEET  # dpc (3) + df, dtau, dpf per foot = 21
_NS = NX + _NU_STAGE  # variables per stage block = 33
#: Bound of a "free" foot tie row [m]: finite so that no row has two infinite bounds (PIQP
#: drops such rows, which would change the pattern whenever the contact schedule changes).
_FREE_TIE_M = 1e3
#: Backend settings applied under ``KDConfig.qp_options``. PIQP's relative duality-gap test
#: is measured against the large state-tracking terms of eq. 18 (objective ~1e5), which
#: lets weakly active foothold bounds (gradient ~0.05) end 1e-5 m inside; one more
#: interior-point iteration with these settings reaches the bound to ~1e-9 m.
_BACKEND_OPTIONS: Mapping[str, Mapping[str, Any]] = MappingProxyType(
    {"piqp": MappingProxyType({"eps_duality_gap_rel": 1e-12, "eps_duality_gap_abs": 1e-10})}
)
_WRENCH_CACHE_SIZE = 256  # memoised foot_wrench_constraints rows, keyed by yaw

#: Total QP time [ms] of one 6-iteration sequential solve per backend (best of 40 per QP,
#: best of three runs, walking problem with h = 10; see module docstring).
BACKEND_TIMINGS_MS: Mapping[str, float] = MappingProxyType(
    {"piqp": 16.1, "osqp": 25.5, "clarabel": 44.2, "daqp": 90.7}
)


# --------------------------------------------------------------------------- helpers
def _array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape``, else :class:`ConfigError`."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(name, value, f"a float array of shape {shape}") from None
    if arr.shape != shape:
        raise ConfigError(name, arr.shape, f"shape {shape}")
    if not np.isfinite(arr).all():
        raise ConfigError(name, "non-finite entries", "finite values")
    return arr


def _bool_array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    arr = np.asarray(value)
    if arr.shape != shape:
        raise ConfigError(name, arr.shape, f"shape {shape}")
    if arr.dtype != np.bool_ and not np.all(np.isin(arr, (0, 1))):
        raise ConfigError(name, "non-boolean entries", "booleans (True = stance)")
    return arr.astype(bool)


def _foot_index(foot: object) -> int:
    if foot in FEET:
        return FEET.index(foot)  # type: ignore[arg-type]
    raise ConfigError("foothold_bounds", foot, f"keys among {FEET}")


def tie_groups(contact_foot: np.ndarray) -> np.ndarray:
    """Group label (h,) of each stage's foot position for one foot.

    Consecutive stages share ``p_f`` unless the foot lifts off between them, so the groups
    are ``[initial stance] [swing + following stance] [swing + following stance] ...``.
    """
    c = np.asarray(contact_foot, dtype=bool)
    liftoff = c[:-1] & ~c[1:]
    return np.concatenate([[0], np.cumsum(liftoff)]).astype(int)


def next_touchdown_mask(contact_foot: np.ndarray) -> np.ndarray:
    """Stages (h,) bool of one foot's next touchdown (default mask of eq. 24).

    This is the first tie group holding a swing stage (its swing stages and the stance
    phase after them, see :func:`tie_groups`); all ``False`` if the foot never swings.
    """
    c = np.asarray(contact_foot, dtype=bool)
    if c.all():
        return np.zeros(c.shape, dtype=bool)
    groups = tie_groups(c)
    return groups == groups[int(np.argmax(~c))]


# --------------------------------------------------------------------------- model
def nonlinear_step(
    x_k: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    p_com: np.ndarray,
    dt: float,
    mass_kg: float,
    gravity_mps2: float = GRAVITY_MPS2,
) -> np.ndarray:
    """Exact discrete centroidal dynamics, eq. 10 with gravity, and the pose update.

    Args:
        x_k: (12,) state ``[H (6); l_G (3); k_G (3)]``.
        f: (2, 3) contact forces [N]; tau: (2, 3) contact moments [N m].
        p_foot: (2, 3) foot positions [m]; p_com: (3,) CoM position [m].
        dt: stage length [s].

    Returns:
        (12,) ``x_{k+1}``: ``H + h dt``, ``l + (sum f + m g) dt``,
        ``k + sum ((p_f - p_c) x f + tau) dt``.
    """
    x_k = np.asarray(x_k, dtype=float)
    f = np.asarray(f, dtype=float).reshape(N_FEET, 3)
    tau = np.asarray(tau, dtype=float).reshape(N_FEET, 3)
    arm = np.asarray(p_foot, dtype=float).reshape(N_FEET, 3) - np.asarray(p_com, dtype=float)
    out = x_k.copy()
    out[0:6] += x_k[6:12] * dt
    out[6:9] += (f.sum(axis=0) + np.array([0.0, 0.0, -mass_kg * gravity_mps2])) * dt
    out[9:12] += (np.cross(arm, f).sum(axis=0) + tau.sum(axis=0)) * dt
    return out


def nonlinear_rollout(
    x0: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    p_com0: np.ndarray,
    dts_s: np.ndarray,
    mass_kg: float,
    gravity_mps2: float = GRAVITY_MPS2,
) -> tuple[np.ndarray, np.ndarray]:
    """Roll eq. 10 and eq. 20 forward: states (h+1, 12) and CoM positions (h+1, 3).

    ``f, tau, p_foot`` are (h, 2, 3); the CoM follows ``p_c,k+1 = p_c,k + l_k / m dt_k``.
    """
    h = len(dts_s)
    xs = np.zeros((h + 1, NX))
    pc = np.zeros((h + 1, 3))
    xs[0] = x0
    pc[0] = p_com0
    for k in range(h):
        dt = float(dts_s[k])
        xs[k + 1] = nonlinear_step(xs[k], f[k], tau[k], p_foot[k], pc[k], dt, mass_kg, gravity_mps2)
        pc[k + 1] = pc[k] + xs[k, 6:9] / mass_kg * dt
    return xs, pc


# --------------------------------------------------------------------------- data
@dataclass(frozen=True)
class KDTolerances:
    """Convergence tolerances of the sequential CMPC (paper Table X)."""

    position_m: float = 1e-5
    force_n: float = 1e-2
    moment_nm: float = 1e-3


@dataclass(frozen=True)
class KDIterate:
    """Total solution of iteration ``j`` (the linearisation point of eqs. 13-15).

    Attributes:
        f: (h, 2, 3) contact forces [N], feet ordered as :data:`FEET`.
        tau: (h, 2, 3) contact moments about the foot centre [N m].
        p_foot: (h, 2, 3) foot positions [m].
        p_com: (h + 1, 3) CoM positions [m]; ``p_com[0]`` is the measured CoM.
    """

    f: np.ndarray
    tau: np.ndarray
    p_foot: np.ndarray
    p_com: np.ndarray

    def __post_init__(self) -> None:
        f = np.asarray(self.f, dtype=float)
        if f.ndim != 3 or f.shape[1:] != (N_FEET, 3) or f.shape[0] < 1:
            raise ConfigError("iterate.f", f.shape, "shape (h, 2, 3) with h >= 1")
        h = f.shape[0]
        object.__setattr__(self, "f", _array("iterate.f", f, (h, N_FEET, 3)))
        object.__setattr__(self, "tau", _array("iterate.tau", self.tau, (h, N_FEET, 3)))
        object.__setattr__(self, "p_foot", _array("iterate.p_foot", self.p_foot, (h, N_FEET, 3)))
        object.__setattr__(self, "p_com", _array("iterate.p_com", self.p_com, (h + 1, 3)))

    @property
    def horizon(self) -> int:
        """Number of stages ``h``."""
        return int(self.f.shape[0])

    def apply(self, step: KDStep, alpha: float = 1.0) -> KDIterate:
        """Iterate ``j + 1 = j + alpha * delta`` (eq. 13); a new object."""
        return KDIterate(
            f=self.f + alpha * step.delta_f,
            tau=self.tau + alpha * step.delta_tau,
            p_foot=self.p_foot + alpha * step.delta_p_foot,
            p_com=self.p_com + alpha * step.delta_p_com,
        )

    def with_measured_com(self, p_com0: np.ndarray) -> KDIterate:
        """Copy with ``p_com[0]`` replaced by a new CoM measurement (3,)."""
        p_com = self.p_com.copy()
        p_com[0] = _array("p_com0", p_com0, (3,))
        return replace(self, p_com=p_com)

    @classmethod
    def initial(
        cls,
        p_com0: np.ndarray,
        p_com_ref: np.ndarray,
        p_foot_ref: np.ndarray,
        contact: np.ndarray,
        mass_kg: float,
        gravity_mps2: float = GRAVITY_MPS2,
    ) -> KDIterate:
        """Warm start ``j = 0``: references for positions, weight shared by stance feet.

        Args:
            p_com0: (3,) measured CoM; p_com_ref: (h + 1, 3); p_foot_ref: (h, 2, 3);
            contact: (h, 2) stance mask.
        """
        p_foot_ref = np.asarray(p_foot_ref, dtype=float)
        h = p_foot_ref.shape[0]
        c = _bool_array("contact", contact, (h, N_FEET))
        n_stance = np.maximum(c.sum(axis=1, keepdims=True), 1)
        f = np.zeros((h, N_FEET, 3))
        f[:, :, 2] = c * mass_kg * gravity_mps2 / n_stance
        p_com = np.array(_array("p_com_ref", p_com_ref, (h + 1, 3)))
        p_com[0] = _array("p_com0", p_com0, (3,))
        return cls(f=f, tau=np.zeros((h, N_FEET, 3)), p_foot=p_foot_ref.copy(), p_com=p_com)


@dataclass(frozen=True)
class KDStep:
    """Solution of one CMPC sub-problem.

    Attributes:
        delta_f: (h, 2, 3) force search direction [N].
        delta_tau: (h, 2, 3) moment search direction [N m].
        delta_p_foot: (h, 2, 3) foot-position search direction [m].
        delta_p_com: (h + 1, 3) CoM search direction [m]; row 0 is zero.
        states: (h + 1, 12) predicted ``[H; l_G; k_G]``, ``states[0] = x0``.
        solution: the backend's :class:`QPSolution`.
        max_delta_pos_m: ``max |delta p_f|, |delta p_c|``.
        max_delta_force_n: ``max |delta f|``.
        max_delta_moment_nm: ``max |delta tau|``.
    """

    delta_f: np.ndarray
    delta_tau: np.ndarray
    delta_p_foot: np.ndarray
    delta_p_com: np.ndarray
    states: np.ndarray
    solution: QPSolution
    max_delta_pos_m: float
    max_delta_force_n: float
    max_delta_moment_nm: float

    def converged(self, tol: KDTolerances | None = None) -> bool:
        """Whether every search direction is within the tolerances (Table X)."""
        tol = tol or KDTolerances()
        return (
            self.max_delta_pos_m <= tol.position_m
            and self.max_delta_force_n <= tol.force_n
            and self.max_delta_moment_nm <= tol.moment_nm
        )


def _positive(name: str, value: float) -> None:
    if not (np.isfinite(value) and value > 0.0):
        raise ConfigError(name, value, "a finite float > 0")


def _weights(name: str, value: tuple[float, ...], size: int) -> None:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)) or np.any(arr < 0.0):
        raise ConfigError(name, value, f"{size} finite non-negative floats")


@dataclass(frozen=True)
class KDConfig:
    """Parameters of the CMPC sub-problem (paper Tables VIII and X; units in names).

    Weights are the diagonals of eq. 18's ``L`` matrices (``w_momentum`` is ``L^h`` over
    ``[l_G; k_G]``, ``w_pose`` is ``L^H``). ``reg_*`` weight the proximal term on the
    search directions (module docstring). ``trust_region_m`` bounds each foot-position
    tie group per axis around its iterate (``None``: off); ``trust_region_com_m`` the same
    for ``delta p_c`` (off by default, see module docstring). ``foot_height_from_reference``
    fixes the height of every free foot-position group to its reference (mean over the
    group's stance stages) unless foothold bounds give it a finite height range.
    ``qp_options`` are passed to :func:`~gaitnet_mpc.mpc.qp.make_workspace` (over
    module defaults for PIQP: tighter duality-gap tolerances, see ``_BACKEND_OPTIONS``).
    """

    horizon: int = 10
    mass_kg: float = 16.0  # humanoid3d total mass; pass RobotModel.total_mass_kg
    gravity_mps2: float = GRAVITY_MPS2
    w_momentum: tuple[float, ...] = (10.0,) * 6  # L^h
    w_pose: tuple[float, ...] = (200.0,) * 6  # L^H
    w_p_foot: tuple[float, float, float] = (0.1, 0.1, 0.1)  # L^{p_f}
    w_p_com: tuple[float, float, float] = (100.0, 100.0, 250.0)  # L^{p_c}
    w_force: float = 1e-4  # L^f
    w_moment: float = 1e-3  # L^tau
    reg_force: float = 1e-6
    reg_moment: float = 1e-5
    reg_position: float = 1e-2
    contact: ContactParams = field(default_factory=ContactParams)
    toe_m: float = 0.075
    heel_m: float = 0.075
    foot_height_from_reference: bool = True
    #: Smallest lateral distance [m] between the feet in the stance foot's heading frame
    #: (module docstring); None: no such row (the paper has none).
    min_foot_separation_m: float | None = None
    trust_region_m: float | None = 0.1
    trust_region_com_m: float | None = None
    qp_backend: str = "piqp"  # fastest here, see BACKEND_TIMINGS_MS
    qp_options: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.horizon, int | np.integer) or self.horizon < 1:
            raise ConfigError("horizon", self.horizon, "an integer >= 1")
        _positive("mass_kg", self.mass_kg)
        if not (np.isfinite(self.gravity_mps2) and self.gravity_mps2 >= 0.0):
            raise ConfigError("gravity_mps2", self.gravity_mps2, "a finite float >= 0")
        _weights("w_momentum", self.w_momentum, 6)
        _weights("w_pose", self.w_pose, 6)
        _weights("w_p_foot", self.w_p_foot, 3)
        _weights("w_p_com", self.w_p_com, 3)
        for name in ("w_force", "w_moment", "reg_force", "reg_moment", "reg_position"):
            _weights(name, (getattr(self, name),), 1)
        for name in ("toe_m", "heel_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0):
                raise ConfigError(name, value, "a finite float >= 0 (0 for a point foot)")
        for name in ("trust_region_m", "trust_region_com_m", "min_foot_separation_m"):
            value = getattr(self, name)
            if value is not None:
                _positive(name, value)


# --------------------------------------------------------------------------- pattern
class _Pattern:
    """Fixed layout of a sparse matrix assembled from groups of dense blocks.

    The QP is assembled into a flat *assembly* array (one slot per reserved entry, in the
    order reserved); :meth:`finalize` sorts the slots into canonical CSC order once, so
    :meth:`csc` is one gather into a matrix with always the same ``indptr``/``indices``
    (QP workspaces then update in place). Explicit zeros are kept.
    """

    def __init__(self, shape: tuple[int, int]) -> None:
        self.shape = shape
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []
        self.nnz = 0
        self._perm: np.ndarray | None = None
        self._indices: np.ndarray | None = None
        self._indptr: np.ndarray | None = None

    def _reserve(self, rows: np.ndarray, cols: np.ndarray) -> slice:
        self._rows.append(rows.ravel())
        self._cols.append(cols.ravel())
        start = self.nnz
        self.nnz += rows.size
        return slice(start, self.nnz)

    def add(self, rows: np.ndarray, cols: np.ndarray) -> slice:
        """Dense blocks ``rows[..., r] x cols[..., c]`` (leading axes: one block each);
        slots in ``(block..., r, c)`` order, i.e. each block row-major."""
        rows, cols = np.asarray(rows), np.asarray(cols)
        r, c = np.broadcast_arrays(rows[..., :, None], cols[..., None, :])
        return self._reserve(r, c)

    def add_diag(self, rows: np.ndarray, cols: np.ndarray) -> slice:
        """Entries ``(rows[...], cols[...])`` (same shape), slots in C order."""
        r, c = np.broadcast_arrays(np.asarray(rows), np.asarray(cols))
        return self._reserve(r, c)

    def finalize(self) -> None:
        rows = np.concatenate(self._rows)
        cols = np.concatenate(self._cols)
        ids = sp.coo_matrix(
            (np.arange(1, self.nnz + 1, dtype=float), (rows, cols)), shape=self.shape
        ).tocsc()
        if ids.nnz != self.nnz:  # pragma: no cover - layout bug
            raise RuntimeError("duplicate entries in a sparse pattern")
        ids.sort_indices()
        self._perm = ids.data.astype(np.int64) - 1
        self._indices = ids.indices.copy()
        self._indptr = ids.indptr.copy()
        self._template = sp.csc_matrix(
            (np.zeros(self.nnz), self._indices.copy(), self._indptr.copy()), shape=self.shape
        )
        self._template.has_canonical_format = True

    def csc(self, data: np.ndarray) -> sp.csc_matrix:
        """Canonical CSC matrix of an assembly array (nnz,), always the same pattern (a
        new matrix each call with its own arrays; the caller owns it).

        A shallow copy of a checked template with its three arrays replaced skips the
        format checks of SciPy's constructor (a third of the assembly time otherwise).
        """
        assert self._perm is not None and self._indices is not None and self._indptr is not None
        out = copy.copy(self._template)
        out.data = data[self._perm]
        out.indices = self._indices.copy()
        out.indptr = self._indptr.copy()
        return out


def _skew_batch(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices (..., 3, 3) of vectors (..., 3), entry for entry
    :func:`~gaitnet_mpc.mpc.srbm.skew`."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


# --------------------------------------------------------------------------- sub-problem
class KDSubproblem:
    """Builds and solves the CMPC QP of one sequential iteration (eqs. 13-24).

    The QP keeps one sparsity pattern for a given configuration (swing/stance, ties and
    foothold bounds only change bounds), so OSQP/PIQP workspaces update in place.

    Args:
        config: parameters (:class:`KDConfig`).
        workspace: a QP workspace to use instead of ``make_workspace(config.qp_backend)``.
    """

    def __init__(
        self, config: KDConfig | None = None, workspace: QPWorkspace | None = None
    ) -> None:
        self.config = config or KDConfig()
        c = self.config
        self.horizon = h = int(c.horizon)
        options = {**_BACKEND_OPTIONS.get(c.qp_backend, {}), **dict(c.qp_options)}
        self.workspace = workspace or make_workspace(c.qp_backend, **options)
        self.n = _NS * h + NX + 3
        c_rows, _, _ = foot_wrench_constraints(0.0, c.contact, c.toe_m, c.heel_m, True)
        self.n_wrench_rows = int(c_rows.shape[0])
        if np.linalg.matrix_rank(c_rows) != 6:  # pragma: no cover - contact model change
            raise ConfigError("contact", c.contact, "stance wrench rows of full column rank")
        self._wrench_cache: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._wrench_stack_last: tuple[bytes, tuple[np.ndarray, ...]] | None = None
        self._build_columns()
        self._build_patterns()
        self._build_cost_diag()

    # ------------------------------------------------------------------ layout
    def ix(self, k: int) -> int:
        """Column of ``x_k`` (12 entries), ``k = 0 .. h``."""
        return _NS * k

    def ipc(self, k: int) -> int:
        """Column of ``delta p_c,k`` (3), ``k = 0 .. h``."""
        return _NS * k + NX

    def i_f(self, k: int, i: int) -> int:
        """Column of ``delta f_i,k`` (3)."""
        return _NS * k + NX + 3 + 3 * i

    def i_tau(self, k: int, i: int) -> int:
        """Column of ``delta tau_i,k`` (3)."""
        return _NS * k + NX + 3 + 3 * N_FEET + 3 * i

    def i_pf(self, k: int, i: int) -> int:
        """Column of ``delta p_f,i,k`` (3)."""
        return _NS * k + NX + 3 + 6 * N_FEET + 3 * i

    @property
    def m_eq(self) -> int:
        """Equality rows: ``x_0`` (12), ``dpc_0`` (3), dynamics + CoM (15 per stage)."""
        return 15 + 15 * self.horizon

    @property
    def m_ineq(self) -> int:
        """Inequality rows: wrench rows per foot and stage, ``p_f`` tie rows, then (with
        ``min_foot_separation_m``) one lateral-separation row per stage."""
        h = self.horizon
        n_sep = h if self.config.min_foot_separation_m is not None else 0
        return N_FEET * h * self.n_wrench_rows + N_FEET * 3 * (h - 1) + n_sep

    def _build_columns(self) -> None:
        """Column index arrays of every variable group (layout of the module docstring)."""
        h = self.horizon
        stage = _NS * np.arange(h + 1)[:, None]  # (h+1, 1) first column of each block
        self._col_x = stage + np.arange(NX)  # (h+1, 12) x_k
        self._col_pc = stage + NX + np.arange(3)  # (h+1, 3) dpc_k
        foot = 3 * np.arange(N_FEET)[:, None] + np.arange(3)  # (2, 3)
        self._col_f = stage[:h, :, None] + NX + 3 + foot  # (h, 2, 3) df_i,k
        self._col_tau = self._col_f + 3 * N_FEET  # dtau_i,k
        self._col_pf = self._col_f + 6 * N_FEET  # dpf_i,k

    def _build_patterns(self) -> None:
        """Reserve every nonzero of ``A_eq`` and ``A``, one vectorised group per kind of
        block (all stages and feet at once), and the constant entries' values."""
        h = self.horizon
        r3, r6, r12 = np.arange(3), np.arange(6), np.arange(NX)
        row = (15 + 15 * np.arange(h))[:, None]  # (h, 1) first dynamics row of stage k
        x_k, x_next = self._col_x[:-1], self._col_x[1:]  # (h, 12)
        pc_k, pc_next = self._col_pc[:-1], self._col_pc[1:]  # (h, 3)
        rows_l = (row + 6 + r3)[:, None, :]  # (h, 1, 3) l_{k+1} rows (eqs. 14, 19)
        rows_k = (row + 9 + r3)[:, None, :]  # (h, 1, 3) k_{k+1} rows (eqs. 15, 19)
        rows_c = row + 12 + r3  # (h, 3) CoM rows (eq. 20)

        eq = _Pattern((self.m_eq, self.n))
        plus_one = (
            eq.add_diag(r12, self._col_x[0]),  # x_0 = measurement
            eq.add_diag(NX + r3, self._col_pc[0]),  # dpc_0 = 0
            eq.add_diag(row + r12, x_next),  # x_{k+1}
            eq.add_diag(rows_c, pc_next),  # dpc_{k+1}
        )
        minus_one = (eq.add_diag(row + r12, x_k), eq.add_diag(rows_c, pc_k))
        self._s_hdt = eq.add_diag(row + r6, x_k[:, 6:])  # (h, 6): -dt h_k
        self._s_df_diag = eq.add_diag(rows_l, self._col_f)  # (h, 2, 3): -dt df
        self._s_dtau = eq.add_diag(rows_k, self._col_tau)  # (h, 2, 3): -dt dtau
        self._s_dpf = eq.add(rows_k, self._col_pf)  # (h, 2, 3, 3): dt skew(f)
        self._s_df_arm = eq.add(rows_k, self._col_f)  # (h, 2, 3, 3): -dt skew(r)
        self._s_dpc = eq.add(rows_k[:, 0], pc_k)  # (h, 3, 3): -dt sum skew(f)
        self._s_com_l = eq.add_diag(rows_c, x_k[:, 6:9])  # (h, 3): -dt / m l_k
        eq.finalize()
        self._eq = eq
        data = np.zeros(eq.nnz)
        for s in plus_one:
            data[s] = 1.0
        for s in minus_one:
            data[s] = -1.0
        self._eq_data_template = data

        ineq = _Pattern((self.m_ineq, self.n))
        mw = self.n_wrench_rows
        wrench_rows = mw * np.arange(h * N_FEET).reshape(h, N_FEET, 1) + np.arange(mw)
        wrench_cols = np.concatenate([self._col_f, self._col_tau], axis=2)  # (h, 2, 6)
        self._s_wrench = ineq.add(wrench_rows, wrench_cols)  # (h, 2, mw, 6)
        self._tie_row0 = tie0 = N_FEET * h * mw
        tie_rows = tie0 + 3 * np.arange((h - 1) * N_FEET).reshape(h - 1, N_FEET, 1) + r3
        tie_next = ineq.add_diag(tie_rows, self._col_pf[1:])  # (h-1, 2, 3)
        tie_prev = ineq.add_diag(tie_rows, self._col_pf[:-1])
        self._s_sep: slice | None = None
        if self.config.min_foot_separation_m is not None:
            sep_rows = (tie0 + N_FEET * 3 * (h - 1) + np.arange(h))[:, None]  # (h, 1)
            sep_cols = self._col_pf[:, :, :2].reshape(h, 2 * N_FEET)  # (h, 4): xL yL xR yR
            self._s_sep = ineq.add(sep_rows, sep_cols)  # (h, 1, 4)
        ineq.finalize()
        self._ineq = ineq
        data = np.zeros(ineq.nnz)
        data[tie_next] = 1.0
        data[tie_prev] = -1.0
        self._ineq_data_template = data

    def _build_cost_diag(self) -> None:
        """Diagonal weights of eq. 18 plus the proximal term, and the linear-cost factors."""
        c = self.config
        diag = np.zeros(self.n)  # weights W of sum_v W v^2 (P = 2 W)
        diag[self._col_x[1:, :6]] = c.w_pose
        diag[self._col_x[1:, 6:]] = c.w_momentum
        diag[self._col_pc[1:]] = np.asarray(c.w_p_com) + c.reg_position
        diag[self._col_pc[0]] = c.reg_position
        diag[self._col_f] = c.w_force + c.reg_force
        diag[self._col_tau] = c.w_moment + c.reg_moment
        diag[self._col_pf] = np.asarray(c.w_p_foot) + c.reg_position
        self._w_diag = diag
        self._P = sp.diags(2.0 * diag, format="csc")
        # gradient factors of eq. 18 at the iterate (q = 2 W (value - reference))
        self._q_pose = -2.0 * np.asarray(c.w_pose)
        self._q_momentum = -2.0 * np.asarray(c.w_momentum)
        self._q_p_com = 2.0 * np.asarray(c.w_p_com)
        self._q_force = 2.0 * c.w_force
        self._q_moment = 2.0 * c.w_moment
        self._q_p_foot = 2.0 * np.asarray(c.w_p_foot)

    # ------------------------------------------------------------------ validation
    def _check_inputs(
        self,
        x0: object,
        iterate: object,
        h_ref: object,
        H_ref: object,
        p_foot_ref: object,
        p_com_ref: object,
        dts_s: object,
        contact: object,
        foot_yaw_rad: object,
        foothold_bounds: object,
        p_foot_measured: object,
    ) -> dict[str, Any]:
        h = self.horizon
        if not isinstance(iterate, KDIterate):
            raise ConfigError("iterate", type(iterate).__name__, "a KDIterate")
        if iterate.horizon != h:
            raise ConfigError("iterate", f"horizon {iterate.horizon}", f"horizon {h}")
        out: dict[str, Any] = {
            "x0": _array("x0", x0, (NX,)),
            "h_ref": _array("h_ref", h_ref, (h + 1, 6)),
            "H_ref": _array("H_ref", H_ref, (h + 1, 6)),
            "p_foot_ref": _array("p_foot_ref", p_foot_ref, (h, N_FEET, 3)),
            "p_com_ref": _array("p_com_ref", p_com_ref, (h + 1, 3)),
            "dts_s": _array("dts_s", dts_s, (h,)),
            "contact": _bool_array("contact", contact, (h, N_FEET)),
            "foot_yaw_rad": _array("foot_yaw_rad", foot_yaw_rad, (h, N_FEET)),
        }
        if np.any(out["dts_s"] <= 0.0):
            raise ConfigError("dts_s", out["dts_s"].tolist(), "sampling times > 0 [s]")
        out["p_foot_measured"] = (
            iterate.p_foot[0].copy()
            if p_foot_measured is None
            else _array("p_foot_measured", p_foot_measured, (N_FEET, 3))
        )
        bounds: list[tuple[np.ndarray, np.ndarray, np.ndarray] | None] = [None] * N_FEET
        if foothold_bounds is not None:
            if not isinstance(foothold_bounds, Mapping):
                raise ConfigError(
                    "foothold_bounds", type(foothold_bounds).__name__, "a dict foot -> bounds"
                )
            for foot, entry in foothold_bounds.items():
                i = _foot_index(foot)
                name = f"foothold_bounds[{foot!r}]"
                if not isinstance(entry, tuple | list) or len(entry) not in (2, 3):
                    raise ConfigError(name, entry, "a tuple (p_min, p_max[, stage_mask])")
                p_min = np.full(3, -np.inf) if entry[0] is None else np.asarray(entry[0], float)
                p_max = np.full(3, np.inf) if entry[1] is None else np.asarray(entry[1], float)
                for side, value in (("p_min", p_min), ("p_max", p_max)):
                    if value.shape != (3,) or np.any(np.isnan(value)):
                        raise ConfigError(f"{name}.{side}", value, "shape (3,), no NaN, or None")
                if np.any(p_min > p_max):
                    raise ConfigError(name, (p_min.tolist(), p_max.tolist()), "p_min <= p_max")
                mask_value = entry[2] if len(entry) == 3 else None
                mask = (
                    next_touchdown_mask(out["contact"][:, i])
                    if mask_value is None
                    else _bool_array(f"{name}.stage_mask", mask_value, (h,))
                )
                bounds[i] = (p_min, p_max, mask)
        out["foothold_bounds"] = bounds
        return out

    # ------------------------------------------------------------------ build
    def build(
        self,
        x0: np.ndarray,
        iterate: KDIterate,
        h_ref: np.ndarray,
        H_ref: np.ndarray,
        p_foot_ref: np.ndarray,
        p_com_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        foot_yaw_rad: np.ndarray,
        foothold_bounds: Mapping[str, tuple[Any, ...]] | None = None,
        p_foot_measured: np.ndarray | None = None,
    ) -> QPProblem:
        """The CMPC QP of iteration ``j + 1`` about ``iterate`` (``j``).

        Args:
            x0: (12,) measured ``[H; l_G; k_G]``.
            iterate: linearisation point; ``iterate.p_com[0]`` is the measured CoM.
            h_ref: (h + 1, 6) momentum reference ``[l_G; k_G]``; row 0 unused.
            H_ref: (h + 1, 6) centroidal-pose reference; row 0 unused.
            p_foot_ref: (h, 2, 3) foot reference [m] (swing stages: planned foothold).
            p_com_ref: (h + 1, 3) CoM reference [m]; row 0 unused.
            dts_s: (h,) per-stage sampling time [s].
            contact: (h, 2) stance mask (True = stance), feet ordered as :data:`FEET`.
            foot_yaw_rad: (h, 2) foot heading (line-foot wrench limits).
            foothold_bounds: foot name -> ``(p_min (3,) | None, p_max (3,) | None,
                stage_mask (h,) | None)`` (eq. 24); a ``None`` mask means the foot's next
                touchdown (:func:`next_touchdown_mask`).
            p_foot_measured: (2, 3) measured foot positions; a foot in stance at stage 0
                is fixed there. ``None``: ``iterate.p_foot[0]``.

        Raises:
            ConfigError: an argument has the wrong shape or invalid values.
        """
        a = self._check_inputs(
            x0, iterate, h_ref, H_ref, p_foot_ref, p_com_ref, dts_s, contact,
            foot_yaw_rad, foothold_bounds, p_foot_measured,
        )  # fmt: skip
        return self._assemble(iterate, a)

    def _assemble(self, it: KDIterate, a: dict[str, Any]) -> QPProblem:
        """The QP of :meth:`build`, every stage and foot at once (vectorised)."""
        c = self.config
        h = self.horizon
        m = c.mass_kg
        dts = a["dts_s"]  # (h,)
        contact = a["contact"]  # (h, 2)
        g_vec = np.array([0.0, 0.0, -c.gravity_mps2])
        arms = it.p_foot - it.p_com[:-1, None, :]  # (h, 2, 3) r_i^j = p_f,i - p_c,k
        skew_f = _skew_batch(it.f)  # (h, 2, 3, 3)
        skew_r = _skew_batch(arms)

        # ---- equality rows (dynamics, eqs. 14, 15, 19, 20). Row form of the angular rows:
        # k_{k+1} - k_k - dt [dtau - skew(f) dpf + skew(f) dpc + skew(r) df]
        #   = dt sum_i (r_i x f_i + tau_i)               (-f x dpf = -skew(f) dpf etc.)
        d = self._eq_data_template.copy()
        d[self._s_hdt] = np.repeat(-dts, 6)
        d[self._s_df_diag] = np.repeat(-dts, 3 * N_FEET)
        d[self._s_dtau] = np.repeat(-dts, 3 * N_FEET)
        d[self._s_dpf] = (dts[:, None, None, None] * skew_f).ravel()
        d[self._s_df_arm] = (-dts[:, None, None, None] * skew_r).ravel()
        d[self._s_dpc] = (-dts[:, None, None] * (skew_f[:, 0] + skew_f[:, 1])).ravel()
        d[self._s_com_l] = np.repeat(-dts / m, 3)
        b = np.zeros(self.m_eq)
        b[:NX] = a["x0"]
        stage_b = b[15:].reshape(h, 15)  # view: rows of stage k
        stage_b[:, 6:9] = dts[:, None] * (it.f.sum(axis=1) + m * g_vec)
        torque = np.matmul(skew_r, it.f[..., None])[..., 0] + it.tau  # (h, 2, 3) r x f + tau
        stage_b[:, 9:12] = dts[:, None] * (torque[:, 0] + torque[:, 1])
        stage_b[:, 12:15] = it.p_com[:-1] - it.p_com[1:]
        a_eq = self._eq.csc(d)

        # ---- inequality rows: wrenches (eqs. 21-23) and foot ties
        cm, l_w, u_w = self._wrench_stack(a["foot_yaw_rad"])  # (h, 2, mw, 6), (h, 2, mw) x2
        data = self._ineq_data_template.copy()
        data[self._s_wrench] = cm.ravel()
        wrench = np.concatenate([it.f, it.tau], axis=2)[..., None]  # (h, 2, 6, 1)
        shift = np.matmul(cm, wrench)[..., 0]  # (h, 2, mw): C w^j
        stance = contact[:, :, None]
        lo_w = np.where(stance, l_w - shift, -shift)  # swing: C (w^j + dw) = 0
        hi_w = np.where(stance, u_w - shift, -shift)
        free = (contact[:-1] & ~contact[1:])[:, :, None]  # lift-off between k and k+1
        gap = it.p_foot[:-1] - it.p_foot[1:]  # (h-1, 2, 3)
        lo_parts = [lo_w.ravel(), np.where(free, -_FREE_TIE_M, gap).ravel()]
        hi_parts = [hi_w.ravel(), np.where(free, _FREE_TIE_M, gap).ravel()]
        if self._s_sep is not None:
            n_y, sep = self._separation(it, contact, a["foot_yaw_rad"])
            data[self._s_sep] = np.concatenate([n_y, -n_y], axis=1).ravel()
            yaw = a["foot_yaw_rad"]
            sweep = max(c.toe_m, c.heel_m) * np.abs(np.sin(yaw[:, 0] - yaw[:, 1]))
            lo_parts.append(c.min_foot_separation_m + sweep - sep)
            hi_parts.append(_FREE_TIE_M - sep)
        lo = np.concatenate(lo_parts)
        hi = np.concatenate(hi_parts)
        a_in = self._ineq.csc(data)

        # ---- box: foot positions (measured stance foot, eq. 24, trust region)
        lb = np.full(self.n, -np.inf)
        ub = np.full(self.n, np.inf)
        for i in range(N_FEET):
            self._foot_box(i, it, a, lb, ub)
        if c.trust_region_com_m is not None:
            lb[self._col_pc[1:]] = -c.trust_region_com_m
            ub[self._col_pc[1:]] = c.trust_region_com_m

        # ---- cost (eq. 18) + proximal term
        q = np.zeros(self.n)
        q[self._col_x[1:, :6]] = self._q_pose * a["H_ref"][1:]
        q[self._col_x[1:, 6:]] = self._q_momentum * a["h_ref"][1:]
        q[self._col_pc[1:]] = self._q_p_com * (it.p_com[1:] - a["p_com_ref"][1:])
        q[self._col_f] = self._q_force * it.f
        q[self._col_tau] = self._q_moment * it.tau
        q[self._col_pf] = self._q_p_foot * (it.p_foot - a["p_foot_ref"])
        return QPProblem(self._P, q, A_eq=a_eq, b_eq=b, A=a_in, l=lo, u=hi, lb=lb, ub=ub)

    @staticmethod
    def _separation(
        it: KDIterate, contact: np.ndarray, foot_yaw_rad: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Leftward axes ``n_y(psi_k)`` (h, 2) of the separation rows (``psi_k``: the
        heading of the foot in swing at stage ``k``, the right foot's where both or neither
        stand) and the iterate's separation ``n_y^T (p_left - p_right)`` (h,) [m]."""
        h = contact.shape[0]
        swing = np.where(contact[:, 1] & ~contact[:, 0], 0, 1)
        yaw = foot_yaw_rad[np.arange(h), swing]
        n_y = np.stack([-np.sin(yaw), np.cos(yaw)], axis=1)  # left = +y of the heading
        d = it.p_foot[:, 0, :2] - it.p_foot[:, 1, :2]
        return n_y, np.einsum("kj,kj->k", n_y, d)

    def _wrench_rows(self, yaw_rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stance rows of :func:`foot_wrench_constraints` at ``yaw_rad``, memoised."""
        rows = self._wrench_cache.get(yaw_rad)
        if rows is None:
            c = self.config
            rows = foot_wrench_constraints(yaw_rad, c.contact, c.toe_m, c.heel_m, True)
            if rows[0].shape[0] != self.n_wrench_rows:  # pragma: no cover - model change
                raise ConfigError("foot_yaw_rad", yaw_rad, "a yaw with the stance row count")
            if len(self._wrench_cache) >= _WRENCH_CACHE_SIZE:
                self._wrench_cache.clear()
            self._wrench_cache[yaw_rad] = rows
        return rows

    def _wrench_stack(self, foot_yaw_rad: np.ndarray) -> tuple[np.ndarray, ...]:
        """Stance rows ``C`` (h, 2, mw, 6) and bounds ``l, u`` (h, 2, mw) of every stage
        and foot; the last result is kept (the yaws are fixed within a sequential solve)."""
        key = foot_yaw_rad.tobytes()
        if self._wrench_stack_last is not None and self._wrench_stack_last[0] == key:
            return self._wrench_stack_last[1]
        rows = [self._wrench_rows(yaw) for yaw in foot_yaw_rad.ravel().tolist()]
        shape = (*foot_yaw_rad.shape, self.n_wrench_rows)
        out = (
            np.stack([r[0] for r in rows]).reshape(*shape, 6),
            np.stack([r[1] for r in rows]).reshape(shape),
            np.stack([r[2] for r in rows]).reshape(shape),
        )
        for arr in out:
            arr.flags.writeable = False
        self._wrench_stack_last = (key, out)
        return out

    def _foot_box(
        self, i: int, it: KDIterate, a: dict[str, Any], lb: np.ndarray, ub: np.ndarray
    ) -> None:
        """Box on ``delta p_f`` of foot ``i``, per tie group, in absolute positions.

        Per group (:func:`tie_groups`: swing stages, then the stance stages after them):
        the measured position for the measured stance group; else the eq. 24 box if the
        group holds a masked stage, the reference height (mean over the group's stance
        stages, or all its stages) unless that box bounds the height, and the trust
        region around the group's mean iterate. Groups are contiguous stage ranges, so
        plain Python over the few groups with slices is cheapest here.
        """
        c = self.config
        h = self.horizon
        contact_i = a["contact"][:, i].tolist()
        starts = [0] + [k for k in range(1, h) if contact_i[k - 1] and not contact_i[k]]
        ends = [*starts[1:], h]
        n_groups = len(starts)
        p_it = it.p_foot[:, i]  # (h, 3)
        lo = np.full((n_groups, 3), -np.inf)  # absolute bounds per group
        hi = np.full((n_groups, 3), np.inf)
        centre = np.zeros((n_groups, 3))  # mean iterate per group
        bounds = a["foothold_bounds"][i]
        mask = None if bounds is None else bounds[2].tolist()
        measured = contact_i[0]  # group 0 is the measured stance foot: fixed
        ref_z = a["p_foot_ref"][:, i, 2]
        for g in range(1 if measured else 0, n_groups):
            s0, s1 = starts[g], ends[g]
            centre[g] = np.add.reduce(p_it[s0:s1], axis=0) / (s1 - s0)  # == .mean(axis=0)
            if mask is not None and any(mask[s0:s1]):
                lo[g], hi[g] = bounds[0], bounds[1]  # type: ignore[index]
            if c.foot_height_from_reference and not (
                np.isfinite(lo[g, 2]) and np.isfinite(hi[g, 2])
            ):
                n_stance = sum(contact_i[s0:s1])  # stance stages end the group
                z0 = s1 - n_stance if n_stance else s0
                lo[g, 2] = hi[g, 2] = float(np.add.reduce(ref_z[z0:s1]) / (s1 - z0))
        if c.trust_region_m is not None:
            t_lo = np.maximum(lo, centre - c.trust_region_m)
            t_hi = np.minimum(hi, centre + c.trust_region_m)
            ok = t_lo <= t_hi  # trust box misses the foothold box: drop it there
            lo = np.where(ok, t_lo, lo)
            hi = np.where(ok, t_hi, hi)
        if measured:
            lo[0] = hi[0] = a["p_foot_measured"][i]
        groups = np.repeat(np.arange(n_groups), np.subtract(ends, starts))  # (h,)
        cols = self._col_pf[:, i]  # (h, 3)
        lb[cols] = lo[groups] - p_it
        ub[cols] = hi[groups] - p_it

    # ------------------------------------------------------------------ solve
    def unpack(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """Split a QP vector (n,) into ``states (h+1, 12)``, ``delta_p_com (h+1, 3)``,
        ``delta_f``, ``delta_tau``, ``delta_p_foot`` (h, 2, 3)."""
        h = self.horizon
        z = np.asarray(z, dtype=float)
        body = z[: _NS * h].reshape(h, _NS)
        tail = z[_NS * h :]
        states = np.vstack([body[:, :NX], tail[:NX]])
        dpc = np.vstack([body[:, NX : NX + 3], tail[NX:]])
        u = body[:, NX + 3 :]
        return {
            "states": states,
            "delta_p_com": dpc,
            "delta_f": u[:, : 3 * N_FEET].reshape(h, N_FEET, 3),
            "delta_tau": u[:, 3 * N_FEET : 6 * N_FEET].reshape(h, N_FEET, 3),
            "delta_p_foot": u[:, 6 * N_FEET :].reshape(h, N_FEET, 3),
        }

    def pack(
        self,
        states: np.ndarray,
        delta_f: np.ndarray,
        delta_tau: np.ndarray,
        delta_p_foot: np.ndarray,
        delta_p_com: np.ndarray,
    ) -> np.ndarray:
        """Inverse of :meth:`unpack`: the QP vector (n,) of states and search directions."""
        h = self.horizon
        body = np.zeros((h, _NS))
        body[:, :NX] = np.asarray(states)[:h]
        body[:, NX : NX + 3] = np.asarray(delta_p_com)[:h]
        body[:, NX + 3 : NX + 3 + 3 * N_FEET] = np.asarray(delta_f).reshape(h, -1)
        body[:, NX + 3 + 3 * N_FEET : NX + 3 + 6 * N_FEET] = np.asarray(delta_tau).reshape(h, -1)
        body[:, NX + 3 + 6 * N_FEET :] = np.asarray(delta_p_foot).reshape(h, -1)
        return np.concatenate([body.ravel(), np.asarray(states)[h], np.asarray(delta_p_com)[h]])

    def solve(
        self,
        x0: np.ndarray,
        iterate: KDIterate,
        h_ref: np.ndarray,
        H_ref: np.ndarray,
        p_foot_ref: np.ndarray,
        p_com_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        foot_yaw_rad: np.ndarray,
        foothold_bounds: Mapping[str, tuple[Any, ...]] | None = None,
        p_foot_measured: np.ndarray | None = None,
    ) -> KDStep:
        """Build (see :meth:`build`) and solve the CMPC QP; return the search directions.

        Raises:
            ConfigError: bad arguments (see :meth:`build`).
            QPSolveError: the backend found no usable solution.
        """
        problem = self.build(
            x0, iterate, h_ref, H_ref, p_foot_ref, p_com_ref, dts_s, contact,
            foot_yaw_rad, foothold_bounds, p_foot_measured,
        )  # fmt: skip
        sol = self.workspace.solve_or_raise(problem)
        parts = self.unpack(sol.x)
        parts["delta_p_com"][0] = 0.0
        return KDStep(
            delta_f=parts["delta_f"],
            delta_tau=parts["delta_tau"],
            delta_p_foot=parts["delta_p_foot"],
            delta_p_com=parts["delta_p_com"],
            states=parts["states"],
            solution=sol,
            max_delta_pos_m=float(
                max(np.abs(parts["delta_p_foot"]).max(), np.abs(parts["delta_p_com"]).max())
            ),
            max_delta_force_n=float(np.abs(parts["delta_f"]).max()),
            max_delta_moment_nm=float(np.abs(parts["delta_tau"]).max()),
        )

    def reset(self) -> None:
        """Forget the QP workspace's state (next solve sets up from scratch)."""
        self.workspace.reset()


__all__ = [
    "BACKEND_TIMINGS_MS",
    "FEET",
    "GRAVITY_MPS2",
    "NX",
    "KDConfig",
    "KDIterate",
    "KDStep",
    "KDSubproblem",
    "KDTolerances",
    "next_touchdown_mask",
    "nonlinear_rollout",
    "nonlinear_step",
    "skew",
    "tie_groups",
]
