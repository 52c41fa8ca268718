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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gaitnet_mpc.control.contact import ContactParams, foot_wrench_constraints
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp import QPProblem, QPSolution, make_workspace
from gaitnet_mpc.robots import FEET

NX = 13  # [Theta (3), p (3), omega (3), v (3), 1]
NU_FOOT = 6
NU = 2 * NU_FOOT
GRAVITY_MPS2 = 9.81


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix: ``skew(a) @ b == np.cross(a, b)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclass(frozen=True)
class SRBMConfig:
    """Weights and limits of the SRBM MPC (units per field)."""

    horizon: int = 10
    w_rpy: tuple[float, float, float] = (300.0, 300.0, 100.0)
    w_pos_m: tuple[float, float, float] = (50.0, 50.0, 500.0)
    w_omega: tuple[float, float, float] = (1.0, 1.0, 1.0)
    w_vel: tuple[float, float, float] = (20.0, 20.0, 10.0)
    w_force: float = 1e-4  # paper Table VIII, L^f
    w_moment: float = 1e-3  # paper Table VIII, L^tau
    contact: ContactParams = field(default_factory=ContactParams)
    qp_backend: str = "daqp"

    def __post_init__(self) -> None:
        if self.horizon < 1:
            raise ConfigError("horizon", self.horizon, "an integer >= 1")


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
        c = self.config
        diag = np.concatenate([c.w_rpy, c.w_pos_m, c.w_omega, c.w_vel, [0.0]])
        self._q_diag = np.tile(diag, c.horizon)
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

    # ---------------------------------------------------------------- solve
    def build(
        self,
        x0: np.ndarray,
        x_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        feet_pos_m: np.ndarray,
        feet_yaw_rad: np.ndarray,
        torque_limits: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> tuple[QPProblem, np.ndarray, np.ndarray]:
        """The condensed QP over U (h*12,); also returns (Sx x0, Su) for predictions.

        Args:
            x0: (13,) measured state.
            x_ref: (h + 1, 13) reference states; x_ref[0] is unused by the cost.
            dts_s: (h,) per-stage sampling time [s].
            contact: (h, 2) stance mask (left, right).
            feet_pos_m: (h, 2, 3) foot centre per stage and foot (stance: where it stands;
                swing: ignored).
            feet_yaw_rad: (h, 2) foot heading per stage.
            torque_limits: optional ``(foot_index, stage_mask (h,), J_T (n_leg, 6),
                tau_max (n_leg,))``: joint-torque limits ``|J_T [f; m]| <= tau_max`` of
                the stance leg (``tau = -J_c^T [f; m]``), on the stages of ``stage_mask``.
        """
        h = self.config.horizon
        sx, su = self.condense(x0, x_ref[:h], dts_s, feet_pos_m)
        free = sx @ x0
        err0 = free - x_ref[1 : h + 1].reshape(-1)
        q_su = su * self._q_diag[:, None]
        hess = su.T @ q_su + np.diag(self._r_diag)
        grad = q_su.T @ err0
        rows, lo, hi = [], [], []
        for k in range(h):
            for i in range(2):
                cm, l_, u_ = foot_wrench_constraints(
                    float(feet_yaw_rad[k, i]),
                    self.config.contact,
                    self.toe_m,
                    self.heel_m,
                    in_stance=bool(contact[k, i]),
                )
                row = np.zeros((cm.shape[0], h * NU))
                col = NU * k + NU_FOOT * i
                row[:, col : col + NU_FOOT] = cm
                rows.append(row)
                lo.append(l_)
                hi.append(u_)
        if torque_limits is not None:
            i, mask, j_t, tau_max = torque_limits
            for k in np.flatnonzero(mask):
                row = np.zeros((j_t.shape[0], h * NU))
                col = NU * k + NU_FOOT * i
                row[:, col : col + NU_FOOT] = j_t
                rows.append(row)
                lo.append(-tau_max)
                hi.append(tau_max)
        problem = QPProblem(
            0.5 * (hess + hess.T),
            grad,
            A=np.vstack(rows),
            l=np.concatenate(lo),
            u=np.concatenate(hi),
        )
        return problem, free, su

    def solve(
        self,
        x0: np.ndarray,
        x_ref: np.ndarray,
        dts_s: np.ndarray,
        contact: np.ndarray,
        feet_pos_m: np.ndarray,
        feet_yaw_rad: np.ndarray,
        torque_limits: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> SRBMPlan:
        """Solve one MPC problem; raises :class:`QPSolveError` if the QP fails."""
        problem, free, su = self.build(
            x0, x_ref, dts_s, contact, feet_pos_m, feet_yaw_rad, torque_limits
        )
        sol = self.workspace.solve_or_raise(problem, warm_start=self._last_u)
        self._last_u = sol.x
        h = self.config.horizon
        states = np.vstack([x0, (free + su @ sol.x).reshape(h, NX)])
        return SRBMPlan(wrenches=sol.x.reshape(h, 2, NU_FOOT), states=states, solution=sol)

    def reset(self) -> None:
        self._last_u = None
        self.workspace.reset()


__all__ = ["FEET", "NU", "NX", "SRBMMPC", "SRBMConfig", "SRBMPlan"]
