"""CD-SQP: the centroidal-dynamics MPC solved by CasADi's ``sqpmethod`` (Table II baseline).

The problem is :class:`~gaitnet_mpc.table2.cd_problem.CDProblem` (eq. 10 with eq. 20,
eq. 18's cost, eqs. 21-24's constraints, fixed ``dt``), transcribed once per horizon and
contact-model size as a CasADi NLP with the per-problem data as parameters, and solved
as the paper did: ``sqpmethod`` with qpOASES for the QP sub-problems (Sec. V-A). Every
SQP iteration solves one QP, so "QPs per solve" is ``sqpmethod``'s iteration count.

Variables per stage ``k = 0 .. h-1`` (``30 h`` in all)::

    w_k = [s_k+1 (12: p_c, l_G, H_ang, k_G), f (2x3), tau (2x3), p_f (2x3)]

Termination (Table X's step norms): ``sqpmethod`` has no step-norm test per variable
group, so its own tests are switched off (``tol_pr = tol_du = 1e-14``, which no iterate
reaches) and an ``iteration_callback`` stops it at the first iterate whose change from the
previous one is within :class:`~gaitnet_mpc.mpc.kd_iterate.KDTolerances`: CoM and foot
positions ``position_m``, forces ``force_n``, moments ``moment_nm``, the very test
Algorithm 1 applies to its search directions. CasADi then reports "User_Requested_Stop";
that counts as converged. With the default line search (``max_iter_ls`` > 0) the change is
``alpha dx``; ``full_steps=True`` (``max_iter_ls = 0``) makes it the QP step itself, as
in Algorithm 1. The Hessian is the exact Lagrangian Hessian (the bilinear torque makes it
indefinite), convexified by CasADi's ``convexify_strategy="regularize"``.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.kd_iterate import KDTolerances
from gaitnet_mpc.table2.cd_problem import NS_CD, CDProblem, CDSolution

NW = NS_CD + 18  # variables per stage: state 12, f 6, tau 6, p_f 6


@contextlib.contextmanager
def _quiet_c_stdout() -> Iterator[None]:
    """Silence C-level stdout (qpOASES prints a licence banner when set up)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@dataclass(frozen=True)
class CDSQPConfig:
    """Settings of the CD-SQP baseline.

    Attributes:
        qpsol: CasADi conic plugin of the QP sub-problems (paper: ``"qpoases"``).
        max_iter: SQP iteration cap (Algorithm 1's ``j_max``).
        tolerances: Table X step norms (module docstring).
        full_steps: no line search (``max_iter_ls = 0``).
        convexify: CasADi ``convexify_strategy`` of the exact Hessian (None: none).
        qpsol_options: extra options of the QP plugin (over the quiet defaults).
    """

    qpsol: str = "qpoases"
    max_iter: int = 50
    tolerances: KDTolerances = field(default_factory=KDTolerances)
    full_steps: bool = False
    convexify: str | None = None
    qpsol_options: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        if not ca.has_conic(self.qpsol):
            raise ConfigError("qpsol", self.qpsol, "a CasADi conic plugin (casadi.has_conic)")
        if not isinstance(self.max_iter, int) or self.max_iter < 1:
            raise ConfigError("max_iter", self.max_iter, "an integer >= 1")


@dataclass(frozen=True)
class CDSQPResult:
    """Outcome of one CD-SQP solve.

    Attributes:
        solution: the last iterate; n_qps: SQP iterations (one QP each);
        converged: stopped by the Table X step test; solve_time_s: wall time of the
        ``nlpsol`` call [s]; status: CasADi's return status; cost: eq. 18 at the plan.
    """

    solution: CDSolution
    n_qps: int
    converged: bool
    solve_time_s: float
    status: str
    cost: float


class _StepTest(ca.Callback):
    """``iteration_callback``: stop once the iterate's change is within the tolerances."""

    def __init__(self, n_x: int, n_g: int, n_p: int, groups: dict[str, np.ndarray]) -> None:
        ca.Callback.__init__(self)
        self._sizes = {"x": n_x, "f": 1, "g": n_g, "lam_x": n_x, "lam_g": n_g, "lam_p": n_p}
        self._groups = groups
        self.tolerances = KDTolerances()
        self.previous: np.ndarray | None = None
        self.converged = False
        self.construct("cd_sqp_step_test", {})

    def reset(self, tolerances: KDTolerances) -> None:
        self.tolerances = tolerances
        self.previous = None
        self.converged = False

    def get_n_in(self) -> int:
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> Any:
        n = self._sizes.get(str(ca.nlpsol_out(i)), 0)
        return ca.Sparsity.dense(n, 1) if n else ca.Sparsity(0, 0)

    def eval(self, args: Sequence[Any]) -> list[Any]:  # type: ignore[override]
        x = np.asarray(args[0], dtype=float).ravel()
        prev, self.previous = self.previous, x
        if prev is None:
            return [0]
        dx = np.abs(x - prev)
        tol = self.tolerances
        self.converged = bool(
            dx[self._groups["position"]].max() <= tol.position_m
            and dx[self._groups["force"]].max() <= tol.force_n
            and dx[self._groups["moment"]].max() <= tol.moment_nm
        )
        return [1 if self.converged else 0]


class CDSQP:
    """CD MPC by ``sqpmethod`` (module docstring). One NLP per ``(h, mw, separation)``."""

    def __init__(self, config: CDSQPConfig | None = None) -> None:
        self.config = config or CDSQPConfig()
        self._solvers: dict[tuple[int, int, bool, float, float], tuple[Any, _StepTest]] = {}

    @staticmethod
    def n_variables(horizon: int) -> int:
        """``30 h`` (module docstring)."""
        return NW * horizon

    def _columns(self, h: int) -> dict[str, np.ndarray]:
        base = NW * np.arange(h)[:, None]
        return {
            "state": base + np.arange(NS_CD),
            "f": base + NS_CD + np.arange(6),
            "tau": base + NS_CD + 6 + np.arange(6),
            "pf": base + NS_CD + 12 + np.arange(6),
        }

    def _build(self, p: CDProblem) -> tuple[Any, _StepTest]:
        c = p.config
        h, mw = p.horizon, p.wrench_c.shape[2]
        sep = p.sep_axis is not None
        key = (h, mw, sep, c.mass_kg, c.gravity_mps2)
        if key in self._solvers:
            return self._solvers[key]
        m = c.mass_kg
        w = ca.SX.sym("w", NW * h)
        s0 = ca.SX.sym("s0", NS_CD)
        dts = ca.SX.sym("dts", h)
        cw = ca.SX.sym("cw", h * 2 * mw * 6)
        h_ref = ca.SX.sym("h_ref", h * 6)
        H_ref = ca.SX.sym("H_ref", h * 6)
        pc_ref = ca.SX.sym("pc_ref", h * 3)
        pf_ref = ca.SX.sym("pf_ref", h * 6)
        axis = ca.SX.sym("axis", h * 2 if sep else 0)
        params = ca.vertcat(s0, dts, cw, h_ref, H_ref, pc_ref, pf_ref, axis)
        g_vec = ca.DM([0.0, 0.0, -c.gravity_mps2])
        wp, wm = np.asarray(c.w_pose), np.asarray(c.w_momentum)
        wpc, wpf = np.asarray(c.w_p_com), np.asarray(c.w_p_foot)
        dyn, wrench, ties, seps = [], [], [], []
        cost = ca.SX(0.0)
        s = s0
        for k in range(h):
            blk = w[NW * k : NW * (k + 1)]
            s_next, f, tau, pf = blk[:12], blk[12:18], blk[18:24], blk[24:30]
            pc, lg, ha, kg = s[:3], s[3:6], s[6:9], s[9:12]
            dt = dts[k]
            torque = ca.SX.zeros(3)
            for i in range(2):
                fi, ti, pi = f[3 * i : 3 * i + 3], tau[3 * i : 3 * i + 3], pf[3 * i : 3 * i + 3]
                torque += ca.cross(pi - pc, fi) + ti
                rows = ca.reshape(cw[(k * 2 + i) * mw * 6 : (k * 2 + i + 1) * mw * 6], 6, mw).T
                wrench.append(ca.mtimes(rows, ca.vertcat(fi, ti)))
            pred = ca.vertcat(
                pc + lg / m * dt, lg + (f[:3] + f[3:] + m * g_vec) * dt, ha + kg * dt,
                kg + torque * dt,
            )  # fmt: skip
            dyn.append(s_next - pred)
            if k + 1 < h:
                ties.append(w[NW * (k + 1) + 24 : NW * (k + 1) + 30] - pf)
            if sep:
                d = pf[0:2] - pf[3:5]
                seps.append(axis[2 * k] * d[0] + axis[2 * k + 1] * d[1])
            # eq. 18 (H_lin = m p_c)
            pc1, lg1, ha1, kg1 = s_next[:3], s_next[3:6], s_next[6:9], s_next[9:12]
            pose = ca.vertcat(m * pc1, ha1) - H_ref[6 * k : 6 * k + 6]
            mom = ca.vertcat(lg1, kg1) - h_ref[6 * k : 6 * k + 6]
            cost += ca.dot(wp * pose, pose) + ca.dot(wm * mom, mom)
            e_pc = pc1 - pc_ref[3 * k : 3 * k + 3]
            e_pf = pf - pf_ref[6 * k : 6 * k + 6]
            cost += ca.dot(wpc * e_pc, e_pc) + ca.dot(np.tile(wpf, 2) * e_pf, e_pf)
            cost += c.w_force * ca.dot(f, f) + c.w_moment * ca.dot(tau, tau)
            s = s_next
        g = ca.vertcat(*dyn, *wrench, *ties, *seps)
        cols = self._columns(h)
        groups = {
            "position": np.concatenate([cols["state"][:, :3].ravel(), cols["pf"].ravel()]),
            "force": cols["f"].ravel(),
            "moment": cols["tau"].ravel(),
        }
        test = _StepTest(w.numel(), g.numel(), params.numel(), groups)
        cfg = self.config
        opts: dict[str, Any] = {
            "qpsol": cfg.qpsol,
            "hessian_approximation": "exact",
            "max_iter": cfg.max_iter,
            "tol_pr": 1e-14,
            "tol_du": 1e-14,
            "min_step_size": 1e-16,
            "iteration_callback": test,
            "print_header": False,
            "print_iteration": False,
            "print_status": False,
            "print_time": False,
            "error_on_fail": False,
        }
        if cfg.qpsol == "qpoases":
            opts["qpsol_options"] = {"printLevel": "none", "error_on_fail": False}
        elif cfg.qpsol == "osqp":
            opts["qpsol_options"] = {"osqp": {"verbose": False}, "error_on_fail": False}
        else:
            opts["qpsol_options"] = {"error_on_fail": False}
        opts["qpsol_options"].update(dict(cfg.qpsol_options))
        if cfg.convexify is not None:
            opts["convexify_strategy"] = cfg.convexify
        if cfg.full_steps:
            opts["max_iter_ls"] = 0
        with _quiet_c_stdout():
            solver = ca.nlpsol(
                "cd_sqp", "sqpmethod", {"x": w, "p": params, "f": cost, "g": g}, opts
            )
        self._solvers[key] = (solver, test)
        return solver, test

    def _arguments(self, p: CDProblem) -> dict[str, Any]:
        """Initial guess (the common ``u^0``), parameters and bounds of one problem."""
        h = p.horizon
        cols = self._columns(h)
        x0 = np.zeros(NW * h)
        x0[cols["state"]] = p.guess_states()
        x0[cols["f"]] = p.guess.f.reshape(h, 6)
        x0[cols["tau"]] = p.guess.tau.reshape(h, 6)
        x0[cols["pf"]] = p.guess.p_foot.reshape(h, 6)
        lbx = np.full(NW * h, -np.inf)
        ubx = np.full(NW * h, np.inf)
        lbx[cols["pf"]] = p.pf_lb_m.reshape(h, 6)
        ubx[cols["pf"]] = p.pf_ub_m.reshape(h, 6)
        # swing (eq. 23, sigma = 0): the wrench is fixed to zero by its box, and the foot's
        # wrench rows are left free (C w = 0 on 10 rows of 6 unknowns is a degenerate
        # equality set that stalls qpOASES; the set of plans is the same)
        swing = ~np.repeat(p.contact, 3, axis=1)  # (h, 6)
        for name in ("f", "tau"):
            lbx[cols[name]] = np.where(swing, 0.0, -np.inf)
            ubx[cols[name]] = np.where(swing, 0.0, np.inf)
        stance_rows = np.repeat(p.contact[:, :, None], p.wrench_lo.shape[2], axis=2)
        w_lo = np.where(stance_rows, p.wrench_lo, -np.inf).ravel()
        w_hi = np.where(stance_rows, p.wrench_hi, np.inf).ravel()
        # _build reads each (mw, 6) block as reshape(v, 6, mw).T (column-major): row-major C
        cw = p.wrench_c.reshape(-1)
        params = np.concatenate(
            [p.s0, p.dts_s, cw, p.h_ref[1:].ravel(), p.H_ref[1:].ravel(),
             p.p_com_ref[1:].ravel(), p.p_foot_ref.ravel(),
             p.sep_axis.ravel() if p.sep_axis is not None else np.zeros(0)]
        )  # fmt: skip
        free = np.repeat(p.tie_free, 3, axis=1)  # (h-1, 6)
        big = 1e3
        lbg = np.concatenate(
            [np.zeros(NS_CD * h), w_lo, np.where(free, -big, 0.0).ravel(),
             p.sep_min_m if p.sep_axis is not None else np.zeros(0)]
        )  # fmt: skip
        ubg = np.concatenate(
            [np.zeros(NS_CD * h), w_hi, np.where(free, big, 0.0).ravel(),
             np.full(h, big) if p.sep_axis is not None else np.zeros(0)]
        )  # fmt: skip
        return {"x0": x0, "p": params, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}

    def prepare(self, p: CDProblem) -> None:
        """Build (and cache) the NLP of ``p``'s sizes; not part of a timed solve."""
        self._build(p)

    def solve(self, p: CDProblem) -> CDSQPResult:
        """Solve ``p`` cold from its ``guess`` (module docstring). A QP plugin that fails
        hard (CasADi raises) gives a result with ``converged=False``, the guess as plan,
        ``max_iter`` QPs and a NaN cost."""
        from gaitnet_mpc.table2.cd_problem import cd_cost

        solver, test = self._build(p)
        args = self._arguments(p)
        test.reset(self.config.tolerances)
        t0 = time.perf_counter()
        try:
            out = solver(**args)
        except RuntimeError as exc:  # a QP plugin that asserts (OSQP on an indefinite H)
            elapsed = time.perf_counter() - t0
            guess = CDSolution(p.guess_states(), p.guess.f, p.guess.tau, p.guess.p_foot)
            status = f"error: {str(exc).splitlines()[-1]}"
            return CDSQPResult(guess, self.config.max_iter, False, elapsed, status, math.nan)
        elapsed = time.perf_counter() - t0
        stats = solver.stats()
        h = p.horizon
        z = np.asarray(out["x"], dtype=float).ravel().reshape(h, NW)
        sol = CDSolution(
            states=z[:, :NS_CD].copy(),
            f=z[:, 12:18].reshape(h, 2, 3).copy(),
            tau=z[:, 18:24].reshape(h, 2, 3).copy(),
            p_foot=z[:, 24:30].reshape(h, 2, 3).copy(),
        )
        return CDSQPResult(
            solution=sol,
            n_qps=int(stats["iter_count"]),
            converged=test.converged,
            solve_time_s=elapsed,
            status=str(stats["return_status"]),
            cost=cd_cost(p, sol),
        )


__all__ = ["CDSQP", "CDSQPConfig", "CDSQPResult"]
