"""WBD-SQP: the whole-body NMPC of Sec. III-A (eqs. 1-4) with variable dt, by ``sqpmethod``.

The transcription of :mod:`gaitnet_mpc.mpc.wholebody.nlp` takes the sampling times as
parameters and builds one NLP per contact schedule for IPOPT/FATROP; Table II's WBD
column needs ``dt`` as decision variables and the recorded problems' terrain (foot
heights and eq. 24 boxes per touchdown), so this module transcribes the same model with
the same dynamics builders (:class:`~gaitnet_mpc.mpc.wholebody.dynamics.WholeBodyDynamics`:
RNEA inverse dynamics of eq. 4, contact kinematics, the semi-implicit step of eq. 3a) and
Table VI's weights and limits (:class:`~gaitnet_mpc.mpc.wholebody.problem.WBConfig`).

Variables per stage ``k = 0 .. h-1``, then one dt per step (``joint_space``)::

    w_k = [qpos_k+1 (25), qvel_k+1 (24), qacc_k (24), tau_j,k (18), lambda_k (4 x 3)],  dt_j

``n = 103 h + n_dt`` (paper: ``78 h`` = q, qdot (24 + 24), tau (18), lambda (12): no
accelerations, whose rows here keep the dynamics an inverse-dynamics equality).

Constraints: eq. 4 as ``ID(q_k, v_k, a_k, lambda_k) = [0; tau_k]``; eq. 3a as ``x_k+1 =
step(x_k, a_k, dt_k)``; per stance foot the friction pyramid of each contact point and
``f_min <= sum f_z <= f_max``, a swing foot's forces zero (bounds); on node ``k+1`` the
contact mode of stage ``k`` as in :mod:`~gaitnet_mpc.mpc.wholebody.nlp` (stance: toe and
heel on the ground, no toe slip, no yaw rate; touchdown node: on the ground and the foot
centre in the eq. 24 box; swing: ``swing_clearance sin(pi s)`` above the lower of the
lift-off and touchdown heights); joint and torque limits; ``dt`` in Table VI's range.

Cost: eq. 2 with Table VI's weights towards the kd reference ``q_ref, qdot_ref`` (the
trunk position included: the kd reference's trunk path, which carries its CoM path).

Step test (:mod:`~gaitnet_mpc.table2.sqp_common`): the quantities CD-SQP and explicit
KD-SQP test, measured from the iterate: CoM and foot centres, each foot's force (the sum
of its contact-point forces) and moment about its centre, and dt (:data:`GROUPS`).
``foot_wrench_test=False`` tests each contact point's force instead and no moment (the
test before 2026-12: :data:`POINT_GROUPS`).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.mpc.wholebody.problem import WBConfig
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.table2.joint_space import DT_BOUNDS_S, JointSpaceProblem, SymbolicKinematics
from gaitnet_mpc.table2.kd_sqp import JointSQPResult, foot_events, rotation_error
from gaitnet_mpc.table2.sqp_common import SQPConfig, build_sqp, objective_and_violation, run_sqp

#: Step-test groups: CoM and foot centres [m], foot forces [N] and moments [N m] (from
#: the contact-point forces: the quantities CD-SQP and explicit KD-SQP test), dt [s].
GROUPS = ("position", "force", "moment", "dt")
#: The groups of the contact-point test (``foot_wrench_test=False``): each point's force.
POINT_GROUPS = ("position", "force", "dt")


def swing_profile(contact: np.ndarray, stages_per_step: int, first_partial: bool) -> np.ndarray:
    """(h,) fraction ``s = (j + 1) / h'`` of its step elapsed at node ``k+1``, ``j`` the
    stage's index in its step; the step in progress counts its stages before the horizon
    when ``first_partial``."""
    h = contact.shape[0]
    change = np.concatenate([[True], np.any(contact[1:] != contact[:-1], axis=1)])
    starts = np.flatnonzero(change)
    first_len = int(starts[1]) if starts.size > 1 else h
    out = np.zeros(h)
    for k in range(h):
        start = int(starts[starts <= k].max())
        j = k - start
        if start == 0 and first_partial:
            j += max(stages_per_step - first_len, 0)
        out[k] = (j + 1) / stages_per_step
    return np.clip(out, 0.0, 1.0)


class WBDSQP:
    """Whole-body NMPC with dt variables by ``sqpmethod`` (module docstring); one NLP per
    contact pattern and dt layout."""

    def __init__(
        self,
        kinematics: SymbolicKinematics,
        config: WBConfig | None = None,
        sqp: SQPConfig | None = None,
        foot_wrench_test: bool = True,
    ) -> None:
        self.kin = kinematics
        self.config = config or WBConfig()
        self.sqp = sqp or SQPConfig()
        self.foot_wrench_test = foot_wrench_test
        d = kinematics.dyn
        self.nq, self.nv, self.nj, self.nc = d.nq, d.nv, d.n_joints, d.n_contacts
        self.nw = self.nq + 2 * self.nv + self.nj + 3 * self.nc
        self._cache: dict[tuple[Any, ...], dict[str, Any]] = {}

    def n_variables(self, horizon: int, n_dt: int) -> int:
        """``(nq + 2 nv + n_j + 3 n_c) h + n_dt`` (module docstring)."""
        return self.nw * horizon + n_dt

    def _slices(self, k: int) -> dict[str, slice]:
        o, nq, nv, nj = self.nw * k, self.nq, self.nv, self.nj
        return {
            "q": slice(o, o + nq),
            "v": slice(o + nq, o + nq + nv),
            "a": slice(o + nq + nv, o + nq + 2 * nv),
            "tau": slice(o + nq + 2 * nv, o + nq + 2 * nv + nj),
            "lam": slice(o + nq + 2 * nv + nj, o + self.nw),
        }

    def _build(self, p: JointSpaceProblem) -> dict[str, Any]:
        key = (p.cd.contact.tobytes(), p.dt_select.tobytes())
        if key in self._cache:
            return self._cache[key]
        kin, d, cfg, wt = self.kin, self.kin.dyn, self.config, self.config.weights
        nq, nv, nj, nw, h = self.nq, self.nv, self.nj, self.nw, p.horizon
        used = np.flatnonzero(p.dt_select.any(axis=0))
        n_dt = used.size
        w = ca.SX.sym("w", nw * h + n_dt)
        dt_vars = w[nw * h :]
        qpos0, qvel0 = ca.SX.sym("qpos0", nq), ca.SX.sym("qvel0", nv)
        dt_fixed = ca.SX.sym("dt_fixed", h)
        q_ref, v_ref = ca.SX.sym("q_ref", h * nq), ca.SX.sym("v_ref", h * nv)
        yaw = ca.SX.sym("yaw", h * 2)
        params = ca.vertcat(qpos0, qvel0, dt_fixed, q_ref, v_ref, yaw)
        contact = p.cd.contact
        touchdown, _ = foot_events(contact)
        qs = [qpos0] + [w[self._slices(k)["q"]] for k in range(h)]
        vs = [qvel0] + [w[self._slices(k)["v"]] for k in range(h)]
        rows: list[tuple[Any, Any, Any, str]] = []

        def add(expr: Any, lo: float, hi: float, tag: str = "") -> None:
            n = expr.shape[0]
            rows.append((expr, np.full(n, lo, float), np.full(n, hi, float), tag))

        mu = cfg.friction_coef
        j0 = nq - nj
        qb = ca.DM(list(wt.q_base))
        vb = ca.DM(list(wt.v_base))
        cost = ca.SX(0.0)
        for k in range(h):
            s = self._slices(k)
            acc, tau, lam = w[s["a"]], w[s["tau"]], w[s["lam"]]
            sel = [j for j in range(n_dt) if p.dt_select[k, used[j]] > 0.0]
            dt = dt_vars[sel[0]] if sel else dt_fixed[k]
            gen = d.inverse_dynamics(qs[k], vs[k], acc, lam)
            add(gen - ca.vertcat(ca.SX.zeros(d.n_root_dofs), tau), 0.0, 0.0)
            q_next, v_next = d.step(qs[k], vs[k], acc, dt)
            add(ca.vertcat(qs[k + 1], vs[k + 1]) - ca.vertcat(q_next, v_next), 0.0, 0.0)
            for i, foot in enumerate(FEET):
                pts = d.contact_points_of(foot)
                if contact[k, i]:
                    for c in pts:
                        fz = lam[3 * c + 2]
                        for a in (0, 1):
                            ft = lam[3 * c + a]
                            add(ca.vertcat(mu * fz - ft, mu * fz + ft), 0.0, np.inf)
                    add(sum(lam[3 * c + 2] for c in pts), cfg.f_min_n, cfg.f_max_n)
            # node k+1: contact mode of stage k (nlp.py's rows)
            p_c, v_c = d.contact_kinematics(qs[k + 1], vs[k + 1])
            for i, foot in enumerate(FEET):
                pts = d.contact_points_of(foot)
                if contact[k, i]:
                    add(ca.vertcat(*[p_c[2, c] for c in pts]), np.nan, np.nan, f"ground{k}{i}")
                    add(v_c[0:2, pts[0]], 0.0, 0.0)
                    dp = p_c[0:2, pts[0]] - p_c[0:2, pts[1]]
                    dv = v_c[0:2, pts[0]] - v_c[0:2, pts[1]]
                    add(dp[0] * dv[1] - dp[1] * dv[0], 0.0, 0.0)
                elif k + 1 < h and touchdown[k + 1, i]:
                    add(ca.vertcat(*[p_c[2, c] for c in pts]), np.nan, np.nan, f"ground{k + 1}{i}")
                    centre = kin.feet(qs[k + 1])[:, i]
                    add(centre[0:2], np.nan, np.nan, f"box{k + 1}{i}")
                    d_th = p_c[0:2, pts[0]] - p_c[0:2, pts[1]]
                    yk = yaw[2 * (k + 1) + i]
                    add(d_th[0] * ca.sin(yk) - d_th[1] * ca.cos(yk), 0.0, 0.0)
                else:
                    add(ca.vertcat(*[p_c[2, c] for c in pts]), np.nan, np.inf, f"swing{k}{i}")
            # eq. 2
            qr, vr = q_ref[nq * k : nq * (k + 1)], v_ref[nv * k : nv * (k + 1)]
            q1, v1 = qs[k + 1], vs[k + 1]
            pose_err = ca.vertcat(q1[0:3] - qr[0:3], rotation_error(q1[3:7], qr[3:7]))
            cost += ca.sum1(qb * pose_err**2) + wt.q_joint * ca.sumsqr(q1[j0:] - qr[j0:])
            cost += ca.sum1(vb * (v1[:6] - vr[:6]) ** 2) + wt.v_joint * ca.sumsqr(v1[6:] - vr[6:])
            cost += wt.tau_joint * ca.sumsqr(tau) + wt.force * ca.sumsqr(lam)
            lever = d.robot.spec.foot_toe_m
            for foot in FEET:
                toe, heel = d.contact_points_of(foot)[:2]
                diff = lam[3 * toe : 3 * toe + 3] - lam[3 * heel : 3 * heel + 3]
                cost += wt.moment * lever**2 * ca.sumsqr(diff)
        g = ca.vertcat(*[r[0] for r in rows])
        positions = ca.Function(
            "wbd_positions",
            [w],
            [ca.vertcat(*[ca.vertcat(kin.com(q), ca.vec(kin.feet(q))) for q in qs[1:]])],
        )
        lam_cols = np.concatenate([np.arange(h * nw)[self._slices(k)["lam"]] for k in range(h)])
        wrench_fun = self._foot_wrench_function(h)
        # the measured state of the problem being solved and the test (set by ``solve``)
        state: dict[str, Any] = {"qpos0": np.zeros(nq), "foot_wrench_test": True}

        def measure(x: np.ndarray) -> dict[str, np.ndarray]:
            if not state["foot_wrench_test"]:
                return {
                    "position": np.asarray(positions(x)).ravel(),
                    "force": x[lam_cols],
                    "dt": x[nw * h :],
                }
            f_feet, t_feet = wrench_fun(x, state["qpos0"])
            return {
                "position": np.asarray(positions(x)).ravel(),
                "force": np.asarray(f_feet).ravel(),
                "moment": np.asarray(t_feet).ravel(),
                "dt": x[nw * h :],
            }

        nlp = {"x": w, "p": params, "f": cost, "g": g}
        solver, test = build_sqp("wbd_sqp", nlp, self.sqp, measure)
        entry = {
            "solver": solver,
            "test": test,
            "rows": [(r[1], r[2], r[3]) for r in rows],
            "used": used,
            "g_fun": ca.Function("wbd_g", [w, params], [g, cost]),
            "state": state,
        }
        self._cache[key] = entry
        return entry

    def _foot_wrench_function(self, h: int) -> Any:
        """``(w, qpos0) -> (F, T)``, (6 h,) each: per stage ``k`` and foot, the sum of its
        contact-point forces and their moment about the foot centre ``p_f(q_k)`` (the
        point explicit KD-SQP's ``tau`` refers to), at the stage's configuration."""
        d, nq, nw = self.kin.dyn, self.nq, self.nw
        w = ca.SX.sym("w", nw * h)
        qpos0 = ca.SX.sym("qpos0", nq)
        qs = [qpos0] + [w[self._slices(k)["q"]] for k in range(h - 1)]
        forces, moments = [], []
        for k in range(h):
            lam = w[self._slices(k)["lam"]]
            pts, _ = d.contact_kinematics(qs[k], ca.SX.zeros(self.nv))
            centres = self.kin.feet(qs[k])
            for i, foot in enumerate(FEET):
                f_i, t_i = ca.SX.zeros(3), ca.SX.zeros(3)
                for c in d.contact_points_of(foot):
                    lam_c = lam[3 * c : 3 * c + 3]
                    f_i += lam_c
                    t_i += ca.cross(pts[:, c] - centres[:, i], lam_c)
                forces.append(f_i)
                moments.append(t_i)
        out = [ca.vertcat(*forces), ca.vertcat(*moments)]
        fun = ca.Function("wbd_foot_wrench", [w, qpos0], out, {"cse": True})

        def wrench(x_all: np.ndarray, q0: np.ndarray) -> tuple[Any, Any]:
            return fun(x_all[: nw * h], q0)

        return wrench

    def _arguments(self, p: JointSpaceProblem, entry: dict[str, Any]) -> dict[str, Any]:
        cd, h, nw = p.cd, p.horizon, self.nw
        d, robot, cfg = self.kin.dyn, self.kin.robot, self.config
        used = entry["used"]
        r = robot.spec.foot_contact_radius_m
        x0 = np.zeros(nw * h + used.size)
        lbx, ubx = np.full(x0.size, -np.inf), np.full(x0.size, np.inf)
        weight_n = cd.config.mass_kg * cd.config.gravity_mps2
        for k in range(h):
            s = self._slices(k)
            x0[s["q"]], x0[s["v"]] = p.qpos_ref[k], p.qvel_ref[k]
            joints = slice(s["q"].stop - self.nj, s["q"].stop)
            lbx[joints], ubx[joints] = robot.joint_lower_rad, robot.joint_upper_rad
            lbx[s["tau"]], ubx[s["tau"]] = -robot.torque_limit_nm, robot.torque_limit_nm
            stance_pts = [
                c for i, f in enumerate(FEET) if cd.contact[k, i] for c in d.contact_points_of(f)
            ]
            lam = np.zeros(3 * self.nc)
            lo_l, hi_l = np.zeros(3 * self.nc), np.zeros(3 * self.nc)
            for c in stance_pts:
                lam[3 * c + 2] = weight_n / len(stance_pts)
                lo_l[3 * c : 3 * c + 3] = (-np.inf, -np.inf, 0.0)
                hi_l[3 * c : 3 * c + 3] = np.inf
            x0[s["lam"]], lbx[s["lam"]], ubx[s["lam"]] = lam, lo_l, hi_l
        x0[nw * h :] = p.dt_guess_s[used]
        lbx[nw * h :], ubx[nw * h :] = DT_BOUNDS_S
        x0 = np.clip(x0, lbx, ubx)
        # heights: a stance stage's box height; swing: the lower of lift-off / touchdown
        z = cd.pf_lb_m[:, :, 2] - r  # (h, 2) contact-point height of the stage's foothold
        z_now = np.asarray(
            [np.asarray(self.kin.feet(p.qpos0)).T[i, 2] - r for i in range(2)], dtype=float
        )
        first_partial = bool(p.dt_select[0].sum() == 0.0)
        frac = swing_profile(cd.contact, cfg.stages_per_step, first_partial)
        clearance = cfg.swing_clearance_m * np.sin(np.pi * frac)
        last = z_now.copy()
        lbg, ubg = [], []
        swing_floor = np.zeros((h, 2))
        for k in range(h):
            for i in range(2):
                if cd.contact[k, i]:
                    last[i] = z[k, i]
                else:
                    swing_floor[k, i] = min(last[i], z[k, i])
        for lo, hi, tag in entry["rows"]:
            if tag.startswith("ground"):
                k, i = int(tag[6:-1]), int(tag[-1])
                lo = hi = np.full(lo.size, z[k, i])
            elif tag.startswith("box"):
                k, i = int(tag[3:-1]), int(tag[-1])
                lo, hi = cd.pf_lb_m[k, i, :2], cd.pf_ub_m[k, i, :2]
            elif tag.startswith("swing"):
                k, i = int(tag[5:-1]), int(tag[-1])
                lo = np.full(lo.size, swing_floor[k, i] + clearance[k])
            lbg.append(lo)
            ubg.append(hi)
        params = np.concatenate(
            [p.qpos0, p.qvel0, p.dt_fixed_s, p.qpos_ref.ravel(), p.qvel_ref.ravel(),
             p.foot_yaw_rad.ravel()]
        )  # fmt: skip
        return {
            "x0": x0, "p": params, "lbx": lbx, "ubx": ubx,
            "lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg),
        }  # fmt: skip

    def prepare(self, p: JointSpaceProblem) -> None:
        """Build (and cache) the NLP of ``p``'s structure; not part of a timed solve."""
        self._build(p)

    def guess(self, p: JointSpaceProblem) -> np.ndarray:
        """The cold start: the kd reference's states, zero accelerations and torques, the
        weight shared by the stance contact points, the recorded sampling times."""
        return np.asarray(self._arguments(p, self._build(p))["x0"])

    def evaluate(self, p: JointSpaceProblem, x: np.ndarray) -> tuple[float, float]:
        """(eq. 2 objective, largest constraint/bound violation) of ``p`` at ``x``."""
        entry = self._build(p)
        return objective_and_violation(entry["g_fun"], self._arguments(p, entry), x)

    def solve(self, p: JointSpaceProblem, feasibility_tol: float = 1e-6) -> JointSQPResult:
        """Solve ``p`` cold; converged: the step test stopped it at a point feasible to
        ``feasibility_tol``."""
        entry = self._build(p)
        args = self._arguments(p, entry)
        entry["state"]["qpos0"] = np.asarray(p.qpos0, dtype=float)
        entry["state"]["foot_wrench_test"] = self.foot_wrench_test
        groups = GROUPS if self.foot_wrench_test else POINT_GROUPS
        run = run_sqp(entry["solver"], entry["test"], self.sqp, groups, args)
        obj, viol = self.evaluate(p, run.x)
        h, nw = p.horizon, self.nw
        z = run.x[: nw * h].reshape(h, nw)
        dt_vars = np.zeros(p.dt_select.shape[1])
        dt_vars[entry["used"]] = run.x[nw * h :]
        return JointSQPResult(
            qpos=np.vstack([p.qpos0, z[:, : self.nq]]),
            qvel=np.vstack([p.qvel0, z[:, self.nq : self.nq + self.nv]]),
            dts_s=p.dts_s(dt_vars),
            n_qps=run.n_qps,
            converged=run.converged and viol <= feasibility_tol,
            solve_time_s=run.solve_time_s,
            status=run.status,
            objective=obj,
            violation=viol,
            plan=None,
            eq18_cost=math.nan,
        )


__all__ = ["GROUPS", "POINT_GROUPS", "WBDSQP", "swing_profile"]
