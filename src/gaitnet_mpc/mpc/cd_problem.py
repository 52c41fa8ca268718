"""The centroidal-dynamics (CD) MPC problem shared by the Table II baselines (CD-SQP, AD(3)).

Table II solves "the same MPC problems" with every method. The implicit kino-dynamic
solver (Algorithm 1) re-makes its references by IK in every iteration (line 9); a
centroidal-dynamics MPC has no kinematics, so its problem is that of Algorithm 1's
*first* sub-problem, with the bilinear terms kept exact and the references frozen:

* state per stage ``k = 1 .. h`` (decision variables): ``s_k = [p_c (3); l_G (3);
  H_ang (3); k_G (3)]``; ``s_0`` is the measurement. The linear centroidal pose is
  ``m p_c`` (eq. 20 integrates it exactly as ``H_lin`` would);
* inputs per stage ``k = 0 .. h-1``: contact force ``f_i``, moment ``tau_i`` and foot
  position ``p_f,i`` of both line feet (footholds are variables, as in the proposed method);
* dynamics, eq. 10 with eq. 20 (explicit Euler, fixed ``dt_k``)::

      p_c,k+1 = p_c,k + l_k / m dt_k
      l_k+1   = l_k + (sum_i f_i + m g) dt_k
      H_ang,k+1 = H_ang,k + k_k dt_k
      k_k+1   = k_k + sum_i ((p_f,i - p_c,k) x f_i + tau_i) dt_k

* cost: eq. 18 with the KDConfig weights against the first sub-problem's references (no
  proximal term, no trust region: those belong to the sequential solver);
* constraints: the same friction pyramid, normal-force and line-foot wrench rows (eqs.
  21-23; swing: ``C w = 0``), foot ties (a foot keeps its position until it lifts off),
  measured stance foot fixed, eq. 24 box on the next touchdown, foot height from the
  reference, and the lateral separation row of the ``kd`` controller.

So ``n = 12 h`` states + ``12 h`` wrenches + ``6 h`` foot positions ``= 30 h`` variables
(paper: ``34 h - 22`` for its CD-SQP; its state layout is not given).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gaitnet_mpc.mpc.contact import StanceWrenchRows
from gaitnet_mpc.mpc.implicit_kd import KDConfig, KDIterate, KDStep, KDSubproblem
from gaitnet_mpc.mpc.kd_inputs import KDInputs
from gaitnet_mpc.mpc.kd_layout import KDLayout
from gaitnet_mpc.mpc.sequential import KDProblem, SequentialKDMPC

NS_CD = 12  # [p_c; l_G; H_ang; k_G]
NW_CD = NS_CD + 18  # variables per stage of CD-SQP and AD(3): state 12, f 6, tau 6, p_f 6


def cd_columns(h: int) -> dict[str, np.ndarray]:
    """(h, n) indices of each stage's state, force, moment and foothold variables in the
    stage-wise vector of CD-SQP and AD(3)."""
    base = NW_CD * np.arange(h)[:, None]
    return {
        "state": base + np.arange(NS_CD),
        "f": base + NS_CD + np.arange(6),
        "tau": base + NS_CD + 6 + np.arange(6),
        "pf": base + NS_CD + 12 + np.arange(6),
    }


@dataclass(frozen=True)
class CDProblem:
    """One centroidal-dynamics MPC problem (module docstring), plain arrays.

    Attributes:
        config: weights, mass, contact model (the proposed solver's :class:`KDConfig`).
        s0: (12,) measured ``[p_c; l_G; H_ang; k_G]``.
        dts_s: (h,) stage lengths [s]; contact: (h, 2) stance mask.
        wrench_c: (h, 2, mw, 6) wrench rows; wrench_lo, wrench_hi: (h, 2, mw) bounds
            (swing: 0, 0).
        tie_free: (h-1, 2) True where foot ``i`` lifts off between ``k`` and ``k+1``.
        pf_lb_m, pf_ub_m: (h, 2, 3) box on the foot positions (equal where fixed).
        sep_axis: (h, 2) leftward axis of the separation row, or None;
        sep_min_m: (h,) its lower bound [m].
        h_ref, H_ref: (h+1, 6); p_com_ref: (h+1, 3); p_foot_ref: (h, 2, 3); row 0 unused.
        guess: the proposed method's ``u^0`` (forces share the weight, positions from the
            references): the common cold start of every method.
    """

    config: KDConfig
    s0: np.ndarray
    dts_s: np.ndarray
    contact: np.ndarray
    wrench_c: np.ndarray
    wrench_lo: np.ndarray
    wrench_hi: np.ndarray
    tie_free: np.ndarray
    pf_lb_m: np.ndarray
    pf_ub_m: np.ndarray
    sep_axis: np.ndarray | None
    sep_min_m: np.ndarray
    h_ref: np.ndarray
    H_ref: np.ndarray
    p_com_ref: np.ndarray
    p_foot_ref: np.ndarray
    guess: KDIterate

    @property
    def horizon(self) -> int:
        return int(self.dts_s.size)

    @property
    def n_variables(self) -> int:
        """``30 h``: states (12 h), wrenches (12 h), foot positions (6 h)."""
        return 30 * self.horizon

    def guess_states(self) -> np.ndarray:
        """(h, 12) initial state guess: the guess's CoM path, the momentum and angular
        pose references."""
        return np.hstack(
            [self.guess.p_com[1:], self.h_ref[1:, :3], self.H_ref[1:, 3:], self.h_ref[1:, 3:]]
        )


class _CapturingSubproblem(KDSubproblem):
    """A :class:`KDSubproblem` that keeps the iterate and inputs of its first solve."""

    captured: tuple[KDIterate, KDInputs] | None = None

    def solve(self, iterate: KDIterate, inputs: KDInputs) -> KDStep:
        if self.captured is None:
            self.captured = (iterate, inputs)
        return super().solve(iterate, inputs)


def centroidal_problem(solver: SequentialKDMPC, problem: KDProblem) -> CDProblem:
    """The CD problem of ``problem``: Algorithm 1's first sub-problem data (references,
    constraints, ``u^0``) with ``solver``'s configuration (module docstring)."""
    c = solver.config.kd
    capture = _CapturingSubproblem(c)
    probe = SequentialKDMPC(solver.robot, solver.config, solver.dt_policy)
    probe.subproblem = capture
    probe.solve(replace(problem, j_max=1))
    assert capture.captured is not None  # j_max = 1: one sub-problem solve
    it0, a = capture.captured
    h = c.horizon
    mass = c.mass_kg
    # box of the foot positions: the sub-problem's own box without the trust region,
    # built about p_f = 0 so that its bounds are absolute
    box_sub = KDSubproblem(replace(c, trust_region_m=None, trust_region_com_m=None))
    zero = replace(it0, p_foot=np.zeros_like(it0.p_foot))
    qp = box_sub.build(zero, a)
    assert qp.lb is not None and qp.ub is not None
    col_pf = KDLayout(h).col_pf
    wrench = StanceWrenchRows(c.contact, c.toe_m, c.heel_m, c.yaw_cone_half_m)
    cm, lo, hi = wrench.stack(a.foot_yaw_rad)
    stance = a.contact[:, :, None]
    sep_axis = None
    sep_min = np.zeros(h)
    if c.min_foot_separation_m is not None:
        swing = np.where(a.contact[:, 1] & ~a.contact[:, 0], 0, 1)
        yaw = a.foot_yaw_rad[np.arange(h), swing]
        sep_axis = np.stack([-np.sin(yaw), np.cos(yaw)], axis=1)
        sweep = max(c.toe_m, c.heel_m) * np.abs(np.sin(a.foot_yaw_rad[:, 0] - a.foot_yaw_rad[:, 1]))
        sep_min = c.min_foot_separation_m + sweep
    s0 = np.concatenate([a.x0[:3] / mass, a.x0[6:9], a.x0[3:6], a.x0[9:12]])
    return CDProblem(
        config=c,
        s0=s0,
        dts_s=a.dts_s.copy(),
        contact=a.contact.copy(),
        wrench_c=np.array(cm),
        wrench_lo=np.where(stance, lo, 0.0),
        wrench_hi=np.where(stance, hi, 0.0),
        tie_free=a.contact[:-1] & ~a.contact[1:],
        pf_lb_m=qp.lb[col_pf],
        pf_ub_m=qp.ub[col_pf],
        sep_axis=sep_axis,
        sep_min_m=sep_min,
        h_ref=a.h_ref.copy(),
        H_ref=a.H_ref.copy(),
        p_com_ref=a.p_com_ref.copy(),
        p_foot_ref=a.p_foot_ref.copy(),
        guess=it0,
    )


@dataclass(frozen=True)
class CDSolution:
    """A plan of the CD problem: states (h, 12) ``s_1 .. s_h``, f, tau, p_foot (h, 2, 3)."""

    states: np.ndarray
    f: np.ndarray
    tau: np.ndarray
    p_foot: np.ndarray


def rollout(p: CDProblem, f: np.ndarray, tau: np.ndarray, p_foot: np.ndarray) -> np.ndarray:
    """States (h, 12) ``s_1 .. s_h`` of the exact dynamics (module docstring) from ``s0``."""
    c = p.config
    g = np.array([0.0, 0.0, -c.gravity_mps2])
    s = p.s0.copy()
    out = np.zeros((p.horizon, NS_CD))
    for k, dt in enumerate(p.dts_s):
        pc, lg, ha, kg = s[:3], s[3:6], s[6:9], s[9:]
        torque = np.cross(p_foot[k] - pc, f[k]).sum(axis=0) + tau[k].sum(axis=0)
        s = np.concatenate(
            [pc + lg / c.mass_kg * dt, lg + (f[k].sum(axis=0) + c.mass_kg * g) * dt,
             ha + kg * dt, kg + torque * dt]
        )  # fmt: skip
        out[k] = s
    return out


def cd_cost(p: CDProblem, sol: CDSolution) -> float:
    """Eq. 18 at a plan (the same terms as ``KDSubproblem.plan_cost``, with ``H_lin = m
    p_c``)."""
    c = p.config
    x = sol.states
    m = c.mass_kg
    pose = np.hstack([m * x[:, :3], x[:, 6:9]])
    momentum = np.hstack([x[:, 3:6], x[:, 9:12]])
    return float(
        np.sum(c.pose_weights * (pose - p.H_ref[1:]) ** 2)
        + np.sum(c.momentum_weights * (momentum - p.h_ref[1:]) ** 2)
        + np.sum(np.asarray(c.w_p_com) * (x[:, :3] - p.p_com_ref[1:]) ** 2)
        + c.w_force * np.sum(sol.f**2)
        + c.w_moment * np.sum(sol.tau**2)
        + np.sum(np.asarray(c.w_p_foot) * (sol.p_foot - p.p_foot_ref) ** 2)
    )


def cd_violation(p: CDProblem, sol: CDSolution) -> dict[str, float]:
    """Largest violation of each constraint family at a plan (dynamics as the state
    error against :func:`rollout`, in the state's units)."""
    w = np.concatenate([sol.f, sol.tau], axis=2)[..., None]  # (h, 2, 6, 1)
    cw = np.matmul(p.wrench_c, w)[..., 0]
    gap = sol.p_foot[:-1] - sol.p_foot[1:]
    tie = np.where(p.tie_free[:, :, None], 0.0, np.abs(gap))
    out = {
        "dynamics": float(np.abs(rollout(p, sol.f, sol.tau, sol.p_foot) - sol.states).max()),
        "wrench": float(np.maximum(p.wrench_lo - cw, cw - p.wrench_hi).clip(0.0).max()),
        "ties_m": float(tie.max()) if tie.size else 0.0,
        "box_m": float(np.maximum(p.pf_lb_m - sol.p_foot, sol.p_foot - p.pf_ub_m).clip(0.0).max()),
    }
    if p.sep_axis is not None:
        d = sol.p_foot[:, 0, :2] - sol.p_foot[:, 1, :2]
        sep = np.einsum("kj,kj->k", p.sep_axis, d)
        out["separation_m"] = float((p.sep_min_m - sep).clip(0.0).max())
    return out


__all__ = [
    "NS_CD",
    "CDProblem",
    "CDSolution",
    "cd_cost",
    "cd_violation",
    "centroidal_problem",
    "rollout",
]
