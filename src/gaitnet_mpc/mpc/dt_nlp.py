"""The paper's baseline 2 of Fig. 6: the step's dt as a decision variable of the MPC.

At each step start the centroidal-dynamics problem of Algorithm 1
(:mod:`~gaitnet_mpc.mpc.cd_problem`: eq. 10 with eq. 20, eq. 18's cost, eqs. 21-24) is
solved with the sampling time ``dt`` of the horizon as one more variable, bounded by the
robot's dt bounds (Table V's [0.03, 0.06] s for the planar biped). Every stage lasts
``r_k dt`` (``r_k`` the stage's share of a full stage: a partial stage 0 stays partial), so
the dynamics hold the products ``dt l_G``, ``dt (f + m g)``, ``dt k_G`` and ``dt (p_f -
p_c) x f``: the problem is a nonlinear program, solved by IPOPT (CasADi), warm-started
from Algorithm 1's ``u^0`` (footholds of the previous plan) and the previous step's dt.

The references of eq. 18 depend on dt too (the CoM path and the momenta are laid along
the stage times, the foot references are Raibert footholds of the step duration). They
are built, as Algorithm 1 builds them (``f_ref`` and its first sub-problem), at both dt
bounds, and the NLP's references are their linear interpolation in dt; for a constant
velocity command the CoM path is linear in dt, so this is exact there and first order
for the rest.

The NLP's dt is the policy's output (:class:`~gaitnet_mpc.mpc.sequential.DtPolicy`): the
implicit kino-dynamic MPC then plans the step with it, as with a fixed dt, Gait-Net or the
grid-search oracle, so the four differ only in how the dt is chosen. A solve that IPOPT
does not report as solved keeps the previous step's dt (a fallback, counted).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.dt_policy import NOMINAL_DT_S, PAPER_DT_BOUNDS_S
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.cd_nlp import CDSymbols, cd_bounds, cd_terms
from gaitnet_mpc.mpc.cd_problem import NS_CD, NW_CD, CDProblem, cd_columns, centroidal_problem
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.mpc.sequential import KDProblem, SequentialKDMPC

#: IPOPT return statuses taken as a solution.
SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


@dataclass(frozen=True)
class NLPDtConfig:
    """Settings of :class:`NLPDt`.

    Attributes:
        bounds_s: (min, max) of the dt variable [s].
        nominal_dt_s: dt of the first step's warm start and the fallback before any
            solution [s].
        max_iter: IPOPT iteration cap.
        tol: IPOPT's convergence tolerance (scaled NLP error).
    """

    bounds_s: tuple[float, float] = PAPER_DT_BOUNDS_S[True]
    nominal_dt_s: float = NOMINAL_DT_S
    max_iter: int = bounded(200, "[1, 10000]", "an integer", "IPOPT iterations")
    tol: float = bounded(1e-6, "(0, 1]", "a tolerance", "IPOPT's scaled NLP error")

    def __post_init__(self) -> None:
        lo, hi = self.bounds_s
        if not (0 < lo < hi and math.isfinite(hi)):
            raise ConfigError("bounds_s", self.bounds_s, "(min, max) with 0 < min < max [s]")
        check_ranges(self)


@dataclass
class NLPDecision:
    """One step start: the NLP's dt, IPOPT's status and effort, and a fallback reason."""

    t_s: float
    dt_s: float = math.nan
    status: str = ""
    iterations: int = 0
    solve_ms: float = math.nan
    cost: float = math.nan
    fallback: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "t_s": round(self.t_s, 4),
            "dts_s": [round(self.dt_s, 5)],
            "status": self.status,
            "iterations": self.iterations,
            "solve_ms": round(self.solve_ms, 2),
            "cost": None if math.isnan(self.cost) else round(self.cost, 4),
            "fallback": self.fallback,
        }


class NLPDt:
    """The optimised-dt policy (module docstring); :meth:`attach` gives it the solver
    whose first sub-problem it reads."""

    def __init__(self, config: NLPDtConfig | None = None) -> None:
        self.config = config or NLPDtConfig()
        self.decisions: list[NLPDecision] = []
        self._solver: SequentialKDMPC | None = None
        self._problem: KDProblem | None = None
        self._nlps: dict[tuple[int, int, bool], Any] = {}  # CasADi solvers by size

    def attach(self, mpc: SequentialKDMPC) -> None:
        """Read the problems with a solver of ``mpc``'s robot and settings (a separate
        instance, so the probes leave the caller's workspaces alone)."""
        self._solver = SequentialKDMPC(mpc.robot, mpc.config)

    @property
    def nominal_dt_s(self) -> float:
        return self.config.nominal_dt_s

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        if problem is not self._problem:  # a new step start: solve once
            self._problem = problem
            self.decisions.append(self._decide(problem))
        return self.decisions[-1].dt_s

    # ------------------------------------------------------------------ the NLP
    def _probe(self, problem: KDProblem, dt_s: float) -> CDProblem:
        """The CD problem of ``problem`` with every stage scaled to ``dt_s``."""
        assert self._solver is not None
        timing = problem.timing
        dt0 = float(timing.stage_lengths_s[0])
        dts = np.asarray(timing.dts_s, dtype=float)
        scaled = replace(problem, timing=timing.with_dts(dts * (dt_s / dt0)), choose_dt=False)
        return centroidal_problem(self._solver, scaled)

    def _nlp_solver(self, p: CDProblem) -> Any:
        h, mw = p.horizon, p.wrench_c.shape[2]
        sep = p.sep_axis is not None
        key = (h, mw, sep)
        if key not in self._nlps:
            self._nlps[key] = self._transcribe(p, h, mw, sep)
        return self._nlps[key]

    def _transcribe(self, p: CDProblem, h: int, mw: int, sep: bool) -> Any:
        lo, hi = self.config.bounds_s
        w = ca.SX.sym("w", NW_CD * h)
        dt = ca.SX.sym("dt")
        a = (dt - lo) / (hi - lo)  # 0 at the lower bound, 1 at the upper
        s0 = ca.SX.sym("s0", NS_CD)
        ratio = ca.SX.sym("ratio", h)
        cw = ca.SX.sym("cw", h * 2 * mw * 6)
        axis = ca.SX.sym("axis", h * 2 if sep else 0)
        refs = {n: (ca.SX.sym(f"{n}_lo", k * h), ca.SX.sym(f"{n}_hi", k * h))
                for n, k in (("h_ref", 6), ("H_ref", 6), ("pc_ref", 3), ("pf_ref", 6))}  # fmt: skip
        at = {n: r_lo + a * (r_hi - r_lo) for n, (r_lo, r_hi) in refs.items()}
        sym = CDSymbols(
            s0=s0, dts=ratio * dt, cw=cw, h_ref=at["h_ref"], H_ref=at["H_ref"],
            pc_ref=at["pc_ref"], pf_ref=at["pf_ref"], axis=axis,
        )  # fmt: skip
        terms = cd_terms(p.config, w, sym, h, mw, sep)
        params = ca.vertcat(s0, ratio, cw, axis, *(s for pair in refs.values() for s in pair))
        nlp = {"x": ca.vertcat(w, dt), "p": params, "f": terms.cost, "g": terms.constraints()}
        opts: dict[str, Any] = {
            "print_time": False,
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "ipopt.max_iter": self.config.max_iter,
            "ipopt.tol": self.config.tol,
        }
        return ca.nlpsol("dt_nlp", "ipopt", nlp, opts)

    def _decide(self, problem: KDProblem) -> NLPDecision:
        if self._solver is None:
            raise ConfigError("NLPDt", "not attached", "attach(mpc) before the first solve")
        t_s = problem.state.state.t_s if problem.state is not None else math.nan
        d = NLPDecision(t_s=t_s)
        previous = self.decisions[-1].dt_s if self.decisions else self.config.nominal_dt_s
        lo, hi = self.config.bounds_s
        p_lo, p_hi = self._probe(problem, lo), self._probe(problem, hi)
        solver = self._nlp_solver(p_lo)
        h = p_lo.horizon
        a0 = (min(max(previous, lo), hi) - lo) / (hi - lo)
        cols = cd_columns(h)
        x0 = np.zeros(NW_CD * h)
        x0[cols["state"]] = (1 - a0) * p_lo.guess_states() + a0 * p_hi.guess_states()
        x0[cols["f"]] = p_lo.guess.f.reshape(h, 6)
        x0[cols["tau"]] = p_lo.guess.tau.reshape(h, 6)
        x0[cols["pf"]] = ((1 - a0) * p_lo.guess.p_foot + a0 * p_hi.guess.p_foot).reshape(h, 6)
        lbx, ubx, lbg, ubg = cd_bounds(
            p_lo.contact, p_lo.pf_lb_m, p_lo.pf_ub_m, p_lo.wrench_lo, p_lo.wrench_hi,
            p_lo.tie_free, p_lo.sep_min_m if p_lo.sep_axis is not None else None,
        )  # fmt: skip
        # the box of the foot positions is the union over both probes (a foot height
        # from the reference may differ by a hair between them)
        cpf = cols["pf"]
        lbx[cpf] = np.minimum(p_lo.pf_lb_m, p_hi.pf_lb_m).reshape(h, 6)
        ubx[cpf] = np.maximum(p_lo.pf_ub_m, p_hi.pf_ub_m).reshape(h, 6)
        ratio = p_lo.dts_s / lo
        params = np.concatenate(
            [p_lo.s0, ratio, p_lo.wrench_c.reshape(-1),
             p_lo.sep_axis.ravel() if p_lo.sep_axis is not None else np.zeros(0),
             p_lo.h_ref[1:].ravel(), p_hi.h_ref[1:].ravel(),
             p_lo.H_ref[1:].ravel(), p_hi.H_ref[1:].ravel(),
             p_lo.p_com_ref[1:].ravel(), p_hi.p_com_ref[1:].ravel(),
             p_lo.p_foot_ref.ravel(), p_hi.p_foot_ref.ravel()]
        )  # fmt: skip
        t0 = time.perf_counter()
        sol = solver(
            x0=np.append(x0, lo + a0 * (hi - lo)),
            p=params,
            lbx=np.append(lbx, lo),
            ubx=np.append(ubx, hi),
            lbg=lbg,
            ubg=ubg,
        )
        d.solve_ms = 1e3 * (time.perf_counter() - t0)
        stats = solver.stats()
        d.status = str(stats.get("return_status", ""))
        d.iterations = int(stats.get("iter_count", 0))
        dt_opt = float(np.asarray(sol["x"]).ravel()[-1])
        if d.status in SOLVED and math.isfinite(dt_opt):
            d.dt_s = min(max(dt_opt, lo), hi)
            d.cost = float(sol["f"])
        else:
            d.dt_s, d.fallback = previous, "not solved"
        return d

    def summary(self) -> dict[str, Any]:
        """``summary.json``'s ``dt_policy`` block."""
        ms = [d.solve_ms for d in self.decisions]
        return {
            "policy": "optdt",
            "decisions": len(self.decisions),
            "fallbacks": {"not solved": sum(d.fallback is not None for d in self.decisions)},
            "dt_bounds_s": list(self.config.bounds_s),
            "solve_ms_median": float(np.median(ms)) if ms else None,
            "steps": [d.to_dict() for d in self.decisions],
        }


__all__ = ["SOLVED", "NLPDecision", "NLPDt", "NLPDtConfig"]
