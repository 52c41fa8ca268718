"""Multiple-shooting transcription of the whole-body NMPC (eqs. 1-4) and its NLP solvers.

Decision variables (eq. 1), in the stage-wise order FATROP's structure detection needs:
``x_0, u_0, x_1, u_1, ..., x_{h-1}, u_{h-1}, x_h`` with ``x_k = (qpos_k, qvel_k)`` and
``u_k = (qacc_k, tau_j,k, lambda_k)``; the accelerations are variables so that the
dynamics are the inverse-dynamics equality of eq. (4) (no symbolic mass-matrix solve).

Constraints of stage k:

* k = 0: ``x_0 = x_measured``;
* k >= 1: contact kinematics of stage k-1's contact mode on node k (3b/3c): a stance foot's
  contact points are on the ground and do not slide (zero tangential velocity of the toe,
  zero yaw rate of a line foot: the heel's tangential velocity would repeat the toe's
  along the foot axis); a swing foot's points clear ``swing_height_min_m``, except at its
  touchdown node (swing in stage k-1, stance in stage k), where they are on the ground;
* eq. (4): ``ID(q_k, v_k, a_k, lambda_k) = [0; tau_k]``;
* contact wrenches (3c): friction pyramid ``|f_t| <= mu f_z`` per point, ``f_min <= sum
  f_z <= f_max`` per stance foot (toe and heel point forces model the line foot's wrench
  exactly, with no roll moment; a point foot's f_z bounds are variable bounds);
* eq. (3a): ``x_{k+1} = step(x_k, u_k, dt_k)``.

The rows are ordered in FATROP's blocks ``gap_0, path_0, gap_1, ..., path_h`` (gap_k: eq.
3a of stage k; path_k: the other rows of stage k). Joint limits (on nodes 1..h), torque
limits and ``f_z >= 0`` are variable bounds; a swing foot's zero force is a fixed variable
for IPOPT and path rows for FATROP. One transcription is built per contact schedule and
cached; everything else (state, dt_k, reference) is an NLP parameter, so a new MPC call
with a known schedule only re-solves.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, replace
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.wholebody.dynamics import WholeBodyDynamics, quat_mul
from gaitnet_mpc.mpc.wholebody.problem import WBConfig, WBProblem
from gaitnet_mpc.mpc.wholebody.solution import WBSolution
from gaitnet_mpc.mpc.wholebody.solvers import (
    MAX_ITER,
    SOLVERS,
    WARM_OPTIONS,
    solve_status,
    solver_options,
)
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET


@dataclass
class _Transcription:
    solver: ca.Function
    lbg: np.ndarray
    ubg: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    build_time_s: float
    block_sizes: tuple[int, ...]  # rows of gap_0, path_0, ..., path_h


class WholeBodyMPC:
    """Whole-body NMPC of Sec. III-A solved by IPOPT or FATROP through CasADi.

    ``solve(problem, warm_start)`` returns a :class:`WBSolution`; ``shift(solution)`` makes
    the warm start of the next receding-horizon call. Run it with ``OPENBLAS_NUM_THREADS=1``:
    CasADi's bundled OpenBLAS otherwise spreads IPOPT's MUMPS over every core for no gain
    at this size (``benchmarks/results/wbmpc.md``).
    """

    def __init__(
        self,
        robot: RobotModel,
        config: WBConfig | None = None,
        solver: str = "ipopt",
        solver_options: dict[str, Any] | None = None,
        dynamics: WholeBodyDynamics | None = None,
        warm_options: dict[str, Any] | None = None,
    ) -> None:
        """``solver_options`` apply to every call; ``warm_options`` (default
        :data:`WARM_OPTIONS`) on top of them to calls given a warm start with duals, which
        use a second cached solver per contact schedule."""
        if solver not in SOLVERS:
            raise ConfigError("solver", solver, f"one of {SOLVERS}")
        self.robot = robot
        self.config = config or WBConfig()
        self.solver_name = solver
        self.solver_options = dict(solver_options or {})
        self.warm_options = dict(WARM_OPTIONS[solver] if warm_options is None else warm_options)
        self.dyn = dynamics or WholeBodyDynamics(robot)
        d = self.dyn
        self.force_axes = (0, 2) if d.planar else (0, 1, 2)
        self.nf = len(self.force_axes)
        self.nx = d.nq + d.nv
        self.nu = d.nv + d.n_joints + self.nf * d.n_contacts
        self._cache: dict[tuple, _Transcription] = {}
        self.last_build_time_s = 0.0

    # ------------------------------------------------------------ layout
    @property
    def horizon_stages(self) -> int:
        return self.config.horizon_stages

    def _stage_offset(self, k: int) -> int:
        return k * (self.nx + self.nu)

    def n_variables(self) -> int:
        return self.horizon_stages * (self.nx + self.nu) + self.nx

    def _unpack_u(self, u: Any) -> tuple[Any, Any, Any]:
        d = self.dyn
        return u[: d.nv], u[d.nv : d.nv + d.n_joints], u[d.nv + d.n_joints :]

    def _force_world(self, lam: Any) -> Any:
        """Stacked 3-D world forces (3 n_c) from the decision forces (nf n_c)."""
        cols = []
        for i in range(self.dyn.n_contacts):
            f = [0] * 3
            for j, ax in enumerate(self.force_axes):
                f[ax] = lam[self.nf * i + j]
            cols.append(ca.vertcat(*f))
        return ca.vertcat(*cols)

    # ------------------------------------------------------------ transcription
    def _build(self, key: tuple[tuple[bool, ...], ...], warm: bool = False) -> _Transcription:
        t0 = time.perf_counter()
        cfg, d, w = self.config, self.dyn, self.config.weights
        h, nq, nv = self.horizon_stages, d.nq, d.nv
        x_all = ca.MX.sym("w", self.n_variables())
        xs = [x_all[self._stage_offset(k) : self._stage_offset(k) + self.nx] for k in range(h + 1)]
        us = [x_all[self._stage_offset(k) + self.nx : self._stage_offset(k + 1)] for k in range(h)]
        n_par = nq + nv + h + h * nq + h * nv + h + 1
        p = ca.MX.sym("p", n_par)
        x_meas, dt = p[: nq + nv], p[nq + nv : nq + nv + h]
        off = nq + nv + h
        q_ref = ca.reshape(p[off : off + h * nq], nq, h)
        off += h * nq
        v_ref = ca.reshape(p[off : off + h * nv], nv, h)
        off += h * nv
        swing_min, ground = p[off : off + h], p[off + h]

        # Rows per stage: path[k] (constraints on x_k, u_k) and gap[k] (x_{k+1} = F(x_k, u_k)).
        path: list[list[tuple[Any, np.ndarray, np.ndarray]]] = [[] for _ in range(h + 1)]
        gap: list[list[tuple[Any, np.ndarray, np.ndarray]]] = [[] for _ in range(h)]
        stage = 0

        def add(expr: Any, lo: float, hi: float, rows: list | None = None) -> None:
            n = expr.shape[0]
            lo_v, hi_v = np.full(n, lo, dtype=float), np.full(n, hi, dtype=float)
            (path[stage] if rows is None else rows).append((expr, lo_v, hi_v))

        line_foot = d.robot.spec.foot_toe_m > 0.0 or d.robot.spec.foot_heel_m > 0.0
        tangent = (0,) if d.planar else (0, 1)
        mu = cfg.friction_coef
        cost = 0
        for k in range(h + 1):
            stage = k
            qk, vk = xs[k][:nq], xs[k][nq:]
            if k == 0:
                add(xs[0] - x_meas, 0.0, 0.0)
            else:
                p_c, v_c = d.contact_kinematics(qk, vk)
                for fi, foot in enumerate(FEET):
                    pts = d.contact_points_of(foot)
                    if key[k - 1][fi]:
                        for i in pts:
                            add(p_c[2, i] - ground, 0.0, 0.0)
                        add(ca.vertcat(*[v_c[a, pts[0]] for a in tangent]), 0.0, 0.0)
                        if line_foot and len(pts) > 1:
                            # Yaw rate of the foot from the toe-heel relative velocity.
                            dp = p_c[0:2, pts[0]] - p_c[0:2, pts[1]]
                            dv = v_c[0:2, pts[0]] - v_c[0:2, pts[1]]
                            add(dp[0] * dv[1] - dp[1] * dv[0], 0.0, 0.0)
                    elif k < h and key[k][fi]:
                        # Touchdown at the scheduled node: the foot stands in stage k, so
                        # its points are on the ground at node k, where stage k's forces
                        # start to act (with only the lower bound the plan let the foot
                        # land one stage late, pushing on the ground from up in the air).
                        for i in pts:
                            add(p_c[2, i] - ground, 0.0, 0.0)
                    else:
                        for i in pts:
                            add(p_c[2, i] - ground - swing_min[k - 1], 0.0, np.inf)
                # Eq. (2): tracking of node k (base pose, joints) and rates.
                scale = w.terminal_scale if k == h else 1.0
                cost += scale * self._state_cost(qk, vk, q_ref[:, k - 1], v_ref[:, k - 1])
            if k == h:
                break
            acc, tau, lam = self._unpack_u(us[k])
            f_world = self._force_world(lam)
            gen = d.inverse_dynamics(qk, vk, acc, f_world)
            add(gen - ca.vertcat(ca.MX.zeros(d.n_root_dofs), tau), 0.0, 0.0)
            for fi, foot in enumerate(FEET):
                pts = d.contact_points_of(foot)
                if not key[k][fi]:
                    # Zero swing force: a fixed variable for IPOPT (treated as a parameter),
                    # path rows for FATROP (its interior point has no fixed-variable mode).
                    if self.solver_name == "fatrop":
                        add(ca.vertcat(*[lam[self.nf * i : self.nf * (i + 1)] for i in pts]), 0, 0)
                    continue
                for i in pts:
                    fz = f_world[3 * i + 2]
                    for a in tangent:
                        ft = f_world[3 * i + a]
                        add(ca.vertcat(mu * fz - ft, mu * fz + ft), 0.0, np.inf)
                if len(pts) > 1:
                    add(sum(f_world[3 * i + 2] for i in pts), cfg.f_min_n, cfg.f_max_n)
            cost += w.tau_joint * ca.sumsqr(tau) + w.force * ca.sumsqr(lam)
            if line_foot:
                lever = d.robot.spec.foot_toe_m
                for foot in FEET:
                    toe, heel = d.contact_points_of(foot)[:2]
                    diff = (
                        lam[self.nf * toe : self.nf * (toe + 1)]
                        - lam[self.nf * heel : self.nf * (heel + 1)]
                    )
                    cost += w.moment * lever**2 * ca.sumsqr(diff)
            q_next, v_next = d.step(qk, vk, acc, dt[k])
            add(xs[k + 1] - ca.vertcat(q_next, v_next), 0.0, 0.0, rows=gap[k])

        # FATROP's block order: gap_0, path_0, gap_1, path_1, ..., path_h.
        rows = [r for k in range(h) for r in gap[k] + path[k]] + path[h]
        g_all = ca.vertcat(*[r[0] for r in rows])
        lbg_all = np.concatenate([r[1] for r in rows])
        ubg_all = np.concatenate([r[2] for r in rows])
        n_path = [sum(r[0].shape[0] for r in path[k]) for k in range(h + 1)]
        n_gap = [sum(r[0].shape[0] for r in gap[k]) for k in range(h)]
        blocks = (*(n for k in range(h) for n in (n_gap[k], n_path[k])), n_path[h])
        lbx, ubx = self._variable_bounds(key)
        nlp = {"x": x_all, "p": p, "f": cost, "g": g_all}
        equality = [bool(lo == hi) for lo, hi in zip(lbg_all, ubg_all, strict=True)]
        opts = solver_options(self.solver_name, self.nx, self.nu, n_path, equality)
        opts.update(self.solver_options)
        if warm:
            opts.update(self.warm_options)
        solver = ca.nlpsol(f"wbmpc_{self.solver_name}", self.solver_name, nlp, opts)
        build = time.perf_counter() - t0
        self.last_build_time_s = build
        return _Transcription(solver, lbg_all, ubg_all, lbx, ubx, build, blocks)

    def _state_cost(self, q: Any, v: Any, q_ref: Any, v_ref: Any) -> Any:
        """Eq. (2): ||q - q_ref||_Q1^2 + ||qdot - qdot_ref||_Q4^2 of one node."""
        d, w = self.dyn, self.config.weights
        if d.planar:
            pose_err, qb, vb = q[0:3] - q_ref[0:3], [0, 2, 4], [0, 2, 4]  # x, z, pitch
            j0 = 3
        else:
            conj = ca.vertcat(q_ref[3], -q_ref[4:7])
            rot_err = 2 * quat_mul(conj, q[3:7])[1:4]
            pose_err, qb, vb = ca.vertcat(q[0:3] - q_ref[0:3], rot_err), [*range(6)], [*range(6)]
            j0 = 7
        q_base_w = ca.DM([w.q_base[i] for i in qb])
        v_base_w = ca.DM([w.v_base[i] for i in vb])
        nb = d.n_root_dofs
        return (
            ca.sum1(q_base_w * pose_err**2)
            + w.q_joint * ca.sumsqr(q[j0:] - q_ref[j0:])
            + ca.sum1(v_base_w * (v[:nb] - v_ref[:nb]) ** 2)
            + w.v_joint * ca.sumsqr(v[nb:] - v_ref[nb:])
        )

    def _variable_bounds(self, key: tuple[tuple[bool, ...], ...]) -> tuple[np.ndarray, np.ndarray]:
        """Joint limits (nodes 1..h), torque limits, ``f_z >= 0`` per point, zero force on
        a swing foot, ``f_min <= f_z <= f_max`` for a single-point foot (3c)."""
        d, r, cfg = self.dyn, self.robot, self.config
        n = self.n_variables()
        lbx, ubx = np.full(n, -np.inf), np.full(n, np.inf)
        j0 = d.nq - d.n_joints
        for k in range(1, self.horizon_stages + 1):
            o = self._stage_offset(k)
            lbx[o + j0 : o + d.nq] = r.joint_lower_rad
            ubx[o + j0 : o + d.nq] = r.joint_upper_rad
        for k in range(self.horizon_stages):
            o = self._stage_offset(k) + self.nx + d.nv
            lbx[o : o + d.n_joints] = -r.torque_limit_nm
            ubx[o : o + d.n_joints] = r.torque_limit_nm
            o_f = o + d.n_joints
            for fi, foot in enumerate(FEET):
                pts = d.contact_points_of(foot)
                for i in pts:
                    sl = slice(o_f + self.nf * i, o_f + self.nf * (i + 1))
                    if not key[k][fi]:
                        if self.solver_name != "fatrop":
                            lbx[sl], ubx[sl] = 0.0, 0.0
                    elif len(pts) == 1:
                        lbx[sl.stop - 1], ubx[sl.stop - 1] = cfg.f_min_n, cfg.f_max_n
                    else:
                        lbx[sl.stop - 1] = 0.0
        return lbx, ubx

    def shift(self, solution: WBSolution) -> WBSolution:
        """Warm start for the next MPC call: every stage moved one earlier, the last stage
        repeated, for the primal variables, the bound duals and the constraint duals (per
        stage block; :meth:`solve` zeroes a block whose size differs in the new schedule)."""
        n_stage, h = self.nx + self.nu, self.horizon_stages

        def shift_stages(v: np.ndarray) -> np.ndarray:
            return np.concatenate([v[n_stage : h * n_stage], v[(h - 1) * n_stage :]])

        b = solution.lam_blocks
        if len(b) == 2 * h + 1:
            # New gap_k, path_k <- old gap_{k+1}, path_{k+1}; the last stage repeats.
            b = (*b[2:-1], b[-3], b[-2], b[-1])
        return replace(
            solution,
            x_opt=shift_stages(solution.x_opt),
            lam_x=shift_stages(solution.lam_x),
            lam_g=np.zeros(0),
            lam_blocks=b,
        )

    # ------------------------------------------------------------ solve
    def parameters(self, problem: WBProblem) -> np.ndarray:
        """NLP parameter vector of one problem (state, dt_k, reference, swing bound, ground)."""
        return np.concatenate(
            [
                problem.qpos0,
                problem.qvel0,
                problem.dt_stage_s,
                np.asarray(problem.qpos_ref).ravel(),
                np.asarray(problem.qvel_ref).ravel(),
                problem.swing_height_min_m,
                [problem.ground_z_m],
            ]
        )

    def cold_start(self, problem: WBProblem) -> np.ndarray:
        """Measured state on every node, zero accelerations and torques, the weight shared
        equally by the stance contact points."""
        d = self.dyn
        x = np.zeros(self.n_variables())
        weight_n = self.robot.total_mass_kg * 9.81
        for k in range(self.horizon_stages + 1):
            o = self._stage_offset(k)
            x[o : o + d.nq], x[o + d.nq : o + self.nx] = problem.qpos0, problem.qvel0
            if k == self.horizon_stages:
                break
            stance_pts = [
                i
                for fi, f in enumerate(FEET)
                if problem.stance[k, fi]
                for i in d.contact_points_of(f)
            ]
            o_f = o + self.nx + d.nv + d.n_joints
            for i in stance_pts:
                x[o_f + self.nf * i + self.nf - 1] = weight_n / len(stance_pts)
        return x

    def prepare(self, problem: WBProblem, warm: bool = False) -> float:
        """Build and cache the solver of ``problem``'s contact schedule (cold or warm-start
        settings); returns the build time [s], 0 if it was cached."""
        key = (problem.schedule_key, warm and bool(self.warm_options))
        if key in self._cache:
            return 0.0
        self._cache[key] = self._build(problem.schedule_key, warm)
        return self._cache[key].build_time_s

    def solve(self, problem: WBProblem, warm_start: WBSolution | None = None) -> WBSolution:
        """Solve one NMPC instance; ``warm_start`` seeds primal and dual variables."""
        d = self.dyn
        problem.validate(d.nq, d.nv)
        if problem.horizon_stages != self.horizon_stages:
            raise ConfigError(
                "WBProblem.stance", problem.horizon_stages, f"{self.horizon_stages} stages"
            )
        # Warm-start settings and duals only where the solver has warm settings (IPOPT);
        # otherwise a warm start is the primal guess on the cold solver.
        warm = (
            bool(self.warm_options)
            and warm_start is not None
            and (warm_start.lam_g.size > 0 or len(warm_start.lam_blocks) > 0)
        )
        self.prepare(problem, warm)
        tr = self._cache[(problem.schedule_key, warm)]
        args: dict[str, Any] = {
            "p": self.parameters(problem),
            "lbx": tr.lbx,
            "ubx": tr.ubx,
            "lbg": tr.lbg,
            "ubg": tr.ubg,
        }
        if warm_start is not None:
            if warm_start.x_opt.shape != (self.n_variables(),):
                raise ConfigError(
                    "warm_start", warm_start.x_opt.shape, f"({self.n_variables()},) decision vector"
                )
            args["x0"] = warm_start.x_opt
            if warm:
                args["lam_x0"] = warm_start.lam_x
                args["lam_g0"] = self._duals_for(tr, warm_start)
        else:
            args["x0"] = self.cold_start(problem)
        t0 = time.perf_counter()
        res = tr.solver(**args)
        solve_time = time.perf_counter() - t0
        stats = tr.solver.stats()
        x = np.array(res["x"]).ravel()
        g = np.array(res["g"]).ravel()
        viol = max(
            float(np.max(np.maximum(tr.lbg - g, 0.0), initial=0.0)),
            float(np.max(np.maximum(g - tr.ubg, 0.0), initial=0.0)),
            float(np.max(np.maximum(tr.lbx - x, 0.0), initial=0.0)),
            float(np.max(np.maximum(x - tr.ubx, 0.0), initial=0.0)),
        )
        sol = self._unpack(x, res, stats, solve_time, viol)
        cuts = np.cumsum((0, *tr.block_sizes))
        blocks = tuple(sol.lam_g[a:b] for a, b in itertools.pairwise(cuts))
        return replace(sol, lam_blocks=blocks)

    @staticmethod
    def _duals_for(tr: _Transcription, warm_start: WBSolution) -> np.ndarray:
        """Constraint duals for ``tr`` from a warm start: its raw ``lam_g`` if the layout
        matches, else its blocks where their sizes match and zeros elsewhere."""
        if not warm_start.lam_blocks:
            lam = warm_start.lam_g
            return lam if lam.shape == tr.lbg.shape else np.zeros(tr.lbg.shape)
        parts = []
        for i, n in enumerate(tr.block_sizes):
            blk = warm_start.lam_blocks[i] if i < len(warm_start.lam_blocks) else None
            parts.append(blk if blk is not None and blk.shape == (n,) else np.zeros(n))
        return np.concatenate(parts)

    def _unpack(
        self, x: np.ndarray, res: dict, stats: dict, solve_time: float, viol: float
    ) -> WBSolution:
        d, h = self.dyn, self.horizon_stages
        states = np.array(
            [x[self._stage_offset(k) : self._stage_offset(k) + self.nx] for k in range(h + 1)]
        )
        inputs = np.array(
            [x[self._stage_offset(k) + self.nx : self._stage_offset(k + 1)] for k in range(h)]
        )
        lam = inputs[:, d.nv + d.n_joints :].reshape(h, d.n_contacts, self.nf)
        force = np.zeros((h, d.n_contacts, 3))
        force[:, :, list(self.force_axes)] = lam
        iters = stats.get("iter_count", stats.get("iterations", {}).get("obj", [0]))
        if not isinstance(iters, int | np.integer):
            iters = len(iters) - 1 if hasattr(iters, "__len__") else -1
        max_iter = int(self.solver_options.get(f"{self.solver_name}.max_iter", MAX_ITER))
        success, status = solve_status(self.solver_name, stats, int(iters), max_iter, viol)
        return WBSolution(
            qpos=states[:, : d.nq],
            qvel=states[:, d.nq :],
            qacc=inputs[:, : d.nv],
            tau_nm=inputs[:, d.nv : d.nv + d.n_joints],
            force_world_n=force,
            cost=float(res["f"]),
            success=success,
            status=status,
            iterations=int(iters),
            solve_time_s=solve_time,
            constraint_violation=viol,
            solver=self.solver_name,
            x_opt=x,
            lam_g=np.array(res["lam_g"]).ravel(),
            lam_x=np.array(res["lam_x"]).ravel(),
        )
