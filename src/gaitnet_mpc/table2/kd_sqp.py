"""Explicit KD-SQP: the explicit kino-dynamic MPC of Sec. III-B (eqs. 5-9) by ``sqpmethod``.

Decision variables (eq. 7, with dt added as the paper's Table II baselines do), per stage
``k = 0 .. h-1`` and then one sampling time per step of the horizon
(:mod:`~gaitnet_mpc.table2.joint_space`)::

    w_k = [q_k+1 (nq = 25, MuJoCo qpos), qdot_k+1 (nv = 24), H_ang,k+1 (3),
           f (2x3), tau (2x3)],  dt_j

so ``n = (nq + nv + 15) h + n_dt = 64 h + n_dt`` (paper: ``60 h`` with a 24-coordinate
``q`` and no angular pose); ``q_0, qdot_0`` are the measurement. The centroidal
quantities are functions of the joint state (kinematic consistency): ``p_c = p_c(q)``,
``h = A_G(q) qdot`` (eq. 6), the foot centres ``p_f,i = p_f,i(q)``. The angular pose
``H_ang`` of eq. 18's cost integrates ``k_G`` as in the centroidal problem; it is a
variable with its own dynamics row, since as a running sum of every earlier node's
momentum it made the exact Hessian dense (179k of 374k entries, a 150 s build).

Dynamics (eq. 9a, the discrete eqs. 5-6, explicit Euler on the momentum as the centroidal
problem's eq. 20, semi-implicit on the configuration as the whole-body model's eq. 3a)::

    h(q_k+1, qdot_k+1) = h(q_k, qdot_k) + dt_k [sum_i f_i + m g;
                                                sum_i (p_f,i(q_k) - p_c(q_k)) x f_i + tau_i]
    q_k+1 = q_k (+) dt_k qdot_k+1
    H_ang,k+1 = H_ang,k + dt_k k_G(q_k, qdot_k)

Constraints (9b-9c): the centroidal problem's wrench rows (eqs. 21-23, swing wrench zero),
joint limits, and for each foot at node ``k >= 1``: at a touchdown (swing in ``k-1``,
stance in ``k``) its centre in the eq. 24 box (height included), toe and heel level and the
toe-heel axis along the foot heading; while it stands (stance in ``k-1`` and ``k``) its toe
and heel do not move; at a touchdown the lateral foot separation row of the ``kd``
controller.

Cost (eq. 8): the centroidal problem's eq. 18 terms on ``p_c(q), h(q, qdot), H`` (``R_1``,
plus the wrench and foot-position terms; a swing stage's foot term acts on the foot's
next touchdown, the point the centroidal problem's tied ``p_f`` stands for) and a state
term ``R_2`` towards the kd reference ``q_ref, qdot_ref`` (joint posture, trunk
orientation, velocities: :class:`KDSQPConfig`), without which joint motions that leave
the momentum unchanged (the arms) are not determined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.cd_problem import CDSolution, cd_cost
from gaitnet_mpc.mpc.wholebody.dynamics import quat_mul
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.table2.joint_space import (
    DT_BOUNDS_S,
    JointSpaceProblem,
    SymbolicKinematics,
)
from gaitnet_mpc.table2.sqp_common import (
    SQPConfig,
    build_sqp,
    objective_and_violation,
    run_sqp,
)

#: Step-test groups: CoM and foot centres [m], forces [N], moments [N m], dt [s].
GROUPS = ("position", "force", "moment", "dt")


@dataclass(frozen=True)
class KDSQPConfig:
    """Settings of explicit KD-SQP.

    Attributes:
        sqp: the shared ``sqpmethod`` settings.
        w_q_joint: ``R_2`` weight of the joint posture error [1/rad^2].
        w_rot_base: ``R_2`` weight of the trunk orientation error [1/rad^2].
        w_v: ``R_2`` weight of every velocity error (trunk and joints).
    """

    sqp: SQPConfig = field(default_factory=SQPConfig)
    w_q_joint: float = 1.0
    w_rot_base: float = 10.0
    w_v: float = 1e-2

    def __post_init__(self) -> None:
        for name in ("w_q_joint", "w_rot_base", "w_v"):
            if not getattr(self, name) >= 0.0:
                raise ConfigError(name, getattr(self, name), "a weight >= 0")


@dataclass(frozen=True)
class JointSQPResult:
    """Outcome of one joint-space SQP solve (explicit KD-SQP or WBD-SQP).

    Attributes:
        qpos, qvel: (h+1, nq), (h+1, nv) planned states (row 0 the measurement).
        dts_s: (h,) planned stage lengths [s].
        n_qps, converged, solve_time_s, status: as :class:`~.sqp_common.SQPRun`.
        objective: the method's own cost at the plan.
        violation: largest violation of the NLP's constraints and bounds at the plan.
        plan: the plan in the centroidal problem's terms (for eq. 18 scoring), or None.
        eq18_cost: eq. 18 at ``plan`` on the centroidal problem (NaN without one).
    """

    qpos: np.ndarray
    qvel: np.ndarray
    dts_s: np.ndarray
    n_qps: int
    converged: bool
    solve_time_s: float
    status: str
    objective: float
    violation: float
    plan: CDSolution | None
    eq18_cost: float


def rotation_error(q_wxyz: Any, q_ref_wxyz: Any) -> Any:
    """Small-angle rotation error ``2 vec(q_ref^-1 q)`` [rad] (eq. 2's orientation term)."""
    conj = ca.vertcat(q_ref_wxyz[0], -q_ref_wxyz[1:4])
    return 2 * quat_mul(conj, q_wxyz)[1:4]


def foot_events(contact: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(touchdown, standing): (h, 2) bool per node ``k`` (row 0 unused): swing in ``k-1``
    and stance in ``k``; stance in ``k-1`` and ``k``."""
    prev = np.vstack([contact[:1], contact[:-1]])
    touchdown = contact & ~prev
    standing = contact & prev
    touchdown[0], standing[0] = False, False
    return touchdown, standing


def next_touchdown(contact: np.ndarray) -> np.ndarray:
    """(h, 2) int: for a swing stage, the node of the foot's next touchdown (-1: none)."""
    touchdown, _ = foot_events(contact)
    h = contact.shape[0]
    out = np.full(contact.shape, -1)
    for i in range(contact.shape[1]):
        nxt = -1
        for k in range(h - 1, -1, -1):
            if touchdown[k, i]:
                nxt = k
            out[k, i] = -1 if contact[k, i] else nxt
    return out


class ExplicitKDSQP:
    """Explicit kino-dynamic MPC by ``sqpmethod`` (module docstring); one NLP per
    contact pattern and dt layout."""

    def __init__(self, kinematics: SymbolicKinematics, config: KDSQPConfig | None = None):
        self.kin = kinematics
        self.config = config or KDSQPConfig()
        self.nq, self.nv = kinematics.dyn.nq, kinematics.dyn.nv
        self.nw = self.nq + self.nv + 15
        self._cache: dict[tuple[Any, ...], dict[str, Any]] = {}

    def n_variables(self, horizon: int, n_dt: int) -> int:
        """``(nq + nv + 15) h + n_dt`` (module docstring)."""
        return self.nw * horizon + n_dt

    @staticmethod
    def _key(p: JointSpaceProblem) -> tuple[Any, ...]:
        return (
            p.cd.contact.tobytes(),
            p.dt_select.tobytes(),
            p.cd.wrench_c.shape,
            p.cd.sep_axis is not None,
        )

    # ------------------------------------------------------------------ transcription
    def _build(self, p: JointSpaceProblem) -> dict[str, Any]:
        key = self._key(p)
        if key in self._cache:
            return self._cache[key]
        kin, cfg, c = self.kin, self.config, p.cd.config
        nq, nv, nw = self.nq, self.nv, self.nw
        h, mw = p.horizon, p.cd.wrench_c.shape[2]
        used = np.flatnonzero(p.dt_select.any(axis=0))
        n_dt = used.size
        m, sep = c.mass_kg, p.cd.sep_axis is not None
        w = ca.SX.sym("w", nw * h + n_dt)
        dt_vars = w[nw * h :]
        par = {
            "qpos0": ca.SX.sym("qpos0", nq),
            "qvel0": ca.SX.sym("qvel0", nv),
            "H_ang0": ca.SX.sym("H_ang0", 3),
            "dt_fixed": ca.SX.sym("dt_fixed", h),
            "cw": ca.SX.sym("cw", h * 2 * mw * 6),
            "h_ref": ca.SX.sym("h_ref", h * 6),
            "H_ref": ca.SX.sym("H_ref", h * 6),
            "pc_ref": ca.SX.sym("pc_ref", h * 3),
            "pf_ref": ca.SX.sym("pf_ref", h * 6),
            "yaw": ca.SX.sym("yaw", h * 2),
            "qpos_ref": ca.SX.sym("qpos_ref", h * nq),
            "qvel_ref": ca.SX.sym("qvel_ref", h * nv),
            "axis": ca.SX.sym("axis", h * 2 if sep else 0),
        }
        params = ca.vertcat(*par.values())
        g_vec = ca.DM([0.0, 0.0, -c.gravity_mps2])
        wp, wm = c.pose_weights, c.momentum_weights
        wpc, wpf = np.asarray(c.w_p_com), np.asarray(c.w_p_foot)
        contact = p.cd.contact
        touchdown, standing = foot_events(contact)
        nxt = next_touchdown(contact)
        j0 = nq - kin.dyn.n_joints
        qs = [par["qpos0"]] + [w[nw * k : nw * k + nq] for k in range(h)]
        vs = [par["qvel0"]] + [w[nw * k + nq : nw * k + nq + nv] for k in range(h)]
        pts = [kin.points(q) for q in qs]
        feet = [kin.feet(q) for q in qs]
        rows: list[tuple[Any, np.ndarray, np.ndarray, str]] = []

        def add(expr: Any, lo: Any, hi: Any, tag: str) -> None:
            n = expr.shape[0]
            rows.append((expr, np.full(n, lo, float), np.full(n, hi, float), tag))

        cost = ca.SX(0.0)
        mom = kin.momentum(qs[0], vs[0])
        has = [par["H_ang0"]] + [w[nw * k + nq + nv : nw * k + nq + nv + 3] for k in range(h)]
        for k in range(h):
            base = nw * k + nq + nv + 3
            f, tau = w[base : base + 6], w[base + 6 : base + 12]
            sel = [j for j in range(n_dt) if p.dt_select[k, used[j]] > 0.0]
            dt = dt_vars[sel[0]] if sel else par["dt_fixed"][k]
            pc = kin.com(qs[k])
            torque = ca.SX.zeros(3)
            for i in range(2):
                fi, ti = f[3 * i : 3 * i + 3], tau[3 * i : 3 * i + 3]
                torque += ca.cross(feet[k][:, i] - pc, fi) + ti
                if contact[k, i]:
                    blk = par["cw"][(k * 2 + i) * mw * 6 : (k * 2 + i + 1) * mw * 6]
                    rows_ci = ca.reshape(blk, 6, mw).T
                    add(ca.mtimes(rows_ci, ca.vertcat(fi, ti)), np.nan, np.nan, f"wrench{k}{i}")
            mom_next = kin.momentum(qs[k + 1], vs[k + 1])
            pred = mom + dt * ca.vertcat(f[:3] + f[3:] + m * g_vec, torque)
            add(mom_next - pred, 0.0, 0.0, "momentum")
            q_int, _ = kin.dyn.step(qs[k], vs[k + 1], ca.SX.zeros(nv), dt)
            add(qs[k + 1] - q_int, 0.0, 0.0, "integration")
            add(has[k + 1] - has[k] - mom[3:] * dt, 0.0, 0.0, "pose")
            pose_ang = has[k + 1]
            # eq. 8 / eq. 18 terms of node k+1
            pc1 = kin.com(qs[k + 1])
            e_pose = ca.vertcat(m * pc1, pose_ang) - par["H_ref"][6 * k : 6 * k + 6]
            e_mom = mom_next - par["h_ref"][6 * k : 6 * k + 6]
            e_pc = pc1 - par["pc_ref"][3 * k : 3 * k + 3]
            cost += ca.dot(wp * e_pose, e_pose) + ca.dot(wm * e_mom, e_mom)
            cost += ca.dot(wpc * e_pc, e_pc)
            cost += c.w_force * ca.dot(f, f) + c.w_moment * ca.dot(tau, tau)
            for i in range(2):
                node = k if contact[k, i] else int(nxt[k, i])
                if node >= 0:
                    e_pf = feet[node][:, i] - par["pf_ref"][6 * k + 3 * i : 6 * k + 3 * i + 3]
                    cost += ca.dot(wpf * e_pf, e_pf)
            q_ref = par["qpos_ref"][nq * k : nq * (k + 1)]
            v_ref = par["qvel_ref"][nv * k : nv * (k + 1)]
            e_rot = rotation_error(qs[k + 1][3:7], q_ref[3:7])
            cost += cfg.w_q_joint * ca.sumsqr(qs[k + 1][j0:] - q_ref[j0:])
            cost += cfg.w_rot_base * ca.sumsqr(e_rot) + cfg.w_v * ca.sumsqr(vs[k + 1] - v_ref)
            mom = mom_next
        # foot rows at nodes 1 .. h-1 (node h carries no wrench)
        for k in range(1, h):
            for i, foot in enumerate(FEET):
                toe, heel = kin.dyn.contact_points_of(foot)[:2]
                if touchdown[k, i]:
                    add(feet[k][:, i], np.nan, np.nan, f"box{k}{i}")
                    add(pts[k][2, toe] - pts[k][2, heel], 0.0, 0.0, "level")
                    d = pts[k][0:2, toe] - pts[k][0:2, heel]
                    yaw = par["yaw"][2 * k + i]
                    add(d[0] * ca.sin(yaw) - d[1] * ca.cos(yaw), 0.0, 0.0, "heading")
                    if sep:
                        gap = feet[k][0:2, 0] - feet[k][0:2, 1]
                        ax = par["axis"][2 * k : 2 * k + 2]
                        add(ax[0] * gap[0] + ax[1] * gap[1], np.nan, np.inf, f"sep{k}")
                elif standing[k, i]:
                    for pt in (toe, heel):
                        add(pts[k][:, pt] - pts[k - 1][:, pt], 0.0, 0.0, "stand")
        g = ca.vertcat(*[r[0] for r in rows])
        sizes = [r[0].shape[0] for r in rows]
        # step test: CoM and foot centres of nodes 1..h, forces, moments, dt
        positions = ca.Function(
            "kd_positions",
            [w],
            [ca.vertcat(*[ca.vertcat(kin.com(q), ca.vec(kin.feet(q))) for q in qs[1:]])],
        )
        cols = nw * np.arange(h)[:, None] + nq + nv + 3
        f_cols = (cols + np.arange(6)).ravel()
        t_cols = (cols + 6 + np.arange(6)).ravel()

        def measure(x: np.ndarray) -> dict[str, np.ndarray]:
            return {
                "position": np.asarray(positions(x)).ravel(),
                "force": x[f_cols],
                "moment": x[t_cols],
                "dt": x[nw * h :],
            }

        nlp = {"x": w, "p": params, "f": cost, "g": g}
        solver, test = build_sqp("kd_sqp", nlp, cfg.sqp, measure)
        g_fun = ca.Function("kd_g", [w, params], [g, cost])
        entry = {
            "solver": solver,
            "test": test,
            "rows": [(r[1], r[2], r[3]) for r in rows],
            "sizes": sizes,
            "used": used,
            "g_fun": g_fun,
            "f_cols": f_cols,
            "t_cols": t_cols,
        }
        self._cache[key] = entry
        return entry

    # ------------------------------------------------------------------ data
    def _arguments(self, p: JointSpaceProblem, entry: dict[str, Any]) -> dict[str, Any]:
        cd, h, nq, nv, nw = p.cd, p.horizon, self.nq, self.nv, self.nw
        used = entry["used"]
        robot = self.kin.robot
        x0 = np.zeros(nw * h + used.size)
        lbx = np.full(x0.size, -np.inf)
        ubx = np.full(x0.size, np.inf)
        j0 = nq - self.kin.dyn.n_joints
        swing = ~np.repeat(cd.contact, 3, axis=1)  # (h, 6)
        for k in range(h):
            o = nw * k
            x0[o : o + nq] = p.qpos_ref[k]
            x0[o + nq : o + nq + nv] = p.qvel_ref[k]
            x0[o + nq + nv : o + nq + nv + 3] = cd.H_ref[k + 1, 3:]
            x0[o + nq + nv + 3 : o + nq + nv + 9] = cd.guess.f[k].ravel()
            x0[o + nq + nv + 9 : o + nw] = cd.guess.tau[k].ravel()
            lbx[o + j0 : o + nq] = robot.joint_lower_rad
            ubx[o + j0 : o + nq] = robot.joint_upper_rad
            for off in (nq + nv + 3, nq + nv + 9):
                lbx[o + off : o + off + 6] = np.where(swing[k], 0.0, -np.inf)
                ubx[o + off : o + off + 6] = np.where(swing[k], 0.0, np.inf)
        x0[nw * h :] = p.dt_guess_s[used]
        lbx[nw * h :], ubx[nw * h :] = DT_BOUNDS_S
        # joint guesses inside the limits
        x0 = np.clip(x0, lbx, ubx)
        lbg, ubg = [], []
        for lo, hi, tag in entry["rows"]:
            if tag.startswith("wrench"):
                k, i = int(tag[6:-1]), int(tag[-1])
                lo, hi = cd.wrench_lo[k, i], cd.wrench_hi[k, i]
            elif tag.startswith("box"):
                k, i = int(tag[3:-1]), int(tag[-1])
                lo, hi = cd.pf_lb_m[k, i], cd.pf_ub_m[k, i]
            elif tag.startswith("sep"):
                lo = np.array([cd.sep_min_m[int(tag[3:])]])
            lbg.append(lo)
            ubg.append(hi)
        params = np.concatenate(
            [p.qpos0, p.qvel0, cd.s0[6:9], p.dt_fixed_s, cd.wrench_c.reshape(-1),
             cd.h_ref[1:].ravel(), cd.H_ref[1:].ravel(), cd.p_com_ref[1:].ravel(),
             cd.p_foot_ref.ravel(), p.foot_yaw_rad.ravel(), p.qpos_ref.ravel(),
             p.qvel_ref.ravel(),
             cd.sep_axis.ravel() if cd.sep_axis is not None else np.zeros(0)]
        )  # fmt: skip
        return {
            "x0": x0,
            "p": params,
            "lbx": lbx,
            "ubx": ubx,
            "lbg": np.concatenate(lbg),
            "ubg": np.concatenate(ubg),
        }

    def prepare(self, p: JointSpaceProblem) -> None:
        """Build (and cache) the NLP of ``p``'s structure; not part of a timed solve."""
        self._build(p)

    def guess(self, p: JointSpaceProblem) -> np.ndarray:
        """The cold start of ``p``: the kd reference's states, ``u^0``'s wrenches, the
        recorded sampling times."""
        entry = self._build(p)
        return np.asarray(self._arguments(p, entry)["x0"])

    def evaluate(self, p: JointSpaceProblem, x: np.ndarray) -> tuple[float, float]:
        """(objective, largest constraint/bound violation) of ``p`` at ``x``."""
        entry = self._build(p)
        return objective_and_violation(entry["g_fun"], self._arguments(p, entry), x)

    def solve(self, p: JointSpaceProblem, feasibility_tol: float = 1e-6) -> JointSQPResult:
        """Solve ``p`` cold (module docstring); converged: the step test stopped it at a
        point feasible to ``feasibility_tol`` (a failed QP leaves the iterate unchanged,
        which the step test alone would take for convergence)."""
        entry = self._build(p)
        args = self._arguments(p, entry)
        run = run_sqp(entry["solver"], entry["test"], self.config.sqp, GROUPS, args)
        obj, viol = self.evaluate(p, run.x)
        res = self._result(p, entry, run.x, run, obj, viol)
        return replace(res, converged=res.converged and viol <= feasibility_tol)

    def _result(
        self, p: JointSpaceProblem, entry: dict[str, Any], x: np.ndarray, run: Any, obj: float,
        viol: float,
    ) -> JointSQPResult:  # fmt: skip
        h, nq, nv, nw = p.horizon, self.nq, self.nv, self.nw
        z = x[: nw * h].reshape(h, nw)
        qpos = np.vstack([p.qpos0, z[:, :nq]])
        qvel = np.vstack([p.qvel0, z[:, nq : nq + nv]])
        dt_vars = np.zeros(p.dt_select.shape[1])
        dt_vars[entry["used"]] = x[nw * h :]
        dts = p.dts_s(dt_vars)
        plan = self.centroidal_plan(p, qpos, qvel, z[:, nq + nv + 3 :], dts)
        return JointSQPResult(
            qpos=qpos,
            qvel=qvel,
            dts_s=dts,
            n_qps=run.n_qps,
            converged=run.converged,
            solve_time_s=run.solve_time_s,
            status=run.status,
            objective=obj,
            violation=viol,
            plan=plan,
            eq18_cost=cd_cost(p.cd, plan) if math.isfinite(obj) else math.nan,
        )

    def centroidal_plan(
        self, p: JointSpaceProblem, qpos: np.ndarray, qvel: np.ndarray, wrench: np.ndarray,
        dts_s: np.ndarray,
    ) -> CDSolution:  # fmt: skip
        """The plan as the centroidal problem's variables: ``p_c(q), h(q, qdot)``, the
        angular pose integrated with the plan's dt, the wrenches, the stance foot centres
        (a swing stage: the foot's next touchdown, else its reference)."""
        kin, h = self.kin, p.horizon
        mom = np.array(
            [np.asarray(kin.momentum(q, v)).ravel() for q, v in zip(qpos, qvel, strict=True)]
        )
        com = np.array([np.asarray(kin.com(q)).ravel() for q in qpos])
        feet = np.array([np.asarray(kin.feet(q)).T for q in qpos])  # (h+1, 2, 3)
        ha = p.cd.s0[6:9] + np.cumsum(mom[:-1, 3:] * dts_s[:, None], axis=0)
        states = np.hstack([com[1:], mom[1:, :3], ha, mom[1:, 3:]])
        nxt = next_touchdown(p.cd.contact)
        p_foot = np.array(p.cd.p_foot_ref, dtype=float)
        for k in range(h):
            for i in range(2):
                node = k if p.cd.contact[k, i] else int(nxt[k, i])
                if node >= 0:
                    p_foot[k, i] = feet[node, i]
        return CDSolution(
            states=states,
            f=wrench[:, :6].reshape(h, 2, 3).copy(),
            tau=wrench[:, 6:12].reshape(h, 2, 3).copy(),
            p_foot=p_foot,
        )


__all__ = [
    "GROUPS",
    "ExplicitKDSQP",
    "JointSQPResult",
    "KDSQPConfig",
    "foot_events",
    "next_touchdown",
    "rotation_error",
]
