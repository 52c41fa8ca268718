"""Structure-exploiting solvers on the KD controller's own QPs (issue 47, step 2).

Run::

    .venv/bin/python benchmarks/kd_qp_structured.py      # ~2 min, 2 cores

1. Recording: ``kd`` walks ``humanoid3d`` on ``flat`` at 0.75 m/s for ``--seconds``; every
   CMPC QP it builds is kept (the controller itself solves with its own PIQP).
2. Each QP is also written in the stage-wise form of an optimal-control QP, as HPIPM and
   FATROP take it through CasADi's ``conic`` interface: state ``s_k = [x_k (12), dp_c,k
   (3), dp_f,k (6)]`` (the foot positions become states), input ``u_k = [df_k (6),
   dtau_k (6), w_k (6)]`` with ``dp_f,k+1 = dp_f,k + w_k``, so a foot tie row of the
   sparse form becomes a box on ``w_k``; ``x_0`` and ``dp_c,0`` are boxes with equal
   bounds; per stage the wrench and separation rows are the general constraints. Same
   cost, so the same minimiser (411 variables, N = 10, nx = 21, nu = 18).
3. Each variant solves every QP; time per QP is the solver call alone (the sparse
   form's conversion to the stage-wise one is not counted: a backend would assemble the
   stage-wise form directly). Accuracy is against the controller's PIQP solution.

Writes ``benchmarks/results/kd_qp_structured.md``.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
import scipy.sparse as sp

from common import add_out_option, command_line, machine_info, write_report

NXS, NU = 21, 18  # stage-wise state and input sizes


def record(seconds: float) -> list[Any]:
    """The QPs (``QPProblem``) that ``kd`` builds while walking ``seconds`` on flat."""
    from gaitnet_mpc.mpc.implicit_kd import KDSubproblem
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.scenario import build_episode, make_scenario

    scenario = make_scenario(controller="kd", course="flat", vx_mps=0.75, duration_s=seconds)
    episode = build_episode(scenario)
    sub: KDSubproblem = episode.controller.mpc.subproblem
    problems: list[Any] = []
    build = sub.build

    def keep(iterate: Any, inputs: Any) -> Any:
        problems.append(build(iterate, inputs))
        return problems[-1]

    sub.build = keep  # type: ignore[method-assign]
    run_episode(episode.sim, episode.controller, scenario.command, seconds, progress=False)
    return problems


class StageWise:
    """The map from the sparse CMPC layout to the stage-wise one (module docstring)."""

    def __init__(self, horizon: int, n_wrench_rows: int) -> None:
        from gaitnet_mpc.mpc.kd_layout import KDLayout

        h = self.h = horizon
        self.mw = n_wrench_rows
        lay = KDLayout(h)
        self.n = (NXS + NU) * h + NXS
        stage = (NXS + NU) * np.arange(h + 1)
        y = np.full(lay.n, -1)
        for k in range(h + 1):
            y[lay.col_x[k]] = stage[k] + np.arange(12)
            y[lay.col_pc[k]] = stage[k] + 12 + np.arange(3)
        for k in range(h):
            y[lay.col_pf[k].ravel()] = stage[k] + 15 + np.arange(6)
            y[lay.col_f[k].ravel()] = stage[k] + NXS + np.arange(6)
            y[lay.col_tau[k].ravel()] = stage[k] + NXS + 6 + np.arange(6)
        self.y_of_z = y
        self.col_w = stage[:h, None] + NXS + 12 + np.arange(6)  # (h, 6)
        self.T = sp.csc_matrix((np.ones(lay.n), (np.arange(lay.n), y)), shape=(lay.n, self.n))
        foot_rows = []  # dp_f,k + w_k - dp_f,k+1 = 0, as rows of the stage-wise vector
        for k in range(h):
            r = np.zeros((6, self.n))
            r[np.arange(6), stage[k] + 15 + np.arange(6)] = 1.0
            r[np.arange(6), self.col_w[k]] = 1.0
            r[np.arange(6), stage[k + 1] + 15 + np.arange(6)] = -1.0
            foot_rows.append(r)
        self.foot_rows = foot_rows

    def convert(self, p: Any) -> tuple[np.ndarray, ...]:
        """(diag H, g, A dense, lba, uba, lbx, ubx) of the stage-wise QP of ``p``."""
        h, mw, T = self.h, self.mw, self.T
        H = (T.T @ p.P @ T).diagonal()
        g = T.T @ p.q
        lbx, ubx = np.full(self.n, -np.inf), np.full(self.n, np.inf)
        lbx[self.y_of_z], ubx[self.y_of_z] = p.lb, p.ub
        a_eq = p.A_eq.toarray() @ T.toarray()
        a_in = p.A.toarray() @ T.toarray()
        for r in range(15):  # x_0 = measurement, dp_c,0 = 0: equal bounds
            j = int(np.flatnonzero(a_eq[r])[0])
            lbx[j] = ubx[j] = p.b_eq[r] / a_eq[r, j]
        tie0, sep0 = 2 * h * mw, 2 * h * mw + 6 * (h - 1)
        rows, lo, hi = [], [], []
        for k in range(h):
            dyn = slice(15 + 15 * k, 30 + 15 * k)  # gap rows: A s_k + B u_k - s_k+1 = c
            rows += [-a_eq[dyn], self.foot_rows[k]]
            lo += [-p.b_eq[dyn], np.zeros(6)]
            hi += [-p.b_eq[dyn], np.zeros(6)]
            wr, sep = slice(2 * mw * k, 2 * mw * (k + 1)), slice(sep0 + k, sep0 + k + 1)
            rows += [a_in[wr], a_in[sep]]
            lo += [p.l[wr], p.l[sep]]
            hi += [p.u[wr], p.u[sep]]
            tie = slice(tie0 + 6 * k, tie0 + 6 * (k + 1))
            lbx[self.col_w[k]] = p.l[tie] if k < h - 1 else -1e3
            ubx[self.col_w[k]] = p.u[tie] if k < h - 1 else 1e3
        return H, g, np.vstack(rows), np.concatenate(lo), np.concatenate(hi), lbx, ubx

    def casadi_solver(self, plugin: str, options: dict[str, Any], a_sp: Any) -> Any:
        """CasADi's ``conic`` with ``plugin`` on this form, ``a_sp`` the constraint rows'
        sparsity."""
        import casadi as ca

        h = self.h
        structure = {
            "N": h,
            "nx": [NXS] * (h + 1),
            "nu": [NU] * h + [0],
            "ng": [2 * self.mw + 1] * h + [0],
        }
        h_sp = ca.Sparsity.diag(self.n)
        return ca.conic(
            "qp", plugin, {"h": h_sp, "a": a_sp}, {**structure, **options, "error_on_fail": False}
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=1.5)
    parser.add_argument("--max-qps", type=int, default=300)
    add_out_option(parser, "kd_qp_structured.md")
    args = parser.parse_args()
    import casadi as ca
    import piqp

    from gaitnet_mpc.mpc.kd_config import KDConfig
    from gaitnet_mpc.mpc.qp import make_workspace

    problems = record(args.seconds)[: args.max_qps]
    cfg = KDConfig()
    mw = (problems[0].A.shape[0] - 6 * (cfg.horizon - 1) - cfg.horizon) // (2 * cfg.horizon)
    sw = StageWise(cfg.horizon, mw)
    converted = [sw.convert(p) for p in problems]
    pattern = np.zeros_like(converted[0][2], dtype=bool)
    for c in converted:
        pattern |= c[2] != 0.0
    base = cfg.qp_workspace_options()
    piqp_variants = {
        "piqp (controller's settings)": base,
        "piqp sparse_multistage KKT": {**base, "kkt_solver": piqp.KKTSolver.sparse_multistage},
        "piqp PIQP's default tolerances": {},
    }
    casadi_variants = {
        "hpipm speed (CasADi conic)": ("hpipm", {"hpipm": {"mode": "speed"}}),
        "hpipm speed, 50 iterations": ("hpipm", {"hpipm": {"mode": "speed", "iter_max": 50}}),
        "hpipm balance": ("hpipm", {"hpipm": {"mode": "balance"}}),
        "hpipm speed, infinite bounds as 1e4": ("hpipm", {"hpipm": {"mode": "speed"}, "inf": 1e4}),
        "fatrop (CasADi conic)": ("fatrop", {"structure_detection": "manual"}),
    }
    workspaces = {name: make_workspace("piqp", **opts) for name, opts in piqp_variants.items()}
    h_sp = ca.Sparsity.diag(sw.n)
    a_sp = ca.DM(sp.csc_matrix(pattern.astype(float))).sparsity()
    solvers = {name: sw.casadi_solver(*v, a_sp=a_sp) for name, v in casadi_variants.items()}
    rows: dict[str, list[tuple[float, int, float, bool]]] = {n: [] for n in [*workspaces, *solvers]}
    for p, (H, g, A, lba, uba, lbx, ubx) in zip(problems, converted, strict=True):
        reference = None  # interleaved: each QP by every variant before the next QP
        for name, ws in workspaces.items():
            sol = ws.solve(p)
            assert sol.x is not None
            reference = sol.x if reference is None else reference
            err = float(np.abs(sol.x - reference).max())
            rows[name].append((sol.solve_time_s, int(sol.iterations or 0), err, sol.found))
        a_val = ca.DM(a_sp, A.T[pattern.T])  # column-major values on the fixed pattern
        for name, solver in solvers.items():
            t0 = time.perf_counter()
            out = solver(h=ca.DM(h_sp, H), g=g, a=a_val, lba=lba, uba=uba, lbx=lbx, ubx=ubx)
            dt = time.perf_counter() - t0
            stats = solver.stats()
            x = np.asarray(out["x"]).ravel()[sw.y_of_z]
            err = float(np.abs(x - reference).max())
            rows[name].append((dt, int(stats.get("iter_count", -1)), err, bool(stats["success"])))
    lines = [
        "# KD controller QPs: structure-exploiting solvers (issue 47, step 2)",
        "",
        machine_info(("numpy", "scipy", "piqp", "casadi")),
        "",
        f"{len(problems)} CMPC QPs recorded from `kd`, humanoid3d, flat, 0.75 m/s, "
        f"{args.seconds:g} s (sparse form: n = {problems[0].n}; stage-wise form: "
        f"n = {sw.n}, N = {cfg.horizon}, nx = {NXS}, nu = {NU}, ng = {2 * mw + 1}). Time "
        "per QP: the solver call; PIQP's includes the project's workspace (update and "
        "conversion), CasADi's excludes the conversion to the stage-wise form. Accuracy: "
        "max |x - x_PIQP| over the sparse form's variables. The machine is shared: compare "
        "rows of one run.",
        "",
        "| variant | median ms/QP | p90 ms/QP | iterations median (max) | reported success "
        "| median max abs dx | worst max abs dx |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, r in rows.items():
        t = np.array([x[0] for x in r]) * 1e3
        it = np.array([x[1] for x in r])
        err = np.array([x[2] for x in r])
        ok = sum(x[3] for x in r)
        lines.append(
            f"| {name} | {np.median(t):.2f} | {np.percentile(t, 90):.2f} | "
            f"{np.median(it):.0f} ({it.max()}) | {ok}/{len(r)} | {np.median(err):.1e} | "
            f"{err.max():.1e} |"
        )
    lines += ["", f"Command: `{command_line()}`", ""]
    write_report(args.out, "\n".join(lines))


if __name__ == "__main__":
    main()
