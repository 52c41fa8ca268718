"""Joint-space data shared by the explicit KD-SQP and WBD-SQP columns of Table II.

Both baselines keep the joint configuration in their decision variables (eqs. 1 and 7),
so each recorded :class:`~gaitnet_mpc.mpc.sequential.KDProblem` is mapped to:

* :class:`SymbolicKinematics`: CasADi functions of MuJoCo's ``(qpos, qvel)`` for the CoM
  ``p_c(q)``, the spatial momentum ``h = A_G(q) qdot`` (eq. 6; adam-robotics' centroidal
  momentum matrix, linear part ``m v_c``, angular part about the CoM, world axes), the
  foot contact points (the whole-body model's toe/heel points,
  :class:`~gaitnet_mpc.mpc.wholebody.dynamics.WholeBodyDynamics`) and the foot centres
  ``p_f(q)`` (mid toe-heel point lifted by the contact radius: the point the centroidal
  problem's ``p_f`` denotes, :attr:`KDProblem.p_foot_now_m`);
* :class:`JointSpaceProblem`: the measured state, the kd reference's joint-space
  trajectory (``q_ref``, ``v_ref`` of ``f_ref``, Algorithm 1 lines 2-3, which the
  proposed method's own references come from), the centroidal problem it extends
  (:func:`~gaitnet_mpc.mpc.cd_problem.centroidal_problem`) and the sampling-time
  variables: one ``dt`` per step of the horizon (a run of stages with the same contact
  pattern), bounded by Table VI's ``[0.045, 0.07] s``. The step in progress keeps its
  recorded stage lengths unless the problem is a step start (``choose_dt``), as in the
  proposed method (Remark 4).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitnet_mpc.dt_policy import paper_dt_bounds_s
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.kinematics.reference import make_reference
from gaitnet_mpc.mpc.cd_problem import CDProblem, centroidal_problem
from gaitnet_mpc.mpc.sequential import KDProblem, SequentialKDMPC
from gaitnet_mpc.mpc.wholebody.dynamics import WholeBodyDynamics, quat_wxyz_to_rot
from gaitnet_mpc.robots import FEET, RobotModel

#: Table VI's range of the MPC sampling time [s] (the variable-dt baselines' bounds).
DT_BOUNDS_S = paper_dt_bounds_s(planar=False)


class SymbolicKinematics:
    """CasADi kinematics of one 3-D robot on MuJoCo's ``(qpos, qvel)`` (module docstring).

    Functions: ``com(qpos) -> (3,)``; ``momentum(qpos, qvel) -> (6,)`` eq. 6;
    ``points(qpos) -> (3, n_c)`` contact points; ``feet(qpos) -> (3, 2)`` foot centres.
    """

    def __init__(self, robot: RobotModel, dynamics: WholeBodyDynamics | None = None) -> None:
        if robot.spec.planar:
            raise ConfigError("robot", robot.name, "a 3-D robot (free-flyer root)")
        from adam.casadi import KinDynComputations

        self.robot = robot
        self.dyn = dynamics or WholeBodyDynamics(robot)
        # joints in the order of ``joint_qpos_adr`` / ``joint_dof_adr``
        kd = KinDynComputations.from_mujoco_model(
            robot.mj_model, joints_name_list=list(robot.joint_names)
        )
        nq, nv = self.dyn.nq, self.dyn.nv
        qpos, qvel = ca.SX.sym("qpos", nq), ca.SX.sym("qvel", nv)
        rot = quat_wxyz_to_rot(qpos[3:7])
        base = ca.vertcat(ca.horzcat(rot, qpos[0:3]), ca.DM([[0.0, 0.0, 0.0, 1.0]]))
        joints = qpos[list(robot.joint_qpos_adr)]
        twist = ca.vertcat(qvel[0:3], rot @ qvel[3:6], qvel[list(robot.joint_dof_adr)])
        com = kd.CoM_position(base, joints)
        momentum = kd.centroidal_momentum_matrix(base, joints) @ twist
        pts, _ = self.dyn.contact_kinematics(qpos, ca.SX.zeros(nv))
        lift = ca.DM([0.0, 0.0, robot.spec.foot_contact_radius_m])
        centres = []
        for foot in FEET:
            idx = self.dyn.contact_points_of(foot)
            centres.append(sum(pts[:, i] for i in idx) / len(idx) + lift)
        opts = {"cse": True}
        self.com = ca.Function("com", [qpos], [com], opts)
        self.momentum = ca.Function("momentum", [qpos, qvel], [momentum], opts)
        self.points = ca.Function("points", [qpos], [pts], opts)
        self.feet = ca.Function("feet", [qpos], [ca.horzcat(*centres)], opts)


@dataclass(frozen=True)
class JointSpaceProblem:
    """One recorded problem in joint space (module docstring).

    Attributes:
        cd: the centroidal problem (references, wrench rows, foot boxes, ``u^0``).
        qpos0, qvel0: (nq,), (nv,) measured state, MuJoCo convention.
        qpos_ref, qvel_ref: (h, nq), (h, nv) kd reference of nodes ``1 .. h``.
        dt_select: (h, n_dt) 1 where stage ``k`` lasts the ``j``-th dt variable.
        dt_guess_s: (n_dt,) recorded sampling time of each dt variable [s]; a column of
            ``dt_select`` that is all zero marks an unused variable (fixed to its guess).
        dt_fixed_s: (h,) recorded stage lengths, used where no dt variable applies [s].
        foot_yaw_rad: (h, 2) foot headings (the wrench rows' frame).
    """

    cd: CDProblem
    qpos0: np.ndarray
    qvel0: np.ndarray
    qpos_ref: np.ndarray
    qvel_ref: np.ndarray
    dt_select: np.ndarray
    dt_guess_s: np.ndarray
    dt_fixed_s: np.ndarray
    foot_yaw_rad: np.ndarray

    @property
    def horizon(self) -> int:
        return self.cd.horizon

    @property
    def n_dt_used(self) -> int:
        """dt variables that some stage uses."""
        return int(np.count_nonzero(self.dt_select.any(axis=0)))

    def dts_s(self, dt_vars_s: np.ndarray) -> np.ndarray:
        """(h,) stage lengths [s] for dt variable values ``dt_vars_s``."""
        used = self.dt_select.sum(axis=1)
        return self.dt_select @ dt_vars_s + (1.0 - used) * self.dt_fixed_s


def max_dt_variables(horizon: int, stages_per_step: int) -> int:
    """Most steps a horizon of ``horizon`` stages can touch: a partial step, full steps
    and a partial last step."""
    return -(-(horizon - 1) // stages_per_step) + 1


def joint_space_problem(
    solver: SequentialKDMPC,
    problem: KDProblem,
    n_dt: int,
    cd: CDProblem | None = None,
) -> JointSpaceProblem:
    """Map ``problem`` to joint space with ``n_dt`` dt variable slots (module docstring).

    Raises:
        ConfigError: the horizon touches more steps than ``n_dt``.
    """
    robot = solver.robot
    cd = cd if cd is not None else centroidal_problem(solver, problem)
    h = cd.horizon
    ref = make_reference(
        robot,
        problem.q,
        problem.timing,
        problem.command,
        problem.footholds_m,
        p_foot_now_m=problem.p_foot_now_m,
        p_liftoff_m=problem.p_liftoff_m,
        p_com_start_m=problem.p_com_start_m,
        workspace=solver.ref_workspace,
    )
    qpos0, qvel0 = robot.pin_to_mj(problem.q, problem.v)
    refs = [robot.pin_to_mj(q, v) for q, v in zip(ref.q_ref[1:], ref.v_ref[1:], strict=True)]
    qpos_ref = np.array([r[0] for r in refs])
    qvel_ref = np.array([r[1] for r in refs])
    # steps: runs of stages with one contact pattern
    change = np.any(cd.contact[1:] != cd.contact[:-1], axis=1)
    step_of = np.concatenate([[0], np.cumsum(change)])
    if step_of[-1] + 1 > n_dt:
        raise ConfigError("n_dt", n_dt, f">= {step_of[-1] + 1} steps in the horizon")
    select = np.zeros((h, n_dt))
    guess = np.full(n_dt, float(np.clip(cd.dts_s[-1], *DT_BOUNDS_S)))
    for k in range(h):
        j = int(step_of[k])
        if j == 0 and not problem.choose_dt:
            continue
        select[k, j] = 1.0
        guess[j] = float(np.clip(cd.dts_s[k], *DT_BOUNDS_S))
    return JointSpaceProblem(
        cd=cd,
        qpos0=qpos0,
        qvel0=qvel0,
        qpos_ref=qpos_ref,
        qvel_ref=qvel_ref,
        dt_select=select,
        dt_guess_s=guess,
        dt_fixed_s=cd.dts_s.copy(),
        foot_yaw_rad=np.asarray(problem.foot_yaw_rad, dtype=float).copy(),
    )


__all__ = [
    "DT_BOUNDS_S",
    "JointSpaceProblem",
    "SymbolicKinematics",
    "joint_space_problem",
    "max_dt_variables",
]
