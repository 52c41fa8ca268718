"""CD-SQP: the centroidal-dynamics MPC solved by CasADi's ``sqpmethod`` (Table II baseline).

The problem is :class:`~gaitnet_mpc.mpc.cd_problem.CDProblem` (eq. 10 with eq. 20,
eq. 18's cost, eqs. 21-24's constraints, fixed ``dt``), transcribed once per horizon and
contact-model size as a CasADi NLP with the per-problem data as parameters, and solved
as the paper did: ``sqpmethod`` with qpOASES for the QP sub-problems (Sec. V-A). Every
SQP iteration solves one QP, so "QPs per solve" is ``sqpmethod``'s iteration count.

Variables per stage ``k = 0 .. h-1`` (``30 h`` in all)::

    w_k = [s_k+1 (12: p_c, l_G, H_ang, k_G), f (2x3), tau (2x3), p_f (2x3)]

Termination (Table X's step norms, :mod:`~gaitnet_mpc.table2.sqp_common`, shared with the
joint-space baselines): ``sqpmethod`` has no step-norm test per variable
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

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.mpc.cd_nlp import CDSymbols, cd_bounds, cd_terms
from gaitnet_mpc.mpc.cd_problem import NS_CD, NW_CD, CDProblem, CDSolution, cd_columns
from gaitnet_mpc.table2.sqp_common import SQPConfig, StepTest, build_sqp, run_sqp

NW = NW_CD  # variables per stage: state 12, f 6, tau 6, p_f 6


class CDSQPConfig(SQPConfig):
    """Settings of the CD-SQP baseline (:class:`~gaitnet_mpc.table2.sqp_common.SQPConfig`)."""


#: Step-test groups of CD-SQP (Table X): CoM and foot positions, forces, moments.
GROUPS = ("position", "force", "moment")


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


class CDSQP:
    """CD MPC by ``sqpmethod`` (module docstring). One NLP per ``(h, mw, separation)``;
    a fresh ``nlpsol`` of it per problem (:meth:`prepare`), so that no QP solver state
    (qpOASES' hot-start working set) carries over from one problem to the next."""

    def __init__(self, config: CDSQPConfig | None = None) -> None:
        self.config = config or CDSQPConfig()
        self._nlps: dict[tuple[int, int, bool, float, float], tuple[dict[str, Any], Any]] = {}
        self._prepared: tuple[int, Any, StepTest] | None = None

    @staticmethod
    def n_variables(horizon: int) -> int:
        """``30 h`` (module docstring)."""
        return NW * horizon

    def _nlp(self, p: CDProblem) -> tuple[dict[str, Any], Any]:
        """The symbolic NLP of ``p``'s sizes and its step-test measure (cached)."""
        c = p.config
        h, mw = p.horizon, p.wrench_c.shape[2]
        sep = p.sep_axis is not None
        key = (h, mw, sep, c.mass_kg, c.gravity_mps2)
        if key not in self._nlps:
            self._nlps[key] = self._transcribe(p, h, mw, sep)
        return self._nlps[key]

    def _transcribe(self, p: CDProblem, h: int, mw: int, sep: bool) -> tuple[dict[str, Any], Any]:
        w = ca.SX.sym("w", NW * h)
        sym = CDSymbols(
            s0=ca.SX.sym("s0", NS_CD),
            dts=ca.SX.sym("dts", h),
            cw=ca.SX.sym("cw", h * 2 * mw * 6),
            h_ref=ca.SX.sym("h_ref", h * 6),
            H_ref=ca.SX.sym("H_ref", h * 6),
            pc_ref=ca.SX.sym("pc_ref", h * 3),
            pf_ref=ca.SX.sym("pf_ref", h * 6),
            axis=ca.SX.sym("axis", h * 2 if sep else 0),
        )
        params = ca.vertcat(
            sym.s0, sym.dts, sym.cw, sym.h_ref, sym.H_ref, sym.pc_ref, sym.pf_ref, sym.axis
        )
        terms = cd_terms(p.config, w, sym, h, mw, sep)
        cols = cd_columns(h)
        pos = np.concatenate([cols["state"][:, :3].ravel(), cols["pf"].ravel()])
        f_cols, tau_cols = cols["f"].ravel(), cols["tau"].ravel()

        def measure(x: np.ndarray) -> dict[str, np.ndarray]:
            return {"position": x[pos], "force": x[f_cols], "moment": x[tau_cols]}

        return {"x": w, "p": params, "f": terms.cost, "g": terms.constraints()}, measure

    def _arguments(self, p: CDProblem) -> dict[str, Any]:
        """Initial guess (the common ``u^0``), parameters and bounds of one problem."""
        h = p.horizon
        cols = cd_columns(h)
        x0 = np.zeros(NW * h)
        x0[cols["state"]] = p.guess_states()
        x0[cols["f"]] = p.guess.f.reshape(h, 6)
        x0[cols["tau"]] = p.guess.tau.reshape(h, 6)
        x0[cols["pf"]] = p.guess.p_foot.reshape(h, 6)
        lbx, ubx, lbg, ubg = cd_bounds(
            p.contact, p.pf_lb_m, p.pf_ub_m, p.wrench_lo, p.wrench_hi, p.tie_free,
            p.sep_min_m if p.sep_axis is not None else None,
        )  # fmt: skip
        # cd_terms reads each (mw, 6) block as reshape(v, 6, mw).T (column-major): row-major C
        cw = p.wrench_c.reshape(-1)
        params = np.concatenate(
            [p.s0, p.dts_s, cw, p.h_ref[1:].ravel(), p.H_ref[1:].ravel(),
             p.p_com_ref[1:].ravel(), p.p_foot_ref.ravel(),
             p.sep_axis.ravel() if p.sep_axis is not None else np.zeros(0)]
        )  # fmt: skip
        return {"x0": x0, "p": params, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}

    def prepare(self, p: CDProblem) -> None:
        """A fresh solver for ``p`` (about 0.05 s; not part of the timed solve)."""
        nlp, measure = self._nlp(p)
        self._prepared = (id(p), *build_sqp("cd_sqp", nlp, self.config, measure))

    def solve(self, p: CDProblem) -> CDSQPResult:
        """Solve ``p`` cold from its ``guess`` (module docstring). A QP plugin that fails
        hard (CasADi raises) gives a result with ``converged=False``, the guess as plan,
        ``max_iter`` QPs and a NaN cost."""
        from gaitnet_mpc.mpc.cd_problem import cd_cost

        if self._prepared is None or self._prepared[0] != id(p):
            self.prepare(p)
        assert self._prepared is not None
        _, solver, test = self._prepared
        self._prepared = None  # used once: the next problem gets a fresh solver
        run = run_sqp(solver, test, self.config, GROUPS, self._arguments(p))
        if run.status.startswith("error"):
            guess = CDSolution(p.guess_states(), p.guess.f, p.guess.tau, p.guess.p_foot)
            return CDSQPResult(guess, run.n_qps, False, run.solve_time_s, run.status, math.nan)
        h = p.horizon
        z = run.x.reshape(h, NW)
        sol = CDSolution(
            states=z[:, :NS_CD].copy(),
            f=z[:, 12:18].reshape(h, 2, 3).copy(),
            tau=z[:, 18:24].reshape(h, 2, 3).copy(),
            p_foot=z[:, 24:30].reshape(h, 2, 3).copy(),
        )
        return CDSQPResult(
            solution=sol,
            n_qps=run.n_qps,
            converged=run.converged,
            solve_time_s=run.solve_time_s,
            status=run.status,
            cost=cd_cost(p, sol),
        )


__all__ = ["CDSQP", "GROUPS", "CDSQPConfig", "CDSQPResult"]
