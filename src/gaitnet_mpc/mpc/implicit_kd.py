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
* Wrench rows: :func:`~gaitnet_mpc.mpc.contact.foot_wrench_constraints` (friction
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
  (:func:`~gaitnet_mpc.mpc.foot_ties.next_touchdown_mask`). Not applied to the measured
  stance group (the foot is already there).
* Lateral foot separation (``min_foot_separation_m``, beside eq. 24; not in the paper):
  at every stage ``n_y(psi_k)^T (p_f,left,k - p_f,right,k) >= d_min + l |sin(psi_L,k -
  psi_R,k)|`` (``l``: the longer of toe and heel; a foot yawed against the other sweeps
  that far sideways) with ``n_y`` the lateral (leftward) axis of the heading ``psi_k``
  planned for the foot in swing at stage ``k`` (fixed within a solve, so the row is
  linear). Not the stance foot's measured yaw: a stance foot yawed by 0.1 rad would shift
  a 0.35 m step's lateral bound by 3.5 cm. During a swing the swing foot's ``p_f`` is its
  next touchdown, so each touchdown lands at least ``d_min`` on its own side of the foot it
  lands beside, and the legs cannot cross. One row per stage, upper bound ``+1 km``.
* Foot height: unless foothold bounds give a group a finite height range, its height is
  fixed to the reference (``foot_height_from_reference``, default on). Without this the
  bilinear problem is unbounded in practice: lowering a foot below the ground lengthens
  the lever arm of the horizontal forces, so the moment cost ``L^tau`` can be traded for
  the tiny ``L^{p_f}`` and the sequential iteration drifts or oscillates.
* Leg reach (``leg_reach_m``, not in the paper): :mod:`~gaitnet_mpc.mpc.kinematic_rows`.
* Trust region: each tie group of ``p_f`` stays within ``trust_region_m`` (per axis) of the
  mean of its iterate positions; the axis is left free where this box misses the foothold
  bounds. ``delta p_c`` is only trust-bounded if ``trust_region_com_m`` is set: eq. 20 pins
  ``dpc`` to the momentum, so a box on it can make the QP infeasible after a new
  measurement.

The sparsity pattern is laid out once (:class:`~gaitnet_mpc.mpc.qp.pattern.BlockPattern`);
``tests/test_perf_kd_fast_paths.py`` checks the vectorised assembly against a dense
stage-by-stage one. Related modules: the nonlinear model (eq. 10,
:mod:`~gaitnet_mpc.mpc.centroidal_model`), the variable layout
(:mod:`~gaitnet_mpc.mpc.kd_layout`), the per-solve data (:mod:`~gaitnet_mpc.mpc.kd_inputs`),
the iterate and step (:mod:`~gaitnet_mpc.mpc.kd_iterate`), the configuration and backend
timings (:mod:`~gaitnet_mpc.mpc.kd_config`), the tie groups
(:mod:`~gaitnet_mpc.mpc.foot_ties`); their public names are re-exported here.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.centroidal_model import (
    N_FEET,
    NX,
    nonlinear_rollout,
    nonlinear_step,
    skew_batch,
)
from gaitnet_mpc.mpc.contact import StanceWrenchRows
from gaitnet_mpc.mpc.foot_ties import next_touchdown_mask, tie_groups
from gaitnet_mpc.mpc.kd_condensed import CondensedQP, KDCondensed
from gaitnet_mpc.mpc.kd_config import KDConfig
from gaitnet_mpc.mpc.kd_inputs import KDInputs
from gaitnet_mpc.mpc.kd_iterate import KDIterate, KDStep, KDTolerances
from gaitnet_mpc.mpc.kd_layout import KDLayout
from gaitnet_mpc.mpc.kinematic_rows import qp_reach_rows, separation_rows
from gaitnet_mpc.mpc.qp import QPProblem, QPSolution, QPWorkspace, make_workspace
from gaitnet_mpc.mpc.qp.pattern import BlockPattern

#: Bound of a "free" foot tie row [m]: finite so that no row has two infinite bounds (PIQP
#: drops such rows, which would change the pattern whenever the contact schedule changes).
_FREE_TIE_M = 1e3


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
        self.workspace = workspace or make_workspace(c.qp_backend, **c.qp_workspace_options())
        self.layout = lay = KDLayout(h)  # columns of the module docstring's layout
        self.n = lay.n
        self._col_x, self._col_pc = lay.col_x, lay.col_pc
        self._col_f, self._col_tau, self._col_pf = lay.col_f, lay.col_tau, lay.col_pf
        self._wrench = StanceWrenchRows(c.contact, c.toe_m, c.heel_m, c.yaw_cone_half_m)
        self.n_wrench_rows = self._wrench.n_rows
        if not self._wrench.full_column_rank:  # pragma: no cover - contact model change
            raise ConfigError("contact", c.contact, "stance wrench rows of full column rank")
        self._build_patterns()
        self._build_cost_diag()
        #: The condensed form's solver (``config.qp_form == "condensed"``), else None.
        self.condensed: KDCondensed | None = None
        if c.qp_form == "condensed":
            self.condensed = KDCondensed(c)
            self._load_kernels()
        #: Condensed solves that failed and were repeated on the sparse QP.
        self.n_fallbacks = 0

    def _load_kernels(self) -> None:
        """Solve one QP of a robot standing still through the condensed form, so that
        its compiled kernels are loaded (from numba's cache: 10-100 ms on a process's
        first call) before a control loop runs, not in its first solve."""
        h, mass = self.horizon, self.config.mass_kg
        contact = np.ones((h, N_FEET), dtype=bool)
        p_com = np.tile([0.0, 0.0, 0.5], (h + 1, 1))
        p_foot = np.zeros((h, N_FEET, 3))
        p_foot[:, :, 1] = [0.1, -0.1]
        it = KDIterate.initial(p_com[0], p_com, p_foot, contact, mass)
        x0 = np.zeros(NX)
        x0[:3] = mass * p_com[0]
        pose = np.zeros((h + 1, 6))
        pose[:, :3] = mass * p_com
        dts = np.full(h, 0.05)
        dts.flags.writeable = False  # as a ReferenceTiming's: numba types read-only apart
        inputs = self.inputs(
            it, x0, np.zeros((h + 1, 6)), pose, p_foot, p_com, dts, contact,
            np.zeros((h, N_FEET)),
        )  # fmt: skip
        self._solve_condensed(it, inputs)

    # ------------------------------------------------------------------ layout
    @property
    def m_eq(self) -> int:
        """Equality rows: ``x_0`` (12), ``dpc_0`` (3), dynamics + CoM (15 per stage)."""
        return 15 + 15 * self.horizon

    @property
    def m_ineq(self) -> int:
        """Inequality rows: wrench rows per foot and stage, ``p_f`` tie rows, then (with
        ``min_foot_separation_m``) one lateral-separation row per stage and (with
        ``leg_reach_m``) four reach rows per stage and foot."""
        h = self.horizon
        n_sep = h if self.config.min_foot_separation_m is not None else 0
        n_reach = 4 * N_FEET * h if self.config.leg_reach_m is not None else 0
        return N_FEET * h * self.n_wrench_rows + N_FEET * 3 * (h - 1) + n_sep + n_reach

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

        eq = BlockPattern((self.m_eq, self.n))
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

        ineq = BlockPattern((self.m_ineq, self.n))
        mw = self.n_wrench_rows
        wrench_rows = mw * np.arange(h * N_FEET).reshape(h, N_FEET, 1) + np.arange(mw)
        wrench_cols = np.concatenate([self._col_f, self._col_tau], axis=2)  # (h, 2, 6)
        self._s_wrench = ineq.add(wrench_rows, wrench_cols)  # (h, 2, mw, 6)
        tie0 = N_FEET * h * mw
        tie_rows = tie0 + 3 * np.arange((h - 1) * N_FEET).reshape(h - 1, N_FEET, 1) + r3
        tie_next = ineq.add_diag(tie_rows, self._col_pf[1:])  # (h-1, 2, 3)
        tie_prev = ineq.add_diag(tie_rows, self._col_pf[:-1])
        self._s_sep: slice | None = None
        if self.config.min_foot_separation_m is not None:
            sep_rows = (tie0 + N_FEET * 3 * (h - 1) + np.arange(h))[:, None]  # (h, 1)
            sep_cols = self._col_pf[:, :, :2].reshape(h, 2 * N_FEET)  # (h, 4): xL yL xR yR
            self._s_sep = ineq.add(sep_rows, sep_cols)  # (h, 1, 4)
        self._s_reach: slice | None = None
        if self.config.leg_reach_m is not None:  # the last rows: n^T (dpf_k,i - dpc_k)
            n_reach = 4 * N_FEET * h
            reach_rows = self.m_ineq - n_reach + np.arange(n_reach).reshape(h, N_FEET, 4)
            pc = np.broadcast_to(self._col_pc[:-1, None, :], (h, N_FEET, 3))
            reach_cols = np.concatenate([self._col_pf, pc], axis=2)  # (h, 2, 6)
            self._s_reach = ineq.add(reach_rows, reach_cols)  # (h, 2, 4, 6)
        ineq.finalize()
        self._ineq = ineq
        data = np.zeros(ineq.nnz)
        data[tie_next] = 1.0
        data[tie_prev] = -1.0
        self._ineq_data_template = data

    def _build_cost_diag(self) -> None:
        """Diagonal weights of eq. 18 plus the proximal term, and the linear-cost factors."""
        c = self.config
        w_state, w_input = c.stage_weights()
        diag = np.zeros(self.n)  # weights W of sum_v W v^2 (P = 2 W)
        diag[self._col_x[1:]] = w_state[:NX]
        diag[self._col_pc[1:]] = w_state[NX:]
        diag[self._col_pc[0]] = c.reg_position
        diag[self._col_f] = w_input[0]
        diag[self._col_tau] = w_input[1]
        diag[self._col_pf] = w_input[2]
        self._P = sp.diags(2.0 * diag, format="csc")
        # gradient factors of eq. 18 at the iterate (q = 2 W (value - reference))
        self._q_pose = -2.0 * c.pose_weights
        self._q_momentum = -2.0 * c.momentum_weights
        self._q_p_com = 2.0 * np.asarray(c.w_p_com)
        self._q_force = 2.0 * c.w_force
        self._q_moment = 2.0 * c.w_moment
        self._q_p_foot = 2.0 * np.asarray(c.w_p_foot)

    # ------------------------------------------------------------------ build
    def inputs(
        self,
        iterate: KDIterate,
        x0: np.ndarray,
        h_ref: np.ndarray,
        H_ref: np.ndarray,
        p_foot_ref: np.ndarray,
        p_com_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        foot_yaw_rad: np.ndarray,
        foothold_bounds: Mapping[str, tuple[Any, ...]] | None = None,
        p_foot_measured: np.ndarray | None = None,
        wrench_ext: np.ndarray | None = None,
    ) -> KDInputs:
        """The per-solve data of the QP about ``iterate``, checked (:class:`KDInputs`).

        Args:
            iterate: linearisation point; ``iterate.p_com[0]`` is the measured CoM.
            x0: (12,) measured ``[H; l_G; k_G]``.
            h_ref: (h + 1, 6) momentum reference ``[l_G; k_G]``; row 0 unused.
            H_ref: (h + 1, 6) centroidal-pose reference; row 0 unused.
            p_foot_ref: (h, 2, 3) foot reference [m] (swing stages: planned foothold);
                p_com_ref: (h + 1, 3) CoM reference [m]; row 0 unused.
            dts_s: (h,) per-stage sampling time [s]; contact: (h, 2) stance mask (True =
                stance), feet as :data:`~gaitnet_mpc.robots.FEET`; foot_yaw_rad: (h, 2).
            foothold_bounds: foot name -> ``(p_min (3,) | None, p_max (3,) | None,
                stage_mask (h,) | None)`` (eq. 24); a ``None`` mask means the foot's next
                touchdown (:func:`next_touchdown_mask`).
            p_foot_measured: (2, 3) measured foot positions; a foot in stance at stage 0
                is fixed there. ``None``: ``iterate.p_foot[0]``.
            wrench_ext: (6,) ``[f_ext; tau_ext]`` beside gravity (eqs. 14-15); None: zeros.

        Raises:
            ConfigError: an argument has the wrong shape or invalid values.
        """
        return KDInputs.check(
            self.horizon, x0, iterate, h_ref, H_ref, p_foot_ref, p_com_ref, dts_s, contact,
            foot_yaw_rad, foothold_bounds, p_foot_measured, wrench_ext,
        )  # fmt: skip

    def build(self, it: KDIterate, a: KDInputs) -> QPProblem:
        """The CMPC QP of iteration ``j + 1`` about the iterate ``it`` (``j``), eqs. 13-24,
        every stage and foot at once (vectorised)."""
        c = self.config
        h = self.horizon
        m = c.mass_kg
        dts = a.dts_s  # (h,)
        contact = a.contact  # (h, 2)
        g_vec = np.array([0.0, 0.0, -c.gravity_mps2])
        arms = it.p_foot - it.p_com[:-1, None, :]  # (h, 2, 3) r_i^j = p_f,i - p_c,k
        skew_f = skew_batch(it.f)  # (h, 2, 3, 3)
        skew_r = skew_batch(arms)

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
        b[:NX] = a.x0
        stage_b = b[15:].reshape(h, 15)  # view: rows of stage k
        stage_b[:, 6:9] = dts[:, None] * (it.f.sum(axis=1) + m * g_vec + a.wrench_ext[:3])
        torque = np.matmul(skew_r, it.f[..., None])[..., 0] + it.tau  # (h, 2, 3) r x f + tau
        stage_b[:, 9:12] = dts[:, None] * (torque[:, 0] + torque[:, 1] + a.wrench_ext[3:])
        stage_b[:, 12:15] = it.p_com[:-1] - it.p_com[1:]
        a_eq = self._eq.csc(d)

        # ---- inequality rows: wrenches (eqs. 21-23) and foot ties
        cm, l_w, u_w = self._wrench.stack(a.foot_yaw_rad)  # (h, 2, mw, 6), (h, 2, mw) x2
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
            n_y, sep = separation_rows(it, contact, a.foot_yaw_rad)
            data[self._s_sep] = np.concatenate([n_y, -n_y], axis=1).ravel()
            yaw = a.foot_yaw_rad
            sweep = max(c.toe_m, c.heel_m) * np.abs(np.sin(yaw[:, 0] - yaw[:, 1]))
            lo_parts.append(c.min_foot_separation_m + sweep - sep)
            hi_parts.append(_FREE_TIE_M - sep)
        lo_pf, hi_pf = a.foot_bounds(it, c.foot_height_from_reference, c.trust_region_m)
        if self._s_reach is not None:
            active, normal, bound = qp_reach_rows(c, it, a, lo_pf, hi_pf)
            data[self._s_reach] = np.concatenate([normal, -normal], axis=3).ravel()
            lo_parts.append(np.full(4 * N_FEET * h, -_FREE_TIE_M))
            hi_parts.append(np.where(active[..., None], bound, _FREE_TIE_M).ravel())
        lo = np.concatenate(lo_parts)
        hi = np.concatenate(hi_parts)
        a_in = self._ineq.csc(data)

        # ---- box: foot positions (measured stance foot, eq. 24, trust region)
        lb = np.full(self.n, -np.inf)
        ub = np.full(self.n, np.inf)
        lb[self._col_pf] = lo_pf - it.p_foot
        ub[self._col_pf] = hi_pf - it.p_foot
        if c.trust_region_com_m is not None:
            lb[self._col_pc[1:]] = -c.trust_region_com_m
            ub[self._col_pc[1:]] = c.trust_region_com_m

        # ---- cost (eq. 18) + proximal term
        q = np.zeros(self.n)
        q[self._col_x[1:, :6]] = self._q_pose * a.H_ref[1:]
        q[self._col_x[1:, 6:]] = self._q_momentum * a.h_ref[1:]
        q[self._col_pc[1:]] = self._q_p_com * (it.p_com[1:] - a.p_com_ref[1:])
        q[self._col_f] = self._q_force * it.f
        q[self._col_tau] = self._q_moment * it.tau
        q[self._col_pf] = self._q_p_foot * (it.p_foot - a.p_foot_ref)
        return QPProblem(self._P, q, A_eq=a_eq, b_eq=b, A=a_in, l=lo, u=hi, lb=lb, ub=ub)

    def plan_cost(self, iterate: KDIterate, states: np.ndarray, inputs: KDInputs) -> float:
        """Eq. 18 at a plan: ``iterate`` (footholds, CoM path, wrenches) with the predicted
        ``states`` (h + 1, 12) ``[H; l_G; k_G]``, against the references of ``inputs``
        (without the proximal term, which vanishes at a converged iterate)."""
        c = self.config
        pose, momentum = states[1:, :6], states[1:, 6:]
        return float(
            np.sum(c.pose_weights * (pose - inputs.H_ref[1:]) ** 2)
            + np.sum(c.momentum_weights * (momentum - inputs.h_ref[1:]) ** 2)
            + np.sum(np.asarray(c.w_p_com) * (iterate.p_com[1:] - inputs.p_com_ref[1:]) ** 2)
            + c.w_force * np.sum(iterate.f**2)
            + c.w_moment * np.sum(iterate.tau**2)
            + np.sum(np.asarray(c.w_p_foot) * (iterate.p_foot - inputs.p_foot_ref) ** 2)
        )

    # ------------------------------------------------------------------ solve
    def condensed_qp(self, iterate: KDIterate, inputs: KDInputs) -> CondensedQP:
        """The condensed form of the QP of :meth:`build` (``qp_form="condensed"``)."""
        assert self.condensed is not None
        wrench_rows = self._wrench.stack(inputs.foot_yaw_rad)
        c = self.config
        lo, hi = inputs.foot_bounds(iterate, c.foot_height_from_reference, c.trust_region_m)
        return self.condensed.condense(iterate, inputs, wrench_rows, lo, hi)

    def _solve_condensed(
        self, iterate: KDIterate, inputs: KDInputs
    ) -> tuple[QPSolution, dict[str, np.ndarray] | None]:
        """DAQP on the condensed QP; a solution DAQP calls inaccurate is found if its
        primal residual on the sparse QP is at most 1e-3."""
        assert self.condensed is not None
        start = time.perf_counter()
        sol, parts = self.condensed.solve(self.condensed_qp(iterate, inputs))
        if parts is not None:
            sol.x = self.layout.pack(parts)
            if sol.status == "solved_inaccurate":
                sol.problem = self.build(iterate, inputs)
                residual = sol.primal_residual
                sol.found = residual is not None and residual <= 1e-3
        sol.solve_time_s = time.perf_counter() - start
        return sol, parts

    def solve(self, iterate: KDIterate, inputs: KDInputs) -> KDStep:
        """Solve the CMPC QP (condensed with ``qp_form="condensed"``, else or where DAQP
        fails the sparse QP of :meth:`build`); return the search directions.

        Raises:
            QPSolveError: the backend found no usable solution.
        """
        parts = None
        if self.condensed is not None:
            sol, parts = self._solve_condensed(iterate, inputs)
            self.n_fallbacks += not sol.found  # then the sparse QP with qp_backend
        if parts is None or not sol.found:
            sol = self.workspace.solve_or_raise(self.build(iterate, inputs))
            assert sol.x is not None  # found, so given
            parts = self.layout.unpack(sol.x)
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


__all__ = [
    "NX",
    "KDConfig",
    "KDIterate",
    "KDStep",
    "KDSubproblem",
    "KDTolerances",
    "next_touchdown_mask",
    "nonlinear_rollout",
    "nonlinear_step",
    "tie_groups",
]
