"""Joint-space reference trajectories over the MPC horizon and their centroidal maps.

(Over 500 lines because of this docstring, the reference motion's specification; the
data types are in :mod:`~gaitnet_mpc.kinematics.reference_workspace`.)

This module implements Algorithm 1's ``f_ref`` (lines 2-3) and ``f_IK`` (line 9):

* :func:`make_reference` (``f_ref``): from the measured configuration, the user command and
  the planned footholds, a whole-body trajectory ``{q_k^ref, v_k^ref}_{k=0..h}`` at the
  ``h + 1`` stage boundaries, mapped to the spatial momentum ``h_k^ref = A_G(q_k^ref)
  v_k^ref`` (eq. 11), the centroidal pose ``H_k^ref`` (eq. 12 / Appendix A), the CoM path
  ``p_c^ref`` and the foot path ``p_f^ref`` (Sec. II, eq. 18).
* :func:`update_reference` (``f_IK``): the same trajectory re-solved from the MPC's latest
  foothold and CoM iterates (and possibly a new ``dt`` from Gait-Net), so that the
  momentum references stay kinematically consistent with the iterate (Remark 1, Remark 3).

Reference motion (f_ref)
------------------------

Stage boundary ``k`` lies at ``t_k = sum(dts_s[:k])`` seconds from now (``t_0 = 0``).

* CoM: starts at the current CoM (x, y) and moves with the commanded velocity
  ``(vx, vy)`` given in the heading frame, whose yaw integrates the commanded yaw rate
  ``psi(t) = psi_0 + omega t`` (exact arc, ``p(t) = p_0 + R_z(psi_0 + omega t / 2)
  v t sinc(omega t / 2)``); its height is ``ground + com_height_m`` where the ground is
  under the feet standing in stage 0 (foot-centre height minus the foot contact radius).
* Trunk: ``R = R_z(psi(t)) R_y(trunk_pitch_rad)`` (upright, roll = 0); its position is
  solved so that the CoM of the whole configuration lands on the CoM path (below).
* Feet: stance and swing segments of each foot's contact column, footholds ``F_0, F_1,
  ...`` and the obstacle-free minimum-jerk swing between them (apex ``max(z_0, z_1) +
  swing_apex_height_m`` at mid-swing, zero touchdown speed), evaluated in closed form by
  :func:`gaitnet_mpc.gait.swing.swing_profile`; see :mod:`gaitnet_mpc.kinematics.foot_plan`.
  Missing targets fall back to a neutral point (:func:`make_reference`).
* Legs: analytic IK (:func:`gaitnet_mpc.kinematics.whole_body_ik`, Appendix B); arms at
  the nominal pose. An out-of-reach target keeps its value in ``p_foot_ref``, the IK
  returns the nearest feasible leg pose and ``reachable`` is False at that stage.

CoM placement (both functions): the trunk position of stage ``k`` is found by the fixed
point ``p_B <- p_B + G^-1 (p_c^des - c(q(p_B)))`` where ``c(q)`` is the CoM of the IK
configuration (``pin.centerOfMass``) and ``G`` a constant diagonal estimate of
``d c / d p_B`` with the feet held fixed (about 0.92: the legs fold; measured once at the
nominal pose in :class:`ReferenceWorkspace`). It starts from the nominal trunk-to-CoM
offset (f_ref) or from the previous reference's trunk-to-CoM offset, corrected to first
order for the CoM and foot moves (f_IK). ``ReferenceConfig.com_iterations`` corrections
follow (default 1: the CoM lands within ~0.5 mm of its target for 2 cm iterate moves, 2:
~0.05 mm); the reported ``p_com_ref`` is always the exact CoM of ``q_ref``.

Velocities, momenta and the centroidal pose
-------------------------------------------

``v_ref`` is the derivative of the configuration path along the stage times by
second-order finite differences on the (non-uniform) grid ``t_k`` (three-point, one-sided
at the ends, as ``numpy.gradient(edge_order=2)``; ``derivative_matrix`` of
:class:`gaitnet_mpc.gait.timing.ReferenceTiming`): joint rates directly, the trunk's
linear velocity as ``R^T dp_B/dt`` and its angular velocity as ``R^T e_z dpsi/dt``
(Pinocchio's local free-flyer velocity; the biped's root is Euclidean, ``v = dq/dt``).
Then ``h_ref[k] = A_G(q_ref[k]) v_ref[k]`` (eq. 11, ``pin.computeCentroidalMomentum``;
``[linear [kg m/s]; angular about the CoM [kg m^2/s]]``, world axes).

Centroidal pose ``H_ref`` (``[linear [kg m]; angular [kg m^2]]``), ``pose_method``:

* ``"riemann"`` (default): linear part ``m p_com_ref`` exactly (the primitive of ``l = m
  dp_c/dt``, the quantity that eq. 20 and the CoM cost of eq. 18 use); angular part
  ``H_0 + sum_{i<k} k_ref[i] dt_i``, the left Riemann sum that the MPC's discrete dynamics
  (eq. 10, ``H_{k+1} = H_k + h_k dt_k``) propagate, started from the measured state's
  angular pose ``H_0`` (argument ``pose0_angular_kgm2``, default 0: only differences of
  the angular pose are physical).
* ``"eq30"``: the paper's integration by parts (eq. 12 = eq. 30) via
  :func:`gaitnet_mpc.kinematics.centroidal_pose_eq30` (``subtract_initial=True``), shifted
  so that ``H_ref[0] = [m p_com_ref[0]; H_0]``. Both parts then differ from the Riemann
  definition by ``O(dt)`` (checked in the tests); it costs ~0.5 ms more per call.

Cost
----

Create one :class:`ReferenceWorkspace` per robot and controller and pass it to
:func:`make_reference` (reading the leg geometry and measuring the CoM gain costs
milliseconds); the returned reference keeps it, so :func:`update_reference` reuses its
Pinocchio data and geometry. Everything is vectorised over the ``h + 1`` stages or runs
in compiled row loops (the leg IK, the foot plan, and the CoM and momentum of the
humanoid's tree: :mod:`~gaitnet_mpc.kinematics.rigid_body_kernel`); the only Python loops
run over the two feet and their few stance/swing segments. See
``benchmarks/results/reference.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import cast

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from gaitnet_mpc.command import Command
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.schedule import GaitHorizon
from gaitnet_mpc.gait.timing import ReferenceTiming
from gaitnet_mpc.geometry import unwrap_angles, wrap_angle
from gaitnet_mpc.kinematics.centroidal import centroidal_pose_eq30, centroidal_pose_riemann
from gaitnet_mpc.kinematics.foot_plan import (
    FootPlan,
    foot_plan,
    foot_timeline,
    footholds_from_iterates,
    heading_displacement,
    neutral_foothold,
)
from gaitnet_mpc.kinematics.reference_workspace import (
    POSE_METHODS,
    CentroidalReference,
    PoseMethod,
    ReferenceConfig,
    ReferenceWorkspace,
)
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET

__all__ = [
    "POSE_METHODS",
    "CentroidalReference",
    "PoseMethod",
    "ReferenceConfig",
    "ReferenceTiming",
    "ReferenceWorkspace",
    "make_reference",
    "update_reference",
]

_N_FEET = len(FEET)


# -------------------------------------------------------------------- core solve
def _place_trunk(
    ws: ReferenceWorkspace,
    plan: FootPlan,
    p_com_target_m: np.ndarray,
    p_base_guess_m: np.ndarray,
    yaw_rad: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Trunk placement by the CoM fixed point + whole-body IK (module docstring).

    Returns:
        q (h+1, nq), p_base (h+1, 3), rot (h+1, 3, 3), reachable (h+1,).
    """
    cfg = ws.config
    rot = ws.trunk_frames(yaw_rad)[0]  # (h+1, 3, 3)
    yaw_targets = None  # None: q0 = 0 (eq. 31), the same when the feet face the trunk heading
    if not ws.planar and np.max(np.abs(wrap_angle(plan.foot_yaw_rad - yaw_rad[:, None]))) > 1e-12:
        yaw_targets = plan.foot_yaw_rad
    placed = ws.place_trunk(p_base_guess_m, yaw_rad, plan.p_foot_m, yaw_targets, p_com_target_m)
    if placed is not None:
        q, p_base, reachable = placed
        return q, p_base, rot, reachable
    p_base = p_base_guess_m.copy()
    for it in range(cfg.com_iterations + 1):
        q, reachable = ws.trunk_configurations(p_base, yaw_rad, rot, plan.p_foot_m, yaw_targets)
        if it == cfg.com_iterations:
            return q, p_base, rot, reachable
        err = p_com_target_m - ws._com(q)  # (h+1, 3)
        if ws.planar:
            err[:, 1] = 0.0
        p_base = p_base + err / ws.com_gain
    raise AssertionError("unreachable")  # pragma: no cover


def _build(
    ws: ReferenceWorkspace,
    timing: ReferenceTiming,
    plan: FootPlan,
    p_com_target_m: np.ndarray,
    p_base_guess_m: np.ndarray,
    yaw_rad: np.ndarray,
    yaw_rate_radps: float,
    pose0_angular_kgm2: np.ndarray,
) -> CentroidalReference:
    """IK trajectory, then v_ref by finite differences, h_ref (eq. 11), p_com_ref and
    H_ref (eq. 12 / 30); shared by f_ref and f_IK."""
    q, p_base, rot, reachable = _place_trunk(ws, plan, p_com_target_m, p_base_guess_m, yaw_rad)
    model, data = ws.model, ws.data
    times = timing.times_s  # (h+1,)
    n = times.size
    d_mat = timing.derivative_matrix  # (h+1, h+1)
    v = np.empty((n, model.nv))
    v[:, ws.robot.n_root_dofs :] = d_mat @ q[:, ws.robot.n_root_q :]
    if ws.planar:  # Euclidean root: v = dq/dt
        v[:, :3] = d_mat @ q[:, :3]
    else:  # local free-flyer velocity: R^T dp/dt, R^T e_z dpsi/dt
        p_dot = d_mat @ p_base  # (h+1, 3)
        yaw_dot = d_mat @ yaw_rad  # (h+1,), yaw_rad is continuous (not wrapped)
        v[:, 0:3] = np.einsum("kji,kj->ki", rot, p_dot)
        v[:, 3:6] = rot[:, 2, :] * yaw_dot[:, None]  # R^T e_z = third row of R
    h_ref, p_com = ws.momentum(q, v)  # eq. 11, h = A_G(q) v; the same pass gives the CoM
    dts = np.append(timing.dts_s, 0.0)  # (h+1,), the last entry is unused
    pose0 = np.concatenate([ws.mass_kg * p_com[0], pose0_angular_kgm2])
    if ws.config.pose_method == "eq30":
        h_pose = centroidal_pose_eq30(model, q, v, dts, data=data, subtract_initial=True)
        h_pose = h_pose - h_pose[0] + pose0
    else:
        h_pose = centroidal_pose_riemann(h_ref, dts, pose0)
        h_pose[:, :3] = ws.mass_kg * p_com  # exact primitive of the linear momentum
    return CentroidalReference(
        q_ref=q,
        v_ref=v,
        h_ref=h_ref,
        H_ref=h_pose,
        p_foot_ref=plan.p_foot_m,
        p_com_ref=p_com,
        reachable=np.asarray(reachable, dtype=bool),
        dts_s=np.array(timing.dts_s),
        times_s=times,
        p_base_ref=p_base,
        rot_base_ref=rot,
        yaw_ref_rad=yaw_rad,
        foot_yaw_ref_rad=plan.foot_yaw_rad,
        footholds_m=plan.footholds_m,
        foothold_yaw_rad=plan.foothold_yaw_rad,
        foothold_index=plan.index,
        swing_phase=plan.phase,
        timing=timing,
        time_in_swing_s=plan.time_in_swing_s,
        yaw_rate_radps=yaw_rate_radps,
        pose0_angular_kgm2=pose0_angular_kgm2,
        workspace=ws,
    )


# ----------------------------------------------------------------------- input parsing
def _command(command: ArrayLike | Command, planar: bool) -> tuple[np.ndarray, float]:
    """``(v_xy [m/s], yaw_rate [rad/s])`` from a :class:`Command` (or any object with its
    three fields, e.g. a controller's ramped command) or a ``(vx, vy, yaw_rate)`` array."""
    if hasattr(command, "vx_mps"):
        cmd = cast(Command, command)  # duck-typed: any object with Command's fields
        vx, vy, wz = cmd.vx_mps, cmd.vy_mps, cmd.yaw_rate_radps
    else:
        c = np.asarray(command, dtype=float).reshape(-1)
        if c.shape != (3,):
            raise ConfigError("command", command, "(vx [m/s], vy [m/s], yaw_rate [rad/s])")
        vx, vy, wz = c
    v = np.array([vx, vy], dtype=float)
    if not (np.all(np.isfinite(v)) and math.isfinite(wz)):
        raise ConfigError("command", command, "finite (vx, vy, yaw_rate)")
    if planar:
        return np.array([float(vx), 0.0]), 0.0
    return v, float(wz)


def _point(value: ArrayLike, name: str) -> np.ndarray:
    p = np.asarray(value, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ConfigError(name, value, "a finite (3,) point [m]")
    return p.copy()


def _targets(footholds: Mapping[str, ArrayLike] | None, foot: str) -> np.ndarray:
    if footholds is None or foot not in footholds:
        return np.empty((0, 3))
    t = np.asarray(footholds[foot], dtype=float)
    t = t.reshape(1, 3) if t.shape == (3,) else t
    if t.ndim != 2 or t.shape[1] != 3 or not np.all(np.isfinite(t)):
        raise ConfigError(f"footholds[{foot!r}]", footholds[foot], "(n, 3) or (3,) points [m]")
    return t


def _workspace(
    robot: RobotModel, workspace: ReferenceWorkspace | None, config: ReferenceConfig | None
) -> ReferenceWorkspace:
    if workspace is None:
        return ReferenceWorkspace(robot, config)
    if workspace.robot is not robot:
        raise ConfigError("workspace", workspace, f"a ReferenceWorkspace of {robot.name}")
    if config is not None and config != workspace.config:
        raise ConfigError("config", config, "None or the workspace's config")
    return workspace


# ------------------------------------------------------------------------------- f_ref
def make_reference(
    robot: RobotModel,
    q_now: ArrayLike,
    timing: ReferenceTiming | GaitHorizon,
    command: ArrayLike | Command,
    footholds: Mapping[str, ArrayLike] | None = None,
    *,
    p_foot_now_m: Mapping[str, ArrayLike] | None = None,
    p_liftoff_m: Mapping[str, ArrayLike] | None = None,
    p_com_start_m: ArrayLike | None = None,
    pose0_angular_kgm2: ArrayLike | None = None,
    workspace: ReferenceWorkspace | None = None,
    config: ReferenceConfig | None = None,
) -> CentroidalReference:
    """Reference trajectory ``f_ref`` (Algorithm 1, lines 2-3; module docstring).

    Typical use, once per MPC solve::

        ws = ReferenceWorkspace(robot)                   # once per controller
        ref = make_reference(robot, q, ReferenceTiming.from_horizon(schedule.horizon()),
                             command, {swing: [target], stance: [next_target]},
                             p_liftoff_m={swing: liftoff}, workspace=ws)
        ...                                              # sequential loop (Alg. 1)
        ref = update_reference(robot, ref, p_foot_iter, p_com_iter, dts_new)

    Args:
        robot: ``humanoid3d`` or ``biped2d``.
        q_now: (nq,) measured Pinocchio configuration; gives the current CoM, trunk
            heading and (by forward kinematics) the current foot positions and headings.
            The measured velocity is not needed: the reference follows the command, the
            measured momentum enters the MPC as ``x_0 = f_j2m(q, v)``.
        timing: stage timing and contact sequence (:class:`ReferenceTiming`); a
            :class:`gaitnet_mpc.gait.GaitHorizon` is converted with
            ``ReferenceTiming.from_horizon(timing)`` (``h' = 5``, boundary 0 = now).
        command: ``(vx [m/s], vy [m/s], yaw_rate [rad/s])`` with ``(vx, vy)`` in the heading
            (yaw) frame, or a :class:`gaitnet_mpc.command.Command` (or any object with
            its fields ``vx_mps, vy_mps, yaw_rate_radps``). The biped uses ``vx`` only.
        footholds: foot -> touchdown targets (n, 3) or (3,) [m] of that foot's upcoming
            swings in the horizon, in order: for the foot swinging now its current target,
            for the standing foot its next foothold, and so on. A missing target is
            replaced by the neutral point ``p_c(t_td) + R_z(psi(t_td)) (0, y_nom, 0) +
            v_cmd T_step / 2`` at the previous foothold's height (``y_nom`` the nominal
            lateral foot offset); controllers should pass their planned footholds.
        p_foot_now_m: foot -> (3,) current foot-centre positions [m]; None or a missing
            foot: forward kinematics of ``q_now``. Standing feet stay there.
        p_liftoff_m: foot -> (3,) lift-off point of a foot swinging in stage 0 [m]; a
            missing one falls back to the current position and the swing restarts now
            (``time_in_step_s`` treated as 0 for that foot).
        p_com_start_m: (3,) start of the CoM path [m] (x, y used; the height is always
            ``ground + com_height_m``); None: the CoM of ``q_now``.
        pose0_angular_kgm2: (3,) angular part of the measured centroidal pose ``H_0``
            [kg m^2] (the MPC's convention); None: zeros.
        workspace: per-robot scratch and constants (:class:`ReferenceWorkspace`); None:
            built here (slow, milliseconds).
        config: None or the workspace's config (used to build a workspace if none given).

    Returns:
        :class:`CentroidalReference` with ``h + 1`` boundaries.
    """
    ws = _workspace(robot, workspace, config)
    if isinstance(timing, GaitHorizon):
        timing = ReferenceTiming.from_horizon(timing)
    q_now = np.asarray(q_now, dtype=float).reshape(-1)
    if q_now.shape != (ws.model.nq,) or not np.all(np.isfinite(q_now)):
        raise ConfigError("q_now", q_now, f"a finite ({ws.model.nq},) Pinocchio configuration")
    v_cmd, yaw_rate = _command(command, ws.planar)
    times = timing.times_s  # (h+1,)
    n = times.size

    # measured state: CoM, trunk heading, feet (forward kinematics)
    com_now = np.array(pin.centerOfMass(ws.model, ws.data, q_now, False))
    pin.updateFramePlacements(ws.model, ws.data)
    if ws.planar:
        yaw0 = 0.0
    else:
        rot_now = pin.Quaternion(q_now[3:7]).normalized().toRotationMatrix()
        yaw0 = float(math.atan2(rot_now[1, 0], rot_now[0, 0]))
    fk_pos: dict[str, np.ndarray] = {}
    fk_yaw: dict[str, float] = {}
    for f in FEET:
        placement = ws.data.oMf[robot.pin_foot_frame_ids[f]]
        fk_pos[f] = placement.translation.copy()
        fk_yaw[f] = float(math.atan2(placement.rotation[1, 0], placement.rotation[0, 0]))
    p_now = {
        f: _point(p_foot_now_m[f], f"p_foot_now_m[{f!r}]")
        if p_foot_now_m is not None and f in p_foot_now_m
        else fk_pos[f]
        for f in FEET
    }

    # CoM target path (module docstring) and trunk heading
    start = com_now if p_com_start_m is None else _point(p_com_start_m, "p_com_start_m")
    stance0 = [f for i, f in enumerate(FEET) if timing.contact[0, i]] or list(FEET)
    ground_z = float(np.mean([p_now[f][2] for f in stance0])) - ws.contact_radius_m
    p_com_des = np.empty((n, 3))
    p_com_des[:, :2] = start[:2] + heading_displacement(v_cmd, yaw0, yaw_rate, times)
    p_com_des[:, 2] = ground_z + ws.com_height_m
    if ws.planar:
        p_com_des[:, 1] = com_now[1]
    yaw = yaw0 + yaw_rate * times  # (h+1,)

    # footholds and foot timelines
    index = np.empty((n, _N_FEET), dtype=np.int64)
    phase = np.empty((n, _N_FEET))
    time_in_swing = np.zeros(_N_FEET)
    fh_all: dict[str, np.ndarray] = {}
    fh_yaw: dict[str, np.ndarray] = {}
    for i, f in enumerate(FEET):
        first: np.ndarray = p_now[f]
        if not timing.contact[0, i] and p_liftoff_m is not None and f in p_liftoff_m:
            first = _point(p_liftoff_m[f], f"p_liftoff_m[{f!r}]")
            time_in_swing[i] = timing.time_in_step_s
        line = foot_timeline(timing, i, times, float(time_in_swing[i]))
        index[:, i], phase[:, i] = line.index, line.phase
        given = _targets(footholds, f)
        pts = [first]
        yaws = [fk_yaw[f]]
        for s_i, sw in enumerate(line.swings):
            yaw_td = yaw0 + yaw_rate * sw.t_touchdown_s
            if s_i < given.shape[0]:
                pts.append(given[s_i].copy())
            else:
                t_step = timing.stages_per_step * float(timing.stage_lengths_s[sw.first_stage])
                lateral = ws.foot_lateral_m[f]
                pts.append(
                    neutral_foothold(
                        start, v_cmd, yaw0, yaw_rate, sw, t_step, pts[-1], lateral, ws.planar
                    )
                )
            yaws.append(yaw_td)
        fh_all[f] = np.array(pts)
        fh_yaw[f] = unwrap_angles(yaws)
    plan = foot_plan(
        index, phase, fh_all, fh_yaw, time_in_swing, ws.config.swing_apex_height_m, ws.planar
    )

    rot = ws.trunk_frames(yaw)[0]
    p_base0 = p_com_des - rot @ ws.com_offset_trunk_m  # nominal trunk-to-CoM offset
    pose0 = (
        np.zeros(3)
        if pose0_angular_kgm2 is None
        else np.asarray(pose0_angular_kgm2, dtype=float).reshape(3).copy()
    )
    return _build(ws, timing, plan, p_com_des, p_base0, yaw, yaw_rate, pose0)


# -------------------------------------------------------------------------------- f_IK
def update_reference(
    robot: RobotModel,
    ref: CentroidalReference,
    p_foot_iter_m: ArrayLike | Mapping[str, ArrayLike] | None,
    p_com_iter_m: ArrayLike | None,
    dts_s: ArrayLike | None = None,
) -> CentroidalReference:
    """Re-solve the reference from the MPC iterate: ``f_IK`` (Algorithm 1, line 9; Remark 1).

    Keeps the contact sequence, the trunk heading law and the swing shape of ``ref``;
    moves the footholds to the iterates, places the trunk so that the CoM of every stage
    goes to ``p_com_iter_m`` (start: the previous reference's trunk-to-CoM offset, then
    ``config.com_iterations`` fixed-point corrections), re-runs the analytic IK and
    recomputes ``v_ref``, ``h_ref`` (eq. 11), ``p_com_ref`` and ``H_ref`` (eq. 12 / 30).

    Args:
        robot: the robot of ``ref``.
        ref: the previous reference (from :func:`make_reference` or this function); its
            workspace is reused.
        p_foot_iter_m: foothold iterates ``p_f^j``: (h+1, 2, 3) at the boundaries or
            (h, 2, 3) per stage [m]. Row ``k`` of a foot is read only if the foot is in
            contact in stage ``k`` (row ``h``: stage ``h - 1``); a swinging foot's rows are
            ignored. Each foothold becomes the mean of its rows, and swing feet move toward
            the new touchdown point along the same swing shape. Footholds with no row in
            contact keep their value (the lift-off point of the foot swinging now).
            Or a mapping foot -> (n, 3) new touchdown targets (as in :func:`make_reference`,
            ``F_1, F_2, ...``). None keeps the footholds. The biped ignores y.
        p_com_iter_m: (h+1, 3) CoM iterate ``p_c^j`` [m]; None keeps ``ref.p_com_ref``.
            The biped ignores y.
        dts_s: (h,) new stage durations (Gait-Net, Alg. 1 line 8) [s]; None keeps them.
            Swing phases are recomputed on the new stage times.

    Returns:
        A new :class:`CentroidalReference` (``ref`` is not modified).
    """
    ws = ref.workspace
    if ws.robot is not robot:
        raise ConfigError("robot", robot.name, "the robot the reference was made for")
    h = ref.horizon
    if dts_s is not None and np.array_equal(dts_s, ref.timing.dts_s):
        dts_s = None  # the same durations (every f_IK call of a sequential solve)
    timing = ref.timing if dts_s is None else ref.timing.with_dts(dts_s)
    times = timing.times_s

    # footholds
    if p_foot_iter_m is None:
        footholds = ref.footholds_m
    elif isinstance(p_foot_iter_m, Mapping):
        footholds = {}
        for f in FEET:
            old = ref.footholds_m[f]
            new = _targets(p_foot_iter_m, f)[: old.shape[0] - 1]
            fh = old.copy()
            fh[1 : 1 + new.shape[0]] = new
            if ws.planar:
                fh[:, 1] = old[:, 1]
            footholds[f] = fh
    else:
        p_iter = np.asarray(p_foot_iter_m, dtype=float)
        if not np.all(np.isfinite(p_iter)):
            raise ConfigError("p_foot_iter_m", "non-finite", "finite foot iterates [m]")
        footholds = footholds_from_iterates(
            p_iter,
            ref.timing.contact,
            ref.foothold_index,
            ref.swing_phase,
            ref.footholds_m,
            ws.planar,
        )

    # timing-dependent quantities: swing phases, trunk heading, foothold headings
    if dts_s is None:
        index, phase = ref.foothold_index, ref.swing_phase
        yaw = ref.yaw_ref_rad
        fh_yaw = ref.foothold_yaw_rad
    else:
        index = np.empty_like(ref.foothold_index)
        phase = np.empty_like(ref.swing_phase)
        yaw = ref.yaw_ref_rad[0] + ref.yaw_rate_radps * times
        fh_yaw = {}
        for i, f in enumerate(FEET):
            line = foot_timeline(timing, i, times, float(ref.time_in_swing_s[i]))
            index[:, i], phase[:, i] = line.index, line.phase
            yaws = ref.foothold_yaw_rad[f].copy()
            for s_i, sw in enumerate(line.swings):
                yaws[s_i + 1] = yaw[0] + ref.yaw_rate_radps * sw.t_touchdown_s
            fh_yaw[f] = yaws
    plan = foot_plan(
        index,
        phase,
        footholds,
        fh_yaw,
        ref.time_in_swing_s,
        ws.config.swing_apex_height_m,
        ws.planar,
    )

    # CoM target and the initial trunk guess from the previous trunk-to-CoM offsets
    if p_com_iter_m is None:
        p_com_target = ref.p_com_ref.copy()
    else:
        p_com_target = np.array(p_com_iter_m, dtype=float)
        if p_com_target.shape != (h + 1, 3) or not np.all(np.isfinite(p_com_target)):
            raise ConfigError("p_com_iter_m", p_com_iter_m, f"a finite ({h + 1}, 3) CoM path [m]")
        if ws.planar:
            p_com_target[:, 1] = ref.p_com_ref[:, 1]
    # previous trunk-to-CoM offset, corrected to first order for the leg folding and for
    # the CoM shift that the foot moves cause
    d_com = p_com_target - ref.p_com_ref
    d_com -= np.einsum("fi,kfi->ki", ws.com_gain_feet, plan.p_foot_m - ref.p_foot_ref)
    p_base0 = ref.p_base_ref + d_com / ws.com_gain
    return _build(
        ws, timing, plan, p_com_target, p_base0, yaw, ref.yaw_rate_radps, ref.pose0_angular_kgm2
    )
