"""Single-rigid-body-model (SRBM) convex MPC with per-foot contact force and moment.

The paper's hardware baseline (Fig. 10; Di Carlo et al. 2018, its ref. [8]), extended to
line feet. State (13): roll-pitch-yaw Theta, CoM position p, world angular velocity omega,
CoM velocity v, and a constant 1 that carries gravity. Inputs (12): ground force and moment
[f; m] of the left and right foot (world-aligned, about the foot centre).

Continuous dynamics, linearised about zero roll and pitch:

    Theta_dot = R_z(psi)^T omega,   p_dot = v,
    omega_dot = I_w^-1 sum_i ((p_f,i - p) x f_i + m_i),   v_dot = sum_i f_i / m + g .

Each stage k has its own sampling time dt_k (a step lasts h' = 5 stages of that step's dt),
so each stage has its own A_k = I + A_c dt_k and B_k = B_c,k dt_k; the condensed matrices
are built from the true time-varying products A_{k-1} ... A_j, never from powers of one A.

The QP is posed over reduced wrench variables (``SRBMMPC._foot_block``): a swinging foot
has none (its wrench is zero), a line foot's moment is spanned by its lateral axis and
the vertical (no moment about the foot axis), a point foot has forces only. With no double
support this is 5 instead of 12 variables per stage and drops all equality rows, which
more than halves the solve time. Dense products use ``einsum`` rather than BLAS, whose
thread pool can stall for tens of milliseconds on a loaded machine.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gaitnet_mpc.config import bounded, check_ranges, weight
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import GRAVITY_MPS2, skew
from gaitnet_mpc.mpc.contact import ContactParams, foot_wrench_constraints
from gaitnet_mpc.mpc.qp import BACKENDS, QPProblem, QPSolution, make_workspace
from gaitnet_mpc.robots import FEET

NX = 13  # [Theta (3), p (3), omega (3), v (3), 1]
NU_FOOT = 6
NU = 2 * NU_FOOT

#: ``(foot_index, stage_mask (h,), J_T (n_leg, 6), tau_max (n_leg,))``, see SRBMMPC.build.
TorqueLimits = tuple[int, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class SRBMConfig:
    """Weights and limits of the SRBM MPC (units per field)."""

    horizon: int = bounded(10, "[1, 100]", "an integer", "stages; two steps of h' = 5")
    w_rpy: tuple[float, float, float] = weight((300.0, 300.0, 100.0))
    # CoM position and velocity weights are (forward, lateral, vertical) in the heading
    # frame of each stage (the reference yaw). The lateral ones are small on purpose: a
    # line foot cannot exert a moment about its long axis, so the MPC can only change the
    # lateral CoM velocity by rolling the trunk (hip strategy). Tracking vy = 0 strongly
    # fights the natural step-to-step sway and leaves a lean of ~0.025 rad with a steady
    # sideways drift of ~0.06 m/s; the lateral CoM is governed by the footholds instead.
    w_pos_m: tuple[float, float, float] = weight((50.0, 1.0, 500.0))
    w_omega: tuple[float, float, float] = weight((1.0, 1.0, 1.0))
    w_vel: tuple[float, float, float] = weight((20.0, 0.5, 10.0))
    w_force: float = weight(1e-4)  # paper Table VIII, L^f
    w_moment: float = weight(1e-3)  # paper Table VIII, L^tau
    # Regularise the wrench about the gravity-compensating one (m g shared by the stance
    # feet of a stage) instead of about zero. Penalising |f|^2 itself pulls the planned
    # vertical force below m g, which the receding horizon turns into a steady sag of the
    # CoM (about 3 cm with the weights above) and a matching lean.
    regularize_about_weight: bool = True
    contact: ContactParams = field(default_factory=ContactParams)
    qp_backend: str = "daqp"

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.qp_backend not in BACKENDS:
            raise ConfigError("qp_backend", self.qp_backend, f"one of {sorted(BACKENDS)}")


@dataclass(frozen=True)
class SRBMPlan:
    """Result of one SRBM MPC solve."""

    wrenches: np.ndarray  # (h, 2, 6) ground wrench per stage and foot [N; N m]
    states: np.ndarray  # (h + 1, 13) predicted states, states[0] = x0
    solution: QPSolution


class SRBMMPC:
    """Builds and solves the condensed SRBM QP; keeps a warm-started QP workspace."""

    def __init__(
        self,
        mass_kg: float,
        inertia_body_kg_m2: np.ndarray,
        toe_m: float,
        heel_m: float,
        config: SRBMConfig | None = None,
    ) -> None:
        self.config = config or SRBMConfig()
        self.mass_kg = float(mass_kg)
        self.inertia_body = np.asarray(inertia_body_kg_m2, dtype=float).reshape(3, 3)
        self.toe_m, self.heel_m = toe_m, heel_m
        self.workspace = make_workspace(self.config.qp_backend)
        self._last_u: np.ndarray | None = None
        self._block_cache: dict[tuple[float, bool], tuple] = {}
        c = self.config
        self._q_stage = np.diag(np.concatenate([c.w_rpy, c.w_pos_m, c.w_omega, c.w_vel, [0.0]]))
        r_foot = [c.w_force] * 3 + [c.w_moment] * 3
        self._r_diag = np.tile(r_foot * 2, c.horizon)

    # ---------------------------------------------------------------- model
    def stage_matrices(
        self, x_lin: np.ndarray, feet_pos_m: np.ndarray, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Discrete A_k (13, 13) and B_k (13, 12) for one stage of length ``dt_s``.

        ``x_lin`` is the reference state of the stage (yaw and CoM position used for the
        rotation and the lever arms); ``feet_pos_m`` (2, 3) the foot centres.
        """
        yaw = x_lin[2]
        c, s = np.cos(yaw), np.sin(yaw)
        rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        a_c = np.zeros((NX, NX))
        a_c[0:3, 6:9] = rz.T
        a_c[3:6, 9:12] = np.eye(3)
        a_c[11, 12] = -GRAVITY_MPS2
        inertia_world = rz @ self.inertia_body @ rz.T
        inv_i = np.linalg.inv(inertia_world)
        b_c = np.zeros((NX, NU))
        for i in range(2):
            r = feet_pos_m[i] - x_lin[3:6]
            cols = slice(NU_FOOT * i, NU_FOOT * i + NU_FOOT)
            b_c[6:9, cols] = inv_i @ np.hstack([skew(r), np.eye(3)])
            b_c[9:12, NU_FOOT * i : NU_FOOT * i + 3] = np.eye(3) / self.mass_kg
        return np.eye(NX) + a_c * dt_s, b_c * dt_s

    def condense(
        self, x0: np.ndarray, x_ref: np.ndarray, dts_s: np.ndarray, feet_pos_m: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Prediction X = Sx x0 + Su U over the horizon with time-varying (A_k, B_k).

        Returns Sx (h*13, 13) and Su (h*13, h*12); row block k is state x_{k+1}.
        """
        h = self.config.horizon
        sx = np.zeros((h * NX, NX))
        su = np.zeros((h * NX, h * NU))
        phi = np.eye(NX)
        prev_rows = None
        for k in range(h):
            a_k, b_k = self.stage_matrices(x_ref[k], feet_pos_m[k], float(dts_s[k]))
            rows = slice(NX * k, NX * k + NX)
            phi = a_k @ phi
            sx[rows] = phi
            if prev_rows is not None:
                su[rows, : NU * k] = a_k @ su[prev_rows, : NU * k]
            su[rows, NU * k : NU * k + NU] = b_k
            prev_rows = rows
        return sx, su

    def stage_weight(self, yaw_rad: float) -> np.ndarray:
        """State weight (13, 13) of one stage: the horizontal CoM position and velocity
        weights rotated from the heading frame at ``yaw_rad`` to the world."""
        c, s = np.cos(yaw_rad), np.sin(yaw_rad)
        rot = np.array([[c, -s], [s, c]])
        q = self._q_stage.copy()
        for i in (3, 9):  # position, velocity
            q[i : i + 2, i : i + 2] = rot @ q[i : i + 2, i : i + 2] @ rot.T
        return q

    # ---------------------------------------------------------------- solve
    def _foot_block(
        self, yaw_rad: float, in_stance: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Reduced wrench variables of one foot in one stage.

        Returns ``(E, C, l, u)``: the wrench is ``[f; m] = E z`` with ``z`` the reduced
        variables (``E`` (6, n_z) with orthonormal columns) and the contact constraints
        ``l <= C z <= u``.  A swinging foot has no variables at all (eq. 23 with sigma = 0
        forces its wrench to zero, so carrying six variables pinned to zero only enlarges
        the QP); a line foot cannot carry a moment about its long axis, so its moment is
        spanned by the foot's lateral axis and the vertical (5 variables); a point foot
        carries forces only (3 variables).
        """
        key = (round(float(yaw_rad), 9), bool(in_stance))
        cached = self._block_cache.get(key)
        if cached is not None:
            return cached
        if not in_stance:
            out = (np.zeros((NU_FOOT, 0)), np.zeros((0, 0)), np.zeros(0), np.zeros(0))
        else:
            c, s = np.cos(yaw_rad), np.sin(yaw_rad)
            cols = [np.eye(NU_FOOT)[:, j] for j in range(3)]
            if self.toe_m != 0.0 or self.heel_m != 0.0:
                cols.append(np.array([0.0, 0.0, 0.0, -s, c, 0.0]))  # moment about lateral
                cols.append(np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]))  # yaw moment
            e = np.stack(cols, axis=1)
            cm, lo, hi = foot_wrench_constraints(
                float(yaw_rad), self.config.contact, self.toe_m, self.heel_m, in_stance=True
            )
            cz = cm @ e
            keep = np.any(np.abs(cz) > 1e-12, axis=1)  # drop rows the basis satisfies
            out = (e, cz[keep], lo[keep], hi[keep])
        if len(self._block_cache) > 64:
            self._block_cache.clear()
        self._block_cache[key] = out
        return out

    def build(
        self,
        x0: np.ndarray,
        x_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        feet_pos_m: np.ndarray,
        feet_yaw_rad: np.ndarray,
        torque_limits: TorqueLimits | list[TorqueLimits] | None = None,
    ) -> tuple[QPProblem, np.ndarray, np.ndarray, np.ndarray]:
        """The condensed QP over the reduced wrench variables Z; U = T Z (h*12,).

        Args:
            x0: (13,) measured state.
            x_ref: (h + 1, 13) reference states; x_ref[0] is unused by the cost.
            dts_s: (h,) per-stage sampling time [s].
            contact: (h, 2) stance mask (left, right).
            feet_pos_m: (h, 2, 3) foot centre per stage and foot (stance: where it stands;
                swing: ignored).
            feet_yaw_rad: (h, 2) foot heading per stage.
            torque_limits: optional ``(foot_index, stage_mask (h,), J_T (n_leg, 6),
                tau_max (n_leg,))``, or a list of them (one per stance leg): joint-torque
                limits ``|J_T [f; m]| <= tau_max`` of a stance leg (``tau = -J_c^T [f; m]``),
                on the stages of ``stage_mask`` where that foot stands.

        Returns:
            ``(problem, Sx x0, Su, T)``: the QP in Z, the free response (h*13,), the full
            input-to-state map (h*13, h*12) and the basis T (h*12, n_z) with U = T Z.
        """
        h = self.config.horizon
        sx, su = self.condense(x0, x_ref[:h], dts_s, feet_pos_m)
        free = sx @ x0
        err0 = free - x_ref[1 : h + 1].reshape(-1)
        blocks = []
        n_z = 0
        for k in range(h):
            for i in range(2):
                blk = self._foot_block(float(feet_yaw_rad[k, i]), bool(contact[k, i]))
                blocks.append((k, i, n_z, blk))
                n_z += blk[0].shape[1]
        basis = np.zeros((h * NU, n_z))
        su_z = np.empty((h * NX, n_z))  # Su T, built block by block (T is block-diagonal)
        for k, i, z0, (e, _, _, _) in blocks:
            col = NU * k + NU_FOOT * i
            basis[col : col + NU_FOOT, z0 : z0 + e.shape[1]] = e
            su_z[:, z0 : z0 + e.shape[1]] = su[:, col : col + NU_FOOT] @ e
        q_su = np.empty_like(su_z)  # Q Su T, Q block-diagonal with one block per stage
        for k in range(h):
            stage_rows = slice(NX * k, NX * k + NX)
            q_su[stage_rows] = self.stage_weight(float(x_ref[k + 1, 2])) @ su_z[stage_rows]
        # einsum instead of BLAS: on a loaded machine a multi-threaded BLAS call on these
        # small matrices can stall for tens of milliseconds.
        hess = np.einsum("ki,kj->ij", su_z, q_su, optimize=False)
        r_basis = basis * self._r_diag[:, None]  # R T
        hess += np.einsum("ki,kj->ij", basis, r_basis, optimize=False)
        grad = q_su.T @ err0
        if self.config.regularize_about_weight:
            u_ref = np.zeros(h * NU)  # nominal wrench: m g shared by the stance feet
            n_stance = np.maximum(np.asarray(contact, dtype=bool).sum(axis=1), 1)
            for k in range(h):
                for i in range(2):
                    if contact[k, i]:
                        u_ref[NU * k + NU_FOOT * i + 2] = self.mass_kg * GRAVITY_MPS2 / n_stance[k]
            grad -= r_basis.T @ u_ref
        rows: list[np.ndarray] = []
        lo: list[np.ndarray] = []
        hi: list[np.ndarray] = []
        for _, _, z0, (e, cz, l_, u_) in blocks:
            if cz.shape[0] == 0:
                continue
            row = np.zeros((cz.shape[0], n_z))
            row[:, z0 : z0 + e.shape[1]] = cz
            rows.append(row)
            lo.append(l_)
            hi.append(u_)
        if torque_limits is None:
            limits = []
        elif isinstance(torque_limits, tuple):
            limits = [torque_limits]
        else:
            limits = list(torque_limits)
        for i, mask, j_t, tau_max in limits:
            for stage in np.flatnonzero(mask):
                row = j_t @ basis[NU * stage + NU_FOOT * i : NU * stage + NU_FOOT * (i + 1)]
                if not np.any(row):
                    continue  # the foot swings in this stage
                rows.append(row)
                lo.append(-tau_max)
                hi.append(tau_max)
        problem = QPProblem(
            0.5 * (hess + hess.T),
            grad,
            A=np.vstack(rows) if rows else None,
            l=np.concatenate(lo) if lo else None,
            u=np.concatenate(hi) if hi else None,
        )
        return problem, free, su, basis

    def solve(
        self,
        x0: np.ndarray,
        x_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        feet_pos_m: np.ndarray,
        feet_yaw_rad: np.ndarray,
        torque_limits: TorqueLimits | list[TorqueLimits] | None = None,
    ) -> SRBMPlan:
        """Solve one MPC problem; raises :class:`QPSolveError` if the QP fails."""
        problem, free, su, basis = self.build(
            x0, x_ref, dts_s, contact, feet_pos_m, feet_yaw_rad, torque_limits
        )
        # Warm start: the previous wrenches projected on this solve's basis (T has
        # orthonormal columns, so T^T U is the least-squares Z).
        warm = None if self._last_u is None else basis.T @ self._last_u
        sol = self.workspace.solve_or_raise(problem, warm_start=warm)
        u = basis @ sol.x
        self._last_u = u
        h = self.config.horizon
        states = np.vstack([x0, (free + su @ u).reshape(h, NX)])
        return SRBMPlan(wrenches=u.reshape(h, 2, NU_FOOT), states=states, solution=sol)

    def reset(self) -> None:
        self._last_u = None
        self.workspace.reset()


__all__ = ["FEET", "GRAVITY_MPS2", "NU", "NX", "SRBMMPC", "SRBMConfig", "SRBMPlan", "TorqueLimits"]
