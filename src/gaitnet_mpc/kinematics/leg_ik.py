"""Analytic inverse kinematics of the legs (paper Appendix B, eqs. 31-40), batched over N.

This module holds the derivation, the geometry readers and the checked entry points; the
per-row arithmetic runs compiled in :mod:`~gaitnet_mpc.kinematics.leg_ik_kernel` (a
3-row whole-body IK: about 21 us against 85-125 us for the NumPy form it replaced,
``docs/design/realtime.md`` item 4; the two agree to 3e-14 rad).

5-DoF humanoid leg (``humanoid3d``)
===================================

Joint order (= the leg's actuator order): ``q = [hip_yaw q0, hip_roll q1, hip_pitch q2,
knee q3, ankle_pitch q4]``. All geometry is read from the MJCF (:func:`leg_geometry`); for
``humanoid3d`` (side sign ``s = +1`` left, ``-1`` right, lengths in m, trunk frame ``B``):

* hip yaw joint at ``p_yaw = (0, 0.045 s, -0.17)`` in ``B``, axis ``z``;
* hip roll joint at ``p_roll = (0, 0, -0.05)`` in the yaw link, axis ``x``;
* hip pitch joint at ``p_pitch = (0, 0.02 s, 0)`` in the roll link (Appendix B's
  ``r_{21,y}``), axis ``y``;
* knee ``l1 = 0.22`` below the hip pitch joint, ankle ``l2 = 0.22`` below the knee, both
  axis ``y``; knee flexion is positive (range 0..2.4 rad);
* the foothold point ``p_f`` is the site ``{side}_foot_center`` at ``c = (0.015, 0, 0)`` in
  the foot frame (line foot along the foot ``x`` axis).

Forward kinematics (``Rx, Ry, Rz`` elementary rotations, ``theta = q2 + q3 + q4``)::

    p_f^B = p_yaw + Rz(q0) [p_roll + Rx(q1) (p_pitch + Ry(q2) (0,0,-l1)
                                             + Ry(q2+q3) (0,0,-l2) + Ry(theta) c)]
    R_foot^B = Rz(q0) Rx(q1) Ry(theta)

Closed form used here (every step exact, no iteration):

1. Target in the trunk frame (eqs. 36-37 with the trunk origin instead of the CoM):
   ``p^B = R_WB^T (p_f^W - p_WB)``.
2. Hip yaw (eq. 31 generalised): ``q0 = wrap(psi_des - psi_B)`` with ``psi_B =
   atan2(R_WB[1,0], R_WB[0,0])`` the trunk heading; the default ``psi_des = psi_B`` gives
   ``q0 = 0`` exactly as eq. 31.
3. Roll-joint-to-target vector in the yaw link (eq. 36): ``r1 = Rz(q0)^T (p^B - p_yaw) -
   p_roll``. Every link after the roll joint moves in the roll link's x-z plane, offset by
   ``w = p_pitch_y`` (``r_{21,y}``) along its y axis, so the y row of the FK reads
   ``cos(q1) r1_y + sin(q1) r1_z = w``, whose solution with the leg hanging down is
   (eqs. 33, 38) ``q1 = atan2(r1_z, r1_y) + arccos(w / rho)``, ``rho = |(r1_y, r1_z)|``,
   evaluated as the single ``atan2(r1_z w + r1_y k, r1_y w - r1_z k)``,
   ``k = sqrt(rho^2 - w^2)``, which needs no angle wrapping.
4. Foot horizontal in the world (eq. 32 generalised to trunk roll/pitch/yaw and hip
   roll/yaw): with ``g = Rz(q0)^T R_WB^T e_z`` (world up in the yaw link) the foot axis
   ``u = Rx(q1) Ry(theta) e_x`` satisfies ``g . u = 0`` iff
   ``theta = atan2(g_x, g_z cos q1 - g_y sin q1)`` (the branch whose sole faces down).
5. ``q1`` and ``theta`` do not depend on ``q2, q3``, so the 0.015 m foot-centre offset is
   removed exactly: ankle in the pitch-joint x-z plane
   ``a = (Rx(q1)^T r1 - p_pitch)_{xz} - Ry(theta) c``.
6. Planar two-link chain (eqs. 34, 35, 40): ``d = |a|``,
   ``q3 = arccos((d^2 - l1^2 - l2^2) / (2 l1 l2))`` and
   ``q2 = atan2(-a_x, -a_z) - atan2(l2 sin q3, l1 + l2 cos q3)`` (again one ``atan2``).
7. Ankle (eq. 32): ``q4 = theta - q2 - q3``, wrapped to ``(-pi, pi]``.

Deviations from Appendix B (and why)
------------------------------------

* Signs: the MJCF uses right-handed joint axes with knee flexion positive, so eq. 35
  (``q3 = 2 arcsin(r_xz / 2l) - pi <= 0``) becomes ``q3 = pi - 2 arcsin(d / 2l)`` (same
  magnitude, opposite sign), written with ``arccos`` to allow ``l1 != l2``; eq. 34's hip
  pitch and eq. 33's hip roll are written with ``atan2`` instead of ``arccos``/``arcsin``
  sums so that all quadrants and both sides (``s = +-1``) are handled by one formula.
* The foothold point ``p_f`` is 0.015 m ahead of the ankle (the paper's ``p_f`` is the
  ankle). Step 5 removes the offset exactly because roll and foot pitch are solved first.
* Eq. 31 (``q0 = 0``) is generalised to a desired world foot yaw ``psi_des``:
  ``q0 = wrap(psi_des - psi_B)``, i.e. ``foot_yaw_rad`` sets the hip yaw relative to the
  trunk heading. With zero trunk roll/pitch the foot heading then equals ``psi_des``
  exactly; with a tilted trunk it does not (the heading is not a constraint of the
  closed form): the error is first order in the tilt times the hip roll/yaw angles,
  measured at most 0.03 rad for 0.1 rad trunk tilt and 0.17 rad for 0.3 rad tilt (the
  foot position and the level foot axis stay exact). The same holds for the default
  ``q0 = 0`` of eq. 31.
* Eq. 32 (``q4 = -q2 - q3 - theta_body``) keeps the foot level only for a trunk pitched
  in the sagittal plane; step 4 keeps the foot's long axis exactly horizontal for any trunk
  orientation and hip roll/yaw (it reduces to eq. 32 when roll = yaw = 0). The foot roll
  is not controllable (no ankle roll), which a line foot does not need.
* Eq. 37 takes the hip position from the CoM ``p_c`` and ``r_c1``; here it is taken from
  the trunk (root joint) frame, which is where the MJCF defines the hip.
* Eq. 40's ``r_{1,xz}`` is the pitch-joint-to-target distance; here ``d`` is the
  pitch-joint-to-*ankle* distance after removing the foot offset (step 5).

Out-of-reach targets (``d > l1 + l2``, ``d`` below the knee-limit minimum, ``rho < |w|``)
and solutions past a joint limit are mapped to the nearest feasible solution: each joint is
clipped to its range in the order ``q0, q1, q3, q2, q4`` and the later joints are computed
from the clipped earlier ones (so the foot stays horizontal whenever ``q4`` is inside its
range); the result is always finite and within limits, and ``reachable`` is False.

Planar biped leg (``biped2d``)
==============================

``q = [hip_pitch, knee]`` with the hip at ``p_hip`` in the trunk frame and two links
``l1, l2`` hanging along ``-z`` (the foot point is the end of the shank); step 6 of the
5-DoF leg with the target rotated into the trunk frame by the trunk pitch (the root hinge
about ``y``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gaitnet_mpc.kinematics.leg_ik_kernel import leg_ik_rows, planar_leg_ik_rows
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET

_TOL_GEOMETRY = 1e-12


# ------------------------------------------------------------------------ data types
@dataclass(frozen=True)
class LegGeometry:
    """Kinematic parameters of one 5-DoF leg, read from the MJCF (lengths in m).

    Attributes:
        foot: ``"left"`` or ``"right"``.
        p_yaw_trunk_m: hip yaw joint in the trunk frame (3,).
        p_roll_yaw_m: hip roll joint in the hip-yaw link frame (3,).
        p_pitch_roll_m: hip pitch joint in the hip-roll link frame (3,); its y entry is
            Appendix B's ``r_{21,y}`` (signed, ``+0.02`` left, ``-0.02`` right).
        thigh_m: hip pitch joint to knee, along ``-z`` (``l1``).
        shank_m: knee to ankle pitch joint, along ``-z`` (``l2``).
        p_foot_ankle_m: foothold point ``p_f`` in the foot (ankle) frame (3,), y = 0.
        lower_rad: joint lower limits (5,), leg joint order.
        upper_rad: joint upper limits (5,), leg joint order.
    """

    foot: str
    p_yaw_trunk_m: np.ndarray
    p_roll_yaw_m: np.ndarray
    p_pitch_roll_m: np.ndarray
    thigh_m: float
    shank_m: float
    p_foot_ankle_m: np.ndarray
    lower_rad: np.ndarray
    upper_rad: np.ndarray


@dataclass(frozen=True)
class PlanarLegGeometry:
    """Kinematic parameters of one planar 2-DoF leg (biped2d), lengths in m.

    Attributes:
        foot: ``"left"`` or ``"right"``.
        p_hip_trunk_xz_m: hip pitch joint (x, z) in the trunk frame (2,).
        thigh_m: hip to knee along ``-z`` (``l1``).
        shank_m: knee to the foot point along ``-z`` (``l2``).
        lower_rad: joint lower limits (2,) ``[hip_pitch, knee]``.
        upper_rad: joint upper limits (2,).
    """

    foot: str
    p_hip_trunk_xz_m: np.ndarray
    thigh_m: float
    shank_m: float
    lower_rad: np.ndarray
    upper_rad: np.ndarray


class LegIKSolution(NamedTuple):
    """Result of a vectorised leg IK call.

    Attributes:
        q_rad: joint angles (N, n_leg_joints) in the leg's joint order, always finite and
            within the joint limits.
        reachable: (N,) False where the target was out of reach or a joint was clipped.
    """

    q_rad: np.ndarray
    reachable: np.ndarray


class WholeBodyIKSolution(NamedTuple):
    """Result of :func:`whole_body_ik`.

    Attributes:
        joint_pos_rad: (N, n_joints) actuated joint angles in actuator (= Pinocchio) order.
        reachable: (N,) True where every requested foot target was reached exactly.
    """

    joint_pos_rad: np.ndarray
    reachable: np.ndarray


# ---------------------------------------------------------------- geometry readers
def _chain(robot: RobotModel, foot: str) -> tuple[list[int], list[int]]:
    m = robot.mj_model
    jids = [m.joint(name).id for name in robot.spec.leg_joints[foot]]
    bids = [int(m.jnt_bodyid[j]) for j in jids]
    for parent, child in zip([robot.trunk_body_id, *bids[:-1]], bids, strict=True):
        if int(m.body_parentid[child]) != parent:
            raise ValueError(f"{robot.name}/{foot}: leg bodies do not form a serial chain")
    for j, b in zip(jids, bids, strict=True):
        if np.any(np.abs(m.jnt_pos[j]) > _TOL_GEOMETRY):
            raise ValueError(f"{robot.name}: joint {m.joint(j).name} is offset in its body")
        if np.any(np.abs(m.body_quat[b] - np.array([1.0, 0, 0, 0])) > _TOL_GEOMETRY):
            raise ValueError(f"{robot.name}: body {m.body(b).name} is rotated")
    return jids, bids


def _check_axes(robot: RobotModel, jids: list[int], axes: list[int]) -> None:
    m = robot.mj_model
    for j, k in zip(jids, axes, strict=True):
        expected = np.eye(3)[k]
        if np.any(np.abs(m.jnt_axis[j] - expected) > _TOL_GEOMETRY):
            raise ValueError(f"{robot.name}: joint {m.joint(j).name} axis is not {expected}")


def _downward_length(pos: np.ndarray, what: str) -> float:
    if abs(pos[0]) > _TOL_GEOMETRY or abs(pos[1]) > _TOL_GEOMETRY or pos[2] >= 0.0:
        raise ValueError(f"{what} must lie straight below its parent joint, got {pos}")
    return float(-pos[2])


def leg_geometry(robot: RobotModel, foot: str) -> LegGeometry:
    """Read the 5-DoF leg geometry of ``foot`` from the robot's MJCF (see module docstring).

    Raises:
        ValueError: if the MJCF leg does not have the yaw-roll-pitch-pitch-pitch structure
            assumed by the closed form (non-zero joint offsets, rotated bodies, other axes).
    """
    if robot.spec.planar:
        raise ValueError(f"{robot.name} is planar; use planar_leg_geometry")
    m = robot.mj_model
    jids, bids = _chain(robot, foot)
    _check_axes(robot, jids, [2, 0, 1, 1, 1])
    site = robot.foot_site_ids[foot]
    if int(m.site_bodyid[site]) != bids[4]:
        raise ValueError(f"{robot.name}: foot site is not on the ankle body")
    if abs(m.site_pos[site][1]) > _TOL_GEOMETRY:
        raise ValueError(f"{robot.name}: foot site must lie in the foot's x-z plane")
    return LegGeometry(
        foot=foot,
        p_yaw_trunk_m=np.array(m.body_pos[bids[0]], dtype=float),
        p_roll_yaw_m=np.array(m.body_pos[bids[1]], dtype=float),
        p_pitch_roll_m=np.array(m.body_pos[bids[2]], dtype=float),
        thigh_m=_downward_length(m.body_pos[bids[3]], "knee"),
        shank_m=_downward_length(m.body_pos[bids[4]], "ankle"),
        p_foot_ankle_m=np.array(m.site_pos[site], dtype=float),
        lower_rad=np.array(robot.joint_lower_rad[robot.leg_joint_index[foot]], dtype=float),
        upper_rad=np.array(robot.joint_upper_rad[robot.leg_joint_index[foot]], dtype=float),
    )


def planar_leg_geometry(robot: RobotModel, foot: str) -> PlanarLegGeometry:
    """Read the planar 2-DoF leg geometry of ``foot`` (biped2d) from the MJCF.

    Raises:
        ValueError: if the leg is not a hip-pitch/knee chain with the foot site straight
            below the knee.
    """
    if not robot.spec.planar:
        raise ValueError(f"{robot.name} is not planar; use leg_geometry")
    m = robot.mj_model
    jids, bids = _chain(robot, foot)
    _check_axes(robot, jids, [1, 1])
    site = robot.foot_site_ids[foot]
    if int(m.site_bodyid[site]) != bids[1]:
        raise ValueError(f"{robot.name}: foot site is not on the shank body")
    p_hip = np.array(m.body_pos[bids[0]], dtype=float)
    return PlanarLegGeometry(
        foot=foot,
        p_hip_trunk_xz_m=p_hip[[0, 2]],
        thigh_m=_downward_length(m.body_pos[bids[1]], "knee"),
        shank_m=_downward_length(m.site_pos[site], "foot site"),
        lower_rad=np.array(robot.joint_lower_rad[robot.leg_joint_index[foot]], dtype=float),
        upper_rad=np.array(robot.joint_upper_rad[robot.leg_joint_index[foot]], dtype=float),
    )


# ------------------------------------------------------------------------- helpers
def _as_batch(
    p_foot_world_m: np.ndarray, p_trunk_world_m: np.ndarray, rot_trunk_world: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p_f = np.asarray(p_foot_world_m, dtype=float).reshape(-1, 3)
    p_b = np.asarray(p_trunk_world_m, dtype=float).reshape(-1, 3)
    rot = np.asarray(rot_trunk_world, dtype=float).reshape(-1, 3, 3)
    n = max(p_f.shape[0], p_b.shape[0], rot.shape[0])
    return _rows(p_f, n), _rows(p_b, n), _rows(rot, n)


def _rows(a: np.ndarray, n: int) -> np.ndarray:
    """``a`` with ``n`` rows (one row repeated) as a C-contiguous array, for the kernels."""
    if a.shape[0] != n:
        a = np.broadcast_to(a, (n, *a.shape[1:]))
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


# ---------------------------------------------------------------------- 5-DoF leg IK
def leg_ik(
    geom: LegGeometry,
    p_foot_world_m: np.ndarray,
    p_trunk_world_m: np.ndarray,
    rot_trunk_world: np.ndarray,
    foot_yaw_rad: np.ndarray | float | None = None,
    tol: float = 1e-9,
) -> LegIKSolution:
    """Analytic 5-DoF leg IK (Appendix B, eqs. 31-40; derivation in the module docstring).

    Args:
        geom: leg geometry from :func:`leg_geometry`.
        p_foot_world_m: desired foothold (foot-centre site) positions (N, 3) or (3,) [m].
        p_trunk_world_m: trunk (root joint frame) positions (N, 3) or (3,) [m].
        rot_trunk_world: trunk rotation matrices world<-trunk (N, 3, 3) or (3, 3).
        foot_yaw_rad: desired world heading of the foot axis (N,) or scalar [rad], applied
            as ``q0 = wrap(foot_yaw - trunk heading)`` (exact heading for a level trunk only,
            see the module docstring); None (default): ``q0 = 0`` (eq. 31).
        tol: tolerance [m, rad, or on the knee cosine] before a target counts as
            unreachable or a joint as past its limit.

    Returns:
        :class:`LegIKSolution` with ``q_rad`` (N, 5) ``[yaw, roll, pitch, knee, ankle]`` and
        ``reachable`` (N,).
    """
    p_f, p_b, rot = _as_batch(p_foot_world_m, p_trunk_world_m, rot_trunk_world)
    n = p_f.shape[0]
    if foot_yaw_rad is None:
        yaw = np.zeros(n)
    else:
        yaw = _rows(np.asarray(foot_yaw_rad, dtype=float).reshape(-1), n)
    q = np.empty((n, 5))
    reachable = np.empty(n, dtype=bool)
    leg_ik_rows(
        p_f, p_b, rot, yaw, foot_yaw_rad is not None, geom.p_yaw_trunk_m, geom.p_roll_yaw_m,
        geom.p_pitch_roll_m, geom.thigh_m, geom.shank_m, geom.p_foot_ankle_m, geom.lower_rad,
        geom.upper_rad, tol, q, reachable,
    )  # fmt: skip
    return LegIKSolution(q, reachable)


# ---------------------------------------------------------------------- planar leg IK
def planar_leg_ik(
    geom: PlanarLegGeometry,
    p_foot_xz_m: np.ndarray,
    p_trunk_xz_m: np.ndarray,
    trunk_pitch_rad: np.ndarray | float,
    tol: float = 1e-9,
) -> LegIKSolution:
    """Analytic IK of the planar biped leg (eqs. 34-35, 40 in the sagittal plane).

    The trunk rotation is ``Ry(pitch)`` (root hinge about ``y``), so a world vector
    ``(x, z)`` is ``(c x - s z, s x + c z)`` in the trunk frame.

    Args:
        geom: from :func:`planar_leg_geometry`.
        p_foot_xz_m: desired foot-point positions (N, 2) or (2,) as world (x, z) [m].
        p_trunk_xz_m: trunk positions (N, 2) or (2,) as world (x, z) [m].
        trunk_pitch_rad: trunk pitch (N,) or scalar [rad].
        tol: tolerance before a target counts as unreachable / past a limit.

    Returns:
        :class:`LegIKSolution` with ``q_rad`` (N, 2) ``[hip_pitch, knee]`` (knee flexion
        positive) and ``reachable`` (N,).
    """
    d = np.asarray(p_foot_xz_m, dtype=float).reshape(-1, 2) - np.asarray(
        p_trunk_xz_m, dtype=float
    ).reshape(-1, 2)  # (N, 2)
    pitch = np.asarray(trunk_pitch_rad, dtype=float).reshape(-1)
    c, s = np.cos(pitch), np.sin(pitch)
    ax = c * d[:, 0] - s * d[:, 1] - geom.p_hip_trunk_xz_m[0]
    az = s * d[:, 0] + c * d[:, 1] - geom.p_hip_trunk_xz_m[1]
    q = np.empty((ax.shape[0], 2))
    reachable = np.empty(ax.shape[0], dtype=bool)
    planar_leg_ik_rows(
        ax, az, geom.thigh_m, geom.shank_m, geom.lower_rad, geom.upper_rad, tol, q, reachable
    )
    return LegIKSolution(q, reachable)


# -------------------------------------------------------------------- whole body
def leg_geometries(robot: RobotModel) -> dict[str, LegGeometry | PlanarLegGeometry]:
    """Geometry of every leg of ``robot`` (planar for biped2d), to reuse across IK calls."""
    read = planar_leg_geometry if robot.spec.planar else leg_geometry
    return {foot: read(robot, foot) for foot in FEET}


def whole_body_ik(
    robot: RobotModel,
    p_base_world_m: np.ndarray,
    rot_base_world: np.ndarray,
    p_foot_world_m: dict[str, np.ndarray],
    foot_yaw_rad: dict[str, np.ndarray] | None = None,
    tol: float = 1e-9,
    geometries: dict[str, LegGeometry | PlanarLegGeometry] | None = None,
) -> WholeBodyIKSolution:
    """Joint angles of the whole robot: legs by analytic IK, arms (and any leg without a
    target) at the nominal pose (:meth:`RobotModel.nominal_joint_pos`).

    Args:
        robot: ``humanoid3d`` or ``biped2d``.
        p_base_world_m: trunk positions (N, 3) or (3,) [m] (biped: the y entry is ignored).
        rot_base_world: trunk rotations (N, 3, 3) or (3, 3) (biped: must be ``Ry(pitch)``,
            as from :meth:`RobotModel.base_pose`).
        p_foot_world_m: foot -> desired foot-centre positions (N, 3) [m].
        foot_yaw_rad: optional foot -> desired world foot heading (N,) [rad] (humanoid only;
            default: trunk heading, ``q0 = 0``).
        tol: see :func:`leg_ik`.
        geometries: output of :func:`leg_geometries` to skip re-reading the MJCF (the read
            costs more than the IK itself).

    Returns:
        :class:`WholeBodyIKSolution`: ``joint_pos_rad`` (N, n_joints) in actuator order and
        ``reachable`` (N,), the AND over the requested feet.
    """
    geoms = leg_geometries(robot) if geometries is None else geometries
    p_base = np.asarray(p_base_world_m, dtype=float).reshape(-1, 3)
    rot = np.asarray(rot_base_world, dtype=float).reshape(-1, 3, 3)
    targets = {}
    for foot, target in p_foot_world_m.items():
        if foot not in FEET:
            raise ValueError(f"unknown foot {foot!r}; expected one of {FEET}")
        targets[foot] = np.asarray(target, dtype=float).reshape(-1, 3)
    n = max(p_base.shape[0], rot.shape[0], *(t.shape[0] for t in targets.values()))
    q = np.tile(robot.nominal_joint_pos(), (n, 1))  # (N, n_joints)
    ok = np.ones(n, dtype=bool)
    for foot, target in targets.items():
        yaw = None if foot_yaw_rad is None else foot_yaw_rad.get(foot)
        sol = foot_ik(geoms[foot], target, p_base, rot, yaw, tol)
        q[:, robot.leg_joint_index[foot]] = sol.q_rad
        ok &= sol.reachable
    return WholeBodyIKSolution(q, ok)


def foot_ik(
    geom: LegGeometry | PlanarLegGeometry,
    p_foot_world_m: np.ndarray,
    p_base_world_m: np.ndarray,
    rot_base_world: np.ndarray,
    foot_yaw_rad: np.ndarray | None = None,
    tol: float = 1e-9,
) -> LegIKSolution:
    """One leg's IK by its geometry: :func:`leg_ik`, or :func:`planar_leg_ik` for the
    biped (trunk pitch read from ``rot_base_world``, ``foot_yaw_rad`` ignored). Shapes
    as in :func:`whole_body_ik`."""
    if isinstance(geom, PlanarLegGeometry):
        target = np.asarray(p_foot_world_m, dtype=float).reshape(-1, 3)
        p_base = np.asarray(p_base_world_m, dtype=float).reshape(-1, 3)
        rot = np.asarray(rot_base_world, dtype=float).reshape(-1, 3, 3)
        pitch = np.arctan2(rot[:, 0, 2], rot[:, 0, 0])
        return planar_leg_ik(geom, target[:, [0, 2]], p_base[:, [0, 2]], pitch, tol)
    return leg_ik(geom, p_foot_world_m, p_base_world_m, rot_base_world, foot_yaw_rad, tol)
