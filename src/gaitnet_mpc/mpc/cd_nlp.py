"""The centroidal-dynamics problem (:mod:`~gaitnet_mpc.mpc.cd_problem`) as CasADi
expressions: eq. 10 with eq. 20 (explicit Euler, exact bilinear torque), eq. 18's cost and
the wrench, tie and separation rows, over stage-wise variables

    w_k = [s_k+1 (12: p_c, l_G, H_ang, k_G), f (2x3), tau (2x3), p_f (2x3)],  k = 0 .. h-1

Shared by CD-SQP (Table II, ``dt`` a parameter) and the optimised-dt policy
(:mod:`~gaitnet_mpc.mpc.dt_nlp`, ``dt`` and the references expressions of a decision
variable). The bounds that make it the CD problem (foot boxes, a swing wrench fixed to
zero, ``lbg`` / ``ubg``) are the caller's.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitnet_mpc.mpc.cd_problem import NS_CD, NW_CD, cd_columns
from gaitnet_mpc.mpc.kd_config import KDConfig


@dataclass(frozen=True)
class CDSymbols:
    """The per-problem data of a CD NLP as CasADi expressions (a parameter, or a function
    of a decision variable): ``s0`` (12,), ``dts`` (h,) stage lengths [s], ``cw`` the wrench
    rows (h 2 mw 6, each (mw, 6) block column-major), ``h_ref``, ``H_ref`` (6 h),
    ``pc_ref`` (3 h), ``pf_ref`` (6 h), ``axis`` (2 h, or empty without the separation
    row): rows 1 .. h of the references."""

    s0: ca.SX
    dts: ca.SX
    cw: ca.SX
    h_ref: ca.SX
    H_ref: ca.SX
    pc_ref: ca.SX
    pf_ref: ca.SX
    axis: ca.SX


@dataclass(frozen=True)
class CDTerms:
    """Eq. 18's cost and the constraint rows: dynamics (12 h, = 0), wrench (2 h mw, within
    the wrench bounds), ties (6 (h-1), = 0 unless the foot lifts off), separation (h, >=
    its minimum; empty without the row)."""

    cost: ca.SX
    dynamics: ca.SX
    wrench: ca.SX
    ties: ca.SX
    separation: ca.SX

    def constraints(self) -> ca.SX:
        """All rows in the order dynamics, wrench, ties, separation."""
        return ca.vertcat(self.dynamics, self.wrench, self.ties, self.separation)


def cd_terms(c: KDConfig, w: ca.SX, p: CDSymbols, h: int, mw: int, sep: bool) -> CDTerms:
    """Cost and rows of the CD problem with ``h`` stages, ``mw`` wrench rows per foot."""
    m = c.mass_kg
    nw = NW_CD
    g_vec = ca.DM([0.0, 0.0, -c.gravity_mps2])
    wp, wm = c.pose_weights, c.momentum_weights
    wpc, wpf = np.asarray(c.w_p_com), np.asarray(c.w_p_foot)
    dyn, wrench, ties, seps = [], [], [], []
    cost = ca.SX(0.0)
    s = p.s0
    for k in range(h):
        blk = w[nw * k : nw * (k + 1)]
        s_next, f, tau, pf = blk[:12], blk[12:18], blk[18:24], blk[24:30]
        pc, lg, ha, kg = s[:3], s[3:6], s[6:9], s[9:12]
        dt = p.dts[k]
        torque = ca.SX.zeros(3)
        for i in range(2):
            fi, ti, pi = f[3 * i : 3 * i + 3], tau[3 * i : 3 * i + 3], pf[3 * i : 3 * i + 3]
            torque += ca.cross(pi - pc, fi) + ti
            rows = ca.reshape(p.cw[(k * 2 + i) * mw * 6 : (k * 2 + i + 1) * mw * 6], 6, mw).T
            wrench.append(ca.mtimes(rows, ca.vertcat(fi, ti)))
        pred = ca.vertcat(
            pc + lg / m * dt, lg + (f[:3] + f[3:] + m * g_vec) * dt, ha + kg * dt,
            kg + torque * dt,
        )  # fmt: skip
        dyn.append(s_next - pred)
        if k + 1 < h:
            ties.append(w[nw * (k + 1) + 24 : nw * (k + 1) + 30] - pf)
        if sep:
            d = pf[0:2] - pf[3:5]
            seps.append(p.axis[2 * k] * d[0] + p.axis[2 * k + 1] * d[1])
        # eq. 18 (H_lin = m p_c)
        pc1, lg1, ha1, kg1 = s_next[:3], s_next[3:6], s_next[6:9], s_next[9:12]
        pose = ca.vertcat(m * pc1, ha1) - p.H_ref[6 * k : 6 * k + 6]
        mom = ca.vertcat(lg1, kg1) - p.h_ref[6 * k : 6 * k + 6]
        cost += ca.dot(wp * pose, pose) + ca.dot(wm * mom, mom)
        e_pc = pc1 - p.pc_ref[3 * k : 3 * k + 3]
        e_pf = pf - p.pf_ref[6 * k : 6 * k + 6]
        cost += ca.dot(wpc * e_pc, e_pc) + ca.dot(np.tile(wpf, 2) * e_pf, e_pf)
        cost += c.w_force * ca.dot(f, f) + c.w_moment * ca.dot(tau, tau)
        s = s_next
    return CDTerms(
        cost=cost,
        dynamics=ca.vertcat(*dyn),
        wrench=ca.vertcat(*wrench),
        ties=ca.vertcat(*ties),
        separation=ca.vertcat(*seps),
    )


def cd_bounds(
    contact: np.ndarray,
    pf_lb_m: np.ndarray,
    pf_ub_m: np.ndarray,
    wrench_lo: np.ndarray,
    wrench_hi: np.ndarray,
    tie_free: np.ndarray,
    sep_min_m: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``lbx, ubx`` of the stage-wise variables (foot boxes; a swing foot's wrench fixed to
    zero, eq. 23 with sigma = 0) and ``lbg, ubg`` of :meth:`CDTerms.constraints`.

    A swing foot's wrench rows are left free: ``C w = 0`` on 10 rows of 6 unknowns is a
    degenerate equality set that stalls active-set QP solvers; the set of plans is the
    same with the wrench boxed to zero.
    """
    h = contact.shape[0]
    cols = cd_columns(h)
    lbx = np.full(NW_CD * h, -np.inf)
    ubx = np.full(NW_CD * h, np.inf)
    lbx[cols["pf"]] = pf_lb_m.reshape(h, 6)
    ubx[cols["pf"]] = pf_ub_m.reshape(h, 6)
    swing = ~np.repeat(contact, 3, axis=1)  # (h, 6)
    for name in ("f", "tau"):
        lbx[cols[name]] = np.where(swing, 0.0, -np.inf)
        ubx[cols[name]] = np.where(swing, 0.0, np.inf)
    stance_rows = np.repeat(contact[:, :, None], wrench_lo.shape[2], axis=2)
    w_lo = np.where(stance_rows, wrench_lo, -np.inf).ravel()
    w_hi = np.where(stance_rows, wrench_hi, np.inf).ravel()
    free = np.repeat(tie_free, 3, axis=1)  # (h-1, 6)
    big = 1e3
    lbg = np.concatenate(
        [np.zeros(NS_CD * h), w_lo, np.where(free, -big, 0.0).ravel(),
         sep_min_m if sep_min_m is not None else np.zeros(0)]
    )  # fmt: skip
    ubg = np.concatenate(
        [np.zeros(NS_CD * h), w_hi, np.where(free, big, 0.0).ravel(),
         np.full(h, big) if sep_min_m is not None else np.zeros(0)]
    )  # fmt: skip
    return lbx, ubx, lbg, ubg


__all__ = ["CDSymbols", "CDTerms", "cd_bounds", "cd_terms"]
