"""AD(3): the CD MPC solved by alternating between three convex sub-problems (Table II).

The only nonconvex term of the centroidal dynamics (eq. 10) is the bilinear torque
``(p_f,i - p_c,k) x f_i``. Fixing one factor makes it linear, so the paper's alternating
direction baseline (after [19], with three directions, "mountain climbing" [44]) cycles
through three QPs on the :class:`~gaitnet_mpc.mpc.cd_problem.CDProblem`, each over
one block of variables plus the states ``s_k = [p_c; l_G; H_ang; k_G]`` (k = 1..h),
which enter the dynamics linearly and so are free in all three:

1. **forces** ``f, tau`` given CoM and footholds: the torque is ``sum_i skew(p̄_f,i -
   c̄_k) f_i + tau_i`` with the lever arm frozen (``c̄``: the CoM path of the last
   CoM sub-problem). Variables ``24 h`` (wrench ``12 h`` + states ``12 h``); constraints:
   dynamics, wrench rows (eqs. 21-23; swing wrench fixed to zero).
2. **CoM** given forces and footholds: torque ``sum_i (p̄_f,i - p_c,k) x f̄_i + tau̅_i``,
   linear in the CoM state. Variables ``12 h`` (the states). With the forces fixed,
   eqs. 10/20 fix the whole state path, so this QP has one feasible point: it re-makes
   the CoM path (and the lever arm ``c̄``) consistent with the forces.
3. **footholds** ``p_f`` given forces and CoM: torque ``sum_i (p_f,i - c̄_k) x f̄_i +
   tau̅_i``. Variables ``18 h`` (foot positions ``6 h`` + states ``12 h``); constraints:
   dynamics, foot ties, eq. 24 box, measured stance foot, separation row.

Each is solved with the project's QP layer (:func:`~gaitnet_mpc.mpc.qp.make_workspace`,
PIQP by default), cold, from the proposed method's ``u^0``. One *round* is the three QPs;
the method stops when a round changes every CoM and foot position by at most
``position_m``, every force by ``force_n`` and every moment by ``moment_nm`` (Table X,
:class:`~gaitnet_mpc.mpc.kd_iterate.KDTolerances`), i.e. the same step test as Algorithm 1
applied to the change over one cycle of the three directions. At such a fixed point the
frozen factors equal the current ones, so the plan satisfies the exact dynamics.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.cd_problem import NS_CD, NW_CD, CDProblem, CDSolution, cd_columns, cd_cost
from gaitnet_mpc.mpc.centroidal_model import skew_batch
from gaitnet_mpc.mpc.kd_iterate import KDTolerances
from gaitnet_mpc.mpc.qp import QPProblem, QPWorkspace, make_workspace

NW = NW_CD  # per stage: state 12, f 6, tau 6, p_f 6 (same layout as CD-SQP)
_FREE_TIE_M = 1e3
SUBPROBLEMS = ("forces", "com", "footholds")


@dataclass(frozen=True)
class AD3Config:
    """Settings of AD(3).

    Attributes:
        qp_backend: QP layer backend of the three sub-problems.
        max_rounds: cap on rounds (three QPs each).
        tolerances: Table X step norms, applied to the change over one round.
    """

    qp_backend: str = "piqp"
    max_rounds: int = 50
    tolerances: KDTolerances = field(default_factory=KDTolerances)

    def __post_init__(self) -> None:
        if not isinstance(self.max_rounds, int) or self.max_rounds < 1:
            raise ConfigError("max_rounds", self.max_rounds, "an integer >= 1")


@dataclass(frozen=True)
class AD3Result:
    """Outcome of one AD(3) solve: the plan, QPs solved (3 per round), whether the round
    test was met, wall time [s] and eq. 18 at the plan."""

    solution: CDSolution
    n_qps: int
    converged: bool
    solve_time_s: float
    cost: float


class AD3:
    """Alternating-direction solver of the CD problem (module docstring)."""

    def __init__(self, config: AD3Config | None = None) -> None:
        self.config = config or AD3Config()
        self._workspaces: dict[str, QPWorkspace] = {
            name: make_workspace(self.config.qp_backend) for name in SUBPROBLEMS
        }

    @staticmethod
    def n_variables(horizon: int) -> dict[str, int]:
        """Variables of each sub-problem: forces ``24 h``, CoM ``12 h``, footholds ``18 h``."""
        return {"forces": 24 * horizon, "com": 12 * horizon, "footholds": 18 * horizon}

    # ------------------------------------------------------------------ pieces
    @staticmethod
    def _cost(p: CDProblem) -> tuple[np.ndarray, np.ndarray]:
        """Diagonal ``W`` and target-weighted ``W t`` of eq. 18 over the full vector
        (``sum W (z - t)^2``; the CoM carries both the pose term ``m p_c`` and its own)."""
        c = p.config
        h = p.horizon
        cols = cd_columns(h)
        m = c.mass_kg
        wp, wm = c.pose_weights, c.momentum_weights
        diag = np.zeros(NW * h)
        wt = np.zeros(NW * h)
        w_pc1, w_pc2 = wp[:3] * m**2, np.asarray(c.w_p_com)
        st = cols["state"]
        diag[st[:, :3]] = w_pc1 + w_pc2
        wt[st[:, :3]] = w_pc1 * p.H_ref[1:, :3] / m + w_pc2 * p.p_com_ref[1:]
        diag[st[:, 3:6]] = wm[:3]
        wt[st[:, 3:6]] = wm[:3] * p.h_ref[1:, :3]
        diag[st[:, 6:9]] = wp[3:]
        wt[st[:, 6:9]] = wp[3:] * p.H_ref[1:, 3:]
        diag[st[:, 9:12]] = wm[3:]
        wt[st[:, 9:12]] = wm[3:] * p.h_ref[1:, 3:]
        diag[cols["f"]] = c.w_force
        diag[cols["tau"]] = c.w_moment
        diag[cols["pf"]] = np.tile(np.asarray(c.w_p_foot), 2)
        wt[cols["pf"]] = np.tile(np.asarray(c.w_p_foot), 2) * p.p_foot_ref.reshape(h, 6)
        return diag, wt

    @staticmethod
    def _dynamics(
        p: CDProblem, mode: str, f: np.ndarray, tau: np.ndarray, p_foot: np.ndarray,
        c_bar: np.ndarray,
    ) -> tuple[sp.csc_matrix, np.ndarray]:  # fmt: skip
        """Eqs. 10/20 as ``A_eq z = b`` over the full vector, with the torque made linear
        for sub-problem ``mode`` (module docstring); fixed values only enter through the
        frozen factor of the torque, everything else stays a column of ``z``."""
        c = p.config
        h, m = p.horizon, c.mass_kg
        cols = cd_columns(h)
        st = cols["state"]
        rows: list[np.ndarray] = []
        cs: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        b = np.zeros(NS_CD * h)
        eye3 = np.arange(3)

        def put(r: np.ndarray, cc: np.ndarray, v: np.ndarray) -> None:
            rr, ccc = np.broadcast_arrays(r[:, None], cc[None, :])
            rows.append(rr.ravel())
            cs.append(ccc.ravel())
            vals.append(np.broadcast_to(v, rr.shape).ravel())

        g = np.array([0.0, 0.0, -c.gravity_mps2])
        skew_f = skew_batch(f)  # (h, 2, 3, 3)
        for k in range(h):
            dt = float(p.dts_s[k])
            r0 = NS_CD * k
            r_pc, r_l, r_ha, r_k = r0 + eye3, r0 + 3 + eye3, r0 + 6 + eye3, r0 + 9 + eye3
            rows.append(r0 + np.arange(NS_CD))  # s_{k+1}
            cs.append(st[k])
            vals.append(np.ones(NS_CD))
            # - s_k terms (s_0 known: right-hand side)
            prev = p.s0 if k == 0 else None
            for blk in range(4):
                rr = r0 + 3 * blk + eye3
                if prev is None:
                    rows.append(rr)
                    cs.append(st[k - 1, 3 * blk + eye3])
                    vals.append(-np.ones(3))
                else:
                    b[rr] += prev[3 * blk : 3 * blk + 3]
            # p_c: - l_k dt / m ; H_ang: - k_k dt
            for rr, blk, scale in ((r_pc, 1, dt / m), (r_ha, 3, dt)):
                if k == 0:
                    b[rr] += scale * p.s0[3 * blk : 3 * blk + 3]
                else:
                    rows.append(rr)
                    cs.append(st[k - 1, 3 * blk + eye3])
                    vals.append(-scale * np.ones(3))
            # l: - sum f dt = m g dt
            b[r_l] += m * g * dt
            for i in range(2):
                rows.append(r_l)
                cs.append(cols["f"][k, 3 * i + eye3])
                vals.append(-dt * np.ones(3))
            # k: - dt sum (arm x f + tau)
            pc_k = p.s0[:3] if k == 0 else None
            for i in range(2):
                fc, tc, pfc = (cols[n][k, 3 * i + eye3] for n in ("f", "tau", "pf"))
                rows.append(r_k)
                cs.append(tc)
                vals.append(-dt * np.ones(3))
                if mode == "forces":
                    arm = p_foot[k, i] - c_bar[k]
                    put(r_k, fc, -dt * skew_batch(arm))
                    continue
                sf = skew_f[k, i]
                if mode == "com":
                    # (p̄_f - p_c) x f̄ = p̄_f x f̄ + skew(f̄) p_c
                    b[r_k] += dt * np.cross(p_foot[k, i], f[k, i])
                    if pc_k is not None:
                        b[r_k] += dt * (sf @ pc_k)
                    else:
                        put(r_k, st[k - 1, eye3], -dt * sf)
                else:  # footholds: (p_f - c̄) x f̄ = -skew(f̄) (p_f - c̄)
                    put(r_k, pfc, dt * sf)
                    b[r_k] += dt * (sf @ c_bar[k])
        a = sp.csc_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cs))),
            shape=(NS_CD * h, NW * h),
        )
        return a, b

    @staticmethod
    def _inequalities(p: CDProblem, mode: str) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        """Wrench rows (forces) or tie and separation rows (footholds) over the full
        vector, with their bounds; none for the CoM sub-problem."""
        h = p.horizon
        cols = cd_columns(h)
        if mode == "forces":
            mw = p.wrench_c.shape[2]
            blocks = []
            for k in range(h):
                for i in range(2):
                    sel = np.concatenate(
                        [cols["f"][k, 3 * i : 3 * i + 3], cols["tau"][k, 3 * i : 3 * i + 3]]
                    )
                    m_ = sp.lil_matrix((mw, NW * h))
                    m_[:, sel] = p.wrench_c[k, i]
                    blocks.append(m_)
            stance = np.repeat(p.contact[:, :, None], mw, axis=2)
            lo = np.where(stance, p.wrench_lo, -np.inf).ravel()
            hi = np.where(stance, p.wrench_hi, np.inf).ravel()
            return sp.vstack(blocks, format="csc"), lo, hi
        if mode == "com":
            return sp.csc_matrix((0, NW * h)), np.zeros(0), np.zeros(0)
        pf = cols["pf"]
        n_tie = 6 * (h - 1)
        r = np.arange(n_tie)
        tie = sp.csc_matrix(
            (
                np.r_[np.ones(n_tie), -np.ones(n_tie)],
                (np.r_[r, r], np.r_[pf[1:].ravel(), pf[:-1].ravel()]),
            ),
            shape=(n_tie, NW * h),
        )
        free = np.repeat(p.tie_free, 3, axis=1).ravel()
        lo = np.where(free, -_FREE_TIE_M, 0.0)
        hi = np.where(free, _FREE_TIE_M, 0.0)
        if p.sep_axis is None:
            return tie, lo, hi
        sep = sp.lil_matrix((h, NW * h))
        for k in range(h):
            ax = p.sep_axis[k]
            sep[k, pf[k, 0:2]] = ax
            sep[k, pf[k, 3:5]] = -ax
        return (
            sp.vstack([tie, sep.tocsc()], format="csc"),
            np.r_[lo, p.sep_min_m],
            np.r_[hi, np.full(h, _FREE_TIE_M)],
        )

    # ------------------------------------------------------------------ solve
    def _subproblem(
        self, p: CDProblem, mode: str, z: np.ndarray, c_bar: np.ndarray,
        cost: tuple[np.ndarray, np.ndarray], box: tuple[np.ndarray, np.ndarray],
    ) -> np.ndarray:  # fmt: skip
        """Solve sub-problem ``mode`` about the full vector ``z``; the new full vector."""
        h = p.horizon
        cols = cd_columns(h)
        block = {"forces": ("f", "tau"), "com": (), "footholds": ("pf",)}[mode]
        free = np.sort(np.concatenate([cols["state"].ravel(), *(cols[b].ravel() for b in block)]))
        fixed = np.setdiff1d(np.arange(NW * h), free)
        f = z[cols["f"]].reshape(h, 2, 3)
        tau = z[cols["tau"]].reshape(h, 2, 3)
        p_foot = z[cols["pf"]].reshape(h, 2, 3)
        a_eq, b_eq = self._dynamics(p, mode, f, tau, p_foot, c_bar)
        a_in, lo, hi = self._inequalities(p, mode)
        z_fixed = z[fixed]
        b_eq = b_eq - a_eq[:, fixed] @ z_fixed
        a_in_free = a_in[:, free]
        keep = np.diff(a_in_free.tocsr().indptr) > 0
        shift = a_in[:, fixed] @ z_fixed
        diag, wt = cost
        qp = QPProblem(
            sp.diags(2.0 * diag[free], format="csc"),
            -2.0 * wt[free],
            A_eq=a_eq[:, free],
            b_eq=b_eq,
            A=a_in_free[keep] if keep.any() else None,
            l=(lo - shift)[keep] if keep.any() else None,
            u=(hi - shift)[keep] if keep.any() else None,
            lb=box[0][free],
            ub=box[1][free],
        )
        sol = self._workspaces[mode].solve_or_raise(qp)
        assert sol.x is not None
        out = z.copy()
        out[free] = sol.x
        return out

    def solve(self, p: CDProblem) -> AD3Result:
        """Alternate the three sub-problems from ``p.guess`` until the round test holds.

        Raises:
            QPSolveError: a sub-problem had no solution.
        """
        t0 = time.perf_counter()
        h = p.horizon
        cols = cd_columns(h)
        cost = self._cost(p)
        lb = np.full(NW * h, -np.inf)
        ub = np.full(NW * h, np.inf)
        lb[cols["pf"]] = p.pf_lb_m.reshape(h, 6)
        ub[cols["pf"]] = p.pf_ub_m.reshape(h, 6)
        swing = ~np.repeat(p.contact, 3, axis=1)
        for name in ("f", "tau"):
            lb[cols[name]] = np.where(swing, 0.0, -np.inf)
            ub[cols[name]] = np.where(swing, 0.0, np.inf)
        z = np.zeros(NW * h)
        z[cols["state"]] = p.guess_states()
        z[cols["f"]] = p.guess.f.reshape(h, 6)
        z[cols["tau"]] = p.guess.tau.reshape(h, 6)
        z[cols["pf"]] = p.guess.p_foot.reshape(h, 6)
        c_bar = p.guess.p_com[:-1].copy()  # lever-arm CoM of stages 0..h-1
        tol = self.config.tolerances
        pos = np.concatenate([cols["state"][:, :3].ravel(), cols["pf"].ravel()])
        n_qps = 0
        converged = False
        for _ in range(self.config.max_rounds):
            z_start = z
            for mode in SUBPROBLEMS:
                z = self._subproblem(p, mode, z, c_bar, cost, (lb, ub))
                n_qps += 1
                if mode == "com":
                    c_bar = np.vstack([p.s0[:3], z[cols["state"][:-1, :3]]])
            dz = np.abs(z - z_start)
            if (
                dz[pos].max() <= tol.position_m
                and dz[cols["f"]].max() <= tol.force_n
                and dz[cols["tau"]].max() <= tol.moment_nm
            ):
                converged = True
                break
        sol = CDSolution(
            states=z[cols["state"]].copy(),
            f=z[cols["f"]].reshape(h, 2, 3).copy(),
            tau=z[cols["tau"]].reshape(h, 2, 3).copy(),
            p_foot=z[cols["pf"]].reshape(h, 2, 3).copy(),
        )
        return AD3Result(sol, n_qps, converged, time.perf_counter() - t0, cd_cost(p, sol))


__all__ = ["AD3", "SUBPROBLEMS", "AD3Config", "AD3Result"]
