"""Algorithm 1: the sequential convex MPC of the implicit kino-dynamic controller.

One solve::

    x_0   = f_j2m(q, v)                                  (line 1)
    ref   = f_ref(q, command, footholds, dt^0)           (lines 2-3)
    u^0   = references (weight shared by stance feet)    (line 1)
    repeat j = 0 .. j_max - 1:                            (line 5)
        du^j   = cmpc(x_ref, p_f_ref, p_c_ref, x_0, dt^j, u^j)     (line 6, eqs. 13-24)
        u^j+1  = u^j + du^j                                         (line 7)
        dt^j+1 = dt_policy(state, u^j+1)                            (line 8: Gait-Net slot)
        ref    = f_IK(p_f^j+1, p_c^j+1, dt^j+1)                     (line 9, Remark 1)
    until every search direction is below Table X's tolerances.

The dt policy acts only at a step start (Remark 4); during a step the same dt is kept
and the loop re-solves footholds and wrenches, warm-started from the previous plan's
footholds.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.kinematics.centroidal import centroidal_map_euler, euler_coordinates, f_j2m
from gaitnet_mpc.kinematics.reference import (
    CentroidalReference,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    update_reference,
)
from gaitnet_mpc.mpc.implicit_kd import (
    KDConfig,
    KDIterate,
    KDStep,
    KDSubproblem,
    KDTolerances,
)
from gaitnet_mpc.robots import FEET, RobotModel


class DtPolicy(Protocol):
    """Chooses the MPC sampling time of the step that is starting (Alg. 1, line 8)."""

    def __call__(self, q: np.ndarray, v: np.ndarray, iterate: KDIterate, dt_s: float) -> float:
        """The next dt [s] given the measured state and the current iterate."""
        ...


@dataclass(frozen=True)
class FixedDt:
    """The paper's baseline 1 (Fig. 6a): the same dt for every step."""

    dt_s: float = 0.045

    def __call__(self, q: np.ndarray, v: np.ndarray, iterate: KDIterate, dt_s: float) -> float:
        return self.dt_s


@dataclass(frozen=True)
class SequentialConfig:
    """Settings of the sequential loop (paper Table X)."""

    j_max: int = 50
    tolerances: KDTolerances = field(default_factory=KDTolerances)
    kd: KDConfig = field(default_factory=KDConfig)
    update_foot_reference: bool = True  # Alg. 1 line 9 re-makes p_f_ref from the iterate
    linear_reference_from_command: bool = True
    # From QP number ``relax_after_qps`` + 1 on, apply ``relax_step`` times the search
    # direction (under-relaxation of the fixed-point iteration, which can cycle). None:
    # full steps always (Algorithm 1 as printed, the default). Measured with 8 and 0.5
    # (benchmarks/kd_runs.py): solves hitting j_max biped2d 16 % -> 8 %, humanoid3d flat
    # 3 % -> 1 %, but the 20 s flat humanoid run then fell at 16.2 s (it does not without),
    # so it stays off.
    relax_after_qps: int | None = None
    relax_step: float = 0.5

    def __post_init__(self) -> None:
        if not isinstance(self.j_max, int) or self.j_max < 1:
            raise ConfigError("j_max", self.j_max, "an integer >= 1")
        n = self.relax_after_qps
        if n is not None and (not isinstance(n, int) or n < 1):
            raise ConfigError("relax_after_qps", n, "None or an integer >= 1")
        if not 0.0 < self.relax_step <= 1.0:
            raise ConfigError("relax_step", self.relax_step, "a step fraction in (0, 1]")


@dataclass
class SequentialResult:
    """Outcome of one sequential solve."""

    iterate: KDIterate
    reference: CentroidalReference
    dts_s: np.ndarray  # (h,) stage durations the plan was made with [s]
    contact: np.ndarray  # (h, 2) stance mask
    n_qps: int
    converged: bool
    solve_time_s: float
    last_step: KDStep | None
    t_plan_s: float = 0.0

    def stage_at(self, t_s: float) -> int:
        """Index of the plan's stage that contains time ``t_s`` (clamped)."""
        boundaries = self.t_plan_s + np.cumsum(self.dts_s)
        return int(min(np.searchsorted(boundaries, t_s, side="right"), len(self.dts_s) - 1))

    def touchdown(self, foot: str) -> np.ndarray | None:
        """(3,) planned touchdown of ``foot``: its position in its next stance stage."""
        i = FEET.index(foot)
        col = self.contact[:, i]
        swinging = np.flatnonzero(~col)
        if swinging.size == 0:
            return None
        after = np.flatnonzero(col[swinging[0] :])
        if after.size == 0:
            return self.iterate.p_foot[swinging[0], i]
        return self.iterate.p_foot[swinging[0] + after[0], i]


def mpc_foot_reference(ref: CentroidalReference, contact: np.ndarray) -> np.ndarray:
    """(h, 2, 3) foothold reference per stage: where a stance foot stands, and for a
    swinging foot its next touchdown (the sub-problem ties swing stages to it)."""
    out = np.zeros((contact.shape[0], 2, 3))
    for i, foot in enumerate(FEET):
        holds = np.asarray(ref.footholds_m[foot])
        stand = np.asarray(contact[:, i], dtype=bool)
        j = np.asarray(ref.foothold_index[: stand.size, i], dtype=int) + ~stand
        out[:, i] = holds[np.minimum(j, len(holds) - 1)]
    return out


def angular_pose_kgm2(
    robot: RobotModel, data: object, q: np.ndarray, yaw_origin_rad: float
) -> np.ndarray:
    """Angular part of the centroidal pose at one configuration, ``[A_xi(q) xi]_ang`` (3,).

    This is eq. 30 at the first sample (the sum is empty), in Euler coordinates
    ``xi = [p_base, rpy, joints]`` (``A_xi`` maps ``xi_dot`` to momentum). Its trunk part is
    about the composite inertia times the roll/pitch/yaw angles, so tracking ``H`` holds
    the trunk orientation. The yaw coordinate is taken relative to ``yaw_origin_rad`` so
    that long turns do not wrap.
    """
    xi = euler_coordinates(robot.pin_model, q)
    if not robot.spec.planar:
        xi[5] = (xi[5] - yaw_origin_rad + np.pi) % (2 * np.pi) - np.pi
    return (centroidal_map_euler(robot.pin_model, data, q) @ xi)[3:]


class SequentialKDMPC:
    """The implicit kino-dynamic MPC solved by sequential convex QPs (Algorithm 1)."""

    def __init__(self, robot: RobotModel, config: SequentialConfig | None = None) -> None:
        self.robot = robot
        self.config = config or SequentialConfig()
        self.subproblem = KDSubproblem(self.config.kd)
        self.ref_workspace = ReferenceWorkspace(robot)
        self.pin_data = robot.pin_model.createData()

    def _yaw_origin(self, q: np.ndarray, command: object) -> float:
        """Commanded heading at the start of the horizon [rad] (the controller's reference)."""
        return float(getattr(command, "heading_rad", 0.0))

    def solve(
        self,
        q: np.ndarray,
        v: np.ndarray,
        timing: ReferenceTiming,
        command: object,
        footholds: Mapping[str, np.ndarray],
        p_foot_now_m: Mapping[str, np.ndarray],
        p_liftoff_m: Mapping[str, np.ndarray],
        foot_yaw_rad: np.ndarray,
        foothold_bounds: Mapping[str, tuple[np.ndarray, np.ndarray, None]] | None = None,
        j_max: int | None = None,
        p_com_start_m: np.ndarray | None = None,
        com_reference: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> SequentialResult:
        """Run Algorithm 1 from the measured state (q, v) in Pinocchio coordinates.

        Args:
            timing: stage durations and contact sequence from now.
            command: velocity command (``vx_mps``, ``vy_mps``, ``yaw_rate_radps``).
            footholds: foot -> initial touchdown targets (n, 3) of its swings in the
                horizon (the warm start ``u^0``; the MPC moves them).
            p_foot_now_m: foot -> (3,) measured foot centres.
            p_liftoff_m: foot -> (3,) lift-off point of the foot swinging now.
            foot_yaw_rad: (h, 2) foot headings for the line-foot wrench limits.
            foothold_bounds: eq. 24 boxes for the next touchdown (one-step preview).
            j_max: iteration cap (default ``config.j_max``).
            p_com_start_m: start of the reference CoM path (default: the measured CoM);
                a point on the commanded path lets the MPC correct drift.
            com_reference: optional ``(p_com (h+1, 3) [m], v_com (h+1, 3) [m/s])`` that
                replaces the CoM path of ``f_ref`` in eq. 18's CoM term, the linear
                centroidal pose ``m p_c`` and the linear momentum ``m v_c`` (with
                ``linear_reference_from_command``), e.g. a LIP sway orbit over the
                planned footholds (the straight command line with ``l_y = 0`` is only
                reachable with the feet under the CoM, as the line foot has no roll
                moment). NaN entries keep ``f_ref``'s value.
        """
        t0 = time.perf_counter()
        cfg = self.config
        robot = self.robot
        mass = robot.total_mass_kg
        # Centroidal pose: measured H_0 and the reference's H_0 from the same map (eq. 30),
        # with yaw measured from the commanded heading at the start of the horizon.
        yaw_cmd = self._yaw_origin(q, command)
        pose0_meas = angular_pose_kgm2(robot, self.pin_data, q, yaw_cmd)
        ref = make_reference(
            robot,
            q,
            timing,
            command,
            footholds,
            p_foot_now_m=p_foot_now_m,
            p_liftoff_m=p_liftoff_m,
            p_com_start_m=p_com_start_m,
            workspace=self.ref_workspace,
        )
        # The reference's angular pose starts at 0; H_ref's angular part is additive in its
        # start value (eq. 30 and the Riemann sum alike), so shift it to the same map of
        # q_ref[0] instead of building the reference a second time.
        pose0_ref = angular_pose_kgm2(robot, self.pin_data, ref.q_ref[0], yaw_cmd)
        H_ref = ref.H_ref.copy()
        H_ref[:, 3:] += pose0_ref - ref.pose0_angular_kgm2
        ref = replace(ref, H_ref=H_ref, pose0_angular_kgm2=pose0_ref)
        h0 = f_j2m(robot.pin_model, self.pin_data, q, v)
        com0 = np.array(self.pin_data.com[0])
        x0 = np.concatenate([mass * com0, pose0_meas, h0])
        contact = np.asarray(timing.contact, dtype=bool)
        dts = np.asarray(timing.dts_s, dtype=float)
        p_measured = np.stack([np.asarray(p_foot_now_m[f], dtype=float) for f in FEET])
        pf_ref = mpc_foot_reference(ref, contact)
        p_com_ref = ref.p_com_ref  # f_ref's CoM path; line 9 updates x_ref and p_f_ref only
        h_lin_ref, pose_lin_ref = ref.h_ref[:, :3].copy(), ref.H_ref[:, :3].copy()
        h_ref, pose_ref = ref.h_ref, ref.H_ref
        if com_reference is not None:
            pc_override = np.asarray(com_reference[0], dtype=float)
            vc_override = np.asarray(com_reference[1], dtype=float)
            p_com_ref = np.where(np.isnan(pc_override), p_com_ref, pc_override)
            pose_lin_ref = np.where(np.isnan(pc_override), pose_lin_ref, mass * pc_override)
            h_lin_ref = np.where(np.isnan(vc_override), h_lin_ref, mass * vc_override)
            h_ref = np.hstack([h_lin_ref, ref.h_ref[:, 3:]])
            pose_ref = np.hstack([pose_lin_ref, ref.H_ref[:, 3:]])
        iterate = KDIterate.initial(com0, p_com_ref, pf_ref, contact, mass)
        step: KDStep | None = None
        converged = False
        n_qps = 0
        for _ in range(j_max or cfg.j_max):
            step = self.subproblem.solve(
                x0,
                iterate,
                h_ref,
                pose_ref,
                pf_ref,
                p_com_ref,
                dts,
                contact,
                foot_yaw_rad,
                foothold_bounds,
                p_measured,
            )
            n_qps += 1
            alpha = 1.0
            if cfg.relax_after_qps is not None and n_qps > cfg.relax_after_qps:
                alpha = cfg.relax_step
            iterate = iterate.apply(step, alpha)
            if step.converged(cfg.tolerances):
                converged = True
                break
            ref = update_reference(robot, ref, iterate.p_foot, iterate.p_com, dts)
            h_ref, pose_ref = ref.h_ref, ref.H_ref
            if cfg.linear_reference_from_command or com_reference is not None:
                h_ref = np.hstack([h_lin_ref, ref.h_ref[:, 3:]])
                pose_ref = np.hstack([pose_lin_ref, ref.H_ref[:, 3:]])
            if cfg.update_foot_reference:
                pf_ref = mpc_foot_reference(ref, contact)
        return SequentialResult(
            iterate=iterate,
            reference=ref,
            dts_s=dts,
            contact=contact,
            n_qps=n_qps,
            converged=converged,
            solve_time_s=time.perf_counter() - t0,
            last_step=step,
        )
