"""The data of the joint-space reference (:mod:`gaitnet_mpc.kinematics.reference`): its
settings (:class:`ReferenceConfig`), the per-robot workspace shared by every call
(:class:`ReferenceWorkspace`), the result (:class:`CentroidalReference`) and the trunk
rotations / Pinocchio configurations of a trajectory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pinocchio as pin

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.timing import ReferenceTiming
from gaitnet_mpc.kinematics.foot_plan_kernel import foothold_means, plan_rows
from gaitnet_mpc.kinematics.leg_ik import (
    LegGeometry,
    PlanarLegGeometry,
    leg_geometries,
    whole_body_ik,
)
from gaitnet_mpc.kinematics.leg_ik_kernel import leg_ik_rows
from gaitnet_mpc.kinematics.rigid_body_kernel import KinematicTree, tree_of
from gaitnet_mpc.kinematics.trunk_placement_kernel import place_trunk_rows
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET

_N_FEET = len(FEET)

#: Definitions of ``H_ref`` (``ReferenceConfig.pose_method``; the module docstring of
#: :mod:`~gaitnet_mpc.kinematics.reference`).
PoseMethod = Literal["riemann", "eq30"]
POSE_METHODS: tuple[PoseMethod, ...] = ("riemann", "eq30")
_GAIN_PROBE_M = 0.01  # trunk / foot displacement that probes the CoM gains [m]


# ------------------------------------------------------------------------ configuration
@dataclass(frozen=True)
class ReferenceConfig:
    """Shape of the reference motion (f_ref) and of its update (f_IK).

    Attributes:
        com_height_m: CoM height above the ground under the stance feet [m]; None: the
            nominal standing pose's (humanoid3d 0.555 m, biped2d 0.502 m).
        swing_apex_height_m: swing apex above ``max(lift-off z, touchdown z)`` [m].
        trunk_pitch_rad: constant trunk pitch [rad] (roll is always 0).
        com_iterations: fixed-point corrections of the trunk position that put the CoM of
            the IK configuration on the target CoM path (module docstring); each costs one
            whole-body IK and ``h + 1`` CoM evaluations [-].
        pose_method: ``"riemann"`` or ``"eq30"``, the definition of ``H_ref`` (module
            docstring).
    """

    com_height_m: float | None = None
    swing_apex_height_m: float = 0.06
    trunk_pitch_rad: float = 0.0
    com_iterations: int = 1
    pose_method: PoseMethod = "riemann"

    def __post_init__(self) -> None:
        if self.com_height_m is not None and not _positive(self.com_height_m):
            raise ConfigError("com_height_m", self.com_height_m, "a finite height > 0 m or None")
        a = self.swing_apex_height_m
        if not (_is_number(a) and math.isfinite(a) and a >= 0.0):
            raise ConfigError("swing_apex_height_m", a, "a finite height >= 0 m")
        p = self.trunk_pitch_rad
        if not (_is_number(p) and math.isfinite(p) and abs(p) < 0.5 * math.pi):
            raise ConfigError("trunk_pitch_rad", p, "a finite angle in (-pi/2, pi/2) rad")
        n = self.com_iterations
        if not isinstance(n, int | np.integer) or isinstance(n, bool) or n < 0:
            raise ConfigError("com_iterations", n, "an integer >= 0")
        if self.pose_method not in POSE_METHODS:
            raise ConfigError("pose_method", self.pose_method, f"one of {list(POSE_METHODS)}")


def _is_number(value: object) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


def _positive(value: object) -> bool:
    return _is_number(value) and math.isfinite(value) and value > 0.0  # type: ignore[arg-type, operator]


# --------------------------------------------------------------------------- workspace
class ReferenceWorkspace:
    """Per-robot constants and scratch data shared by every reference call.

    Holds the Pinocchio data, the leg geometries, the total mass, the nominal CoM height,
    the nominal trunk-to-CoM offset, the nominal lateral foot offsets and the CoM gains
    ``G = diag(d c / d p_B)`` (feet fixed) and ``diag(d c / d p_f)`` (trunk fixed) of the
    fixed-point CoM placement. Not thread-safe (the Pinocchio data is scratch space);
    create one per controller. Building it costs a few milliseconds.

    Args:
        robot: ``humanoid3d`` or ``biped2d``.
        config: reference settings; None: defaults.
    """

    def __init__(self, robot: RobotModel, config: ReferenceConfig | None = None) -> None:
        self.robot = robot
        self.config = config if config is not None else ReferenceConfig()
        self.model: pin.Model = robot.pin_model
        self.data: pin.Data = self.model.createData()
        self.geometries: dict[str, LegGeometry | PlanarLegGeometry] = leg_geometries(robot)
        self.mass_kg = float(pin.computeTotalMass(self.model))
        self.planar = bool(robot.spec.planar)
        self.contact_radius_m = float(robot.spec.foot_contact_radius_m)
        #: the model as arrays for the compiled CoM and momentum, None: Pinocchio's
        self.tree: KinematicTree | None = tree_of(self.model)
        self._nominal_joints = robot.nominal_joint_pos()
        self._leg_arrays = self._stacked_legs()
        self._frames: tuple[bytes, np.ndarray, np.ndarray] | None = None

        q_nom, _ = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
        com_nom = np.array(pin.centerOfMass(self.model, self.data, q_nom, False))
        pin.updateFramePlacements(self.model, self.data)
        p_feet = {f: self.data.oMf[robot.pin_foot_frame_ids[f]].translation.copy() for f in FEET}
        p_base = np.array([q_nom[0], 0.0, q_nom[1]]) if self.planar else q_nom[:3].copy()
        ground_z = min(p[2] for p in p_feet.values()) - self.contact_radius_m
        #: nominal CoM height above the ground [m]
        self.nominal_com_height_m = float(com_nom[2] - ground_z)
        self.com_height_m = (
            self.nominal_com_height_m
            if self.config.com_height_m is None
            else float(self.config.com_height_m)
        )
        #: (3,) trunk origin -> CoM at the nominal pose, trunk frame (level trunk) [m]
        self.com_offset_trunk_m = com_nom - p_base
        #: nominal lateral foot offset from the CoM (heading-frame y) [m], 0 for the biped
        self.foot_lateral_m = {
            f: 0.0 if self.planar else float(p_feet[f][1] - com_nom[1]) for f in FEET
        }
        #: (3,) diag(d c / d p_B), feet fixed; (2, 3) diag(d c / d p_f) per foot
        self.com_gain, self.com_gain_feet = self._measure_com_gains(p_base, p_feet)
        # load the compiled kernels now (numba's cache: 10-100 ms on a process's first
        # call), not in the first f_ref of a control loop (the CoM gains loaded the IK's)
        self.momentum(q_nom[None, :], np.zeros((1, self.model.nv)))
        rows = np.zeros((1, _N_FEET), dtype=np.int64)
        plan_rows(np.zeros((1, 3)), np.zeros(1), rows, rows, np.zeros((1, _N_FEET)), 0.1, False)
        on_ground = np.ones((1, _N_FEET), bool)
        on_ground.flags.writeable = False  # a ReferenceTiming's contact; numba types it apart
        foothold_means(np.zeros((1, _N_FEET, 3)), on_ground, rows, np.zeros((1, 3)))
        feet = np.stack([p_feet[f] for f in FEET])[None]
        self.place_trunk(p_base[None], np.zeros(1), feet, None, com_nom[None])

    def _measure_com_gains(
        self, p_base: np.ndarray, p_feet: dict[str, np.ndarray]
    ) -> tuple[np.ndarray, np.ndarray]:
        """CoM sensitivities at the nominal pose by central differences (probe 1 cm):
        ``diag(d c / d p_B)`` (3,) with the feet fixed, and ``diag(d c / d p_f)`` (2, 3)
        per foot with the trunk and the other foot fixed (the CoM follows the trunk only
        partly because the legs fold; translation invariance makes the three sum to 1)."""
        probe = np.concatenate([np.eye(3), -np.eye(3)]) * _GAIN_PROBE_M  # (6, 3)
        n = 6 * (1 + _N_FEET)
        bases = np.tile(p_base, (n, 1))
        bases[:6] += probe
        targets = {f: np.tile(p, (n, 1)) for f, p in p_feet.items()}
        for i, f in enumerate(FEET):
            targets[f][6 * (i + 1) : 6 * (i + 2)] += probe
        rot = np.broadcast_to(np.eye(3), (n, 3, 3))
        sol = whole_body_ik(self.robot, bases, rot, targets, geometries=self.geometries)
        q = configurations(self, bases, np.zeros(n), 0.0, sol.joint_pos_rad)
        com = self._com(q).reshape(1 + _N_FEET, 2, 3, 3)  # (which, +/-, axis, xyz)
        gains = np.diagonal(com[:, 0] - com[:, 1], axis1=1, axis2=2) / (2.0 * _GAIN_PROBE_M)
        gains = gains.copy()  # (3, 3): trunk, left foot, right foot
        if self.planar:  # y is not a degree of freedom of the planar model
            gains[0, 1], gains[1:, 1] = 1.0, 0.0
        if not (sol.reachable.all() and np.all(gains[0] > 0.2) and np.all(gains[0] < 1.5)):
            raise RuntimeError(f"{self.robot.name}: implausible CoM gains {gains}")
        return gains[0], gains[1:]

    def _stacked_legs(self) -> tuple[np.ndarray, ...] | None:
        """:func:`place_trunk_rows`'s leg arguments: the nominal configuration, the legs'
        entries of ``q`` and their geometries, stacked in :data:`FEET` order (None: the
        planar biped)."""
        if self.planar:
            return None
        nominal_q = np.concatenate([np.zeros(self.robot.n_root_q), self._nominal_joints])
        legs = [self.geometries[f] for f in FEET]
        assert all(isinstance(g, LegGeometry) for g in legs)
        index = np.stack([self.robot.leg_joint_index[f] + self.robot.n_root_q for f in FEET])
        fields = ("p_yaw_trunk_m", "p_roll_yaw_m", "p_pitch_roll_m", "thigh_m", "shank_m",
                  "p_foot_ankle_m", "lower_rad", "upper_rad")  # fmt: skip
        stacked = [
            np.ascontiguousarray([getattr(g, name) for g in legs], dtype=float) for name in fields
        ]
        return (nominal_q, index.astype(np.int64), *stacked)

    def trunk_configurations(
        self,
        p_base_m: np.ndarray,
        yaw_rad: np.ndarray,
        rot: np.ndarray,
        p_foot_m: np.ndarray,
        foot_yaw_rad: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Configurations (N, nq) and reachability (N,) of trunk poses with both feet at
        their targets: :func:`whole_body_ik` then :func:`configurations`, in one pass.

        Args:
            p_base_m: (N, 3) trunk positions; yaw_rad: (N,) trunk headings; rot: (N, 3, 3)
                their rotations ``R_z(yaw) R_y(trunk_pitch)``.
            p_foot_m: (N, 2, 3) foot targets [m], :data:`FEET` order.
            foot_yaw_rad: (N, 2) foot headings, or None for ``q0 = 0`` (eq. 31).
        """
        pitch = self.config.trunk_pitch_rad
        if self.planar:  # the sagittal IK of whole_body_ik
            targets = {f: p_foot_m[:, i] for i, f in enumerate(FEET)}
            sol = whole_body_ik(self.robot, p_base_m, rot, targets, geometries=self.geometries)
            joints, reachable = sol.joint_pos_rad, sol.reachable
        else:  # the compiled leg IK directly: no batching, dicts or nominal-pose tiling
            n = p_base_m.shape[0]
            p_base = np.ascontiguousarray(p_base_m)
            rot = np.ascontiguousarray(rot)
            joints = np.empty((n, self._nominal_joints.size))
            joints[:] = self._nominal_joints
            leg_q = np.empty((n, 5))
            reach = np.empty(n, dtype=bool)
            reachable = np.ones(n, dtype=bool)
            no_yaw = np.zeros(n)
            for i, f in enumerate(FEET):
                g = self.geometries[f]
                assert isinstance(g, LegGeometry)
                yaw = no_yaw if foot_yaw_rad is None else np.ascontiguousarray(foot_yaw_rad[:, i])
                leg_ik_rows(
                    np.ascontiguousarray(p_foot_m[:, i]), p_base, rot, yaw,
                    foot_yaw_rad is not None, g.p_yaw_trunk_m, g.p_roll_yaw_m, g.p_pitch_roll_m,
                    g.thigh_m, g.shank_m, g.p_foot_ankle_m, g.lower_rad, g.upper_rad, 1e-9, leg_q,
                    reach,
                )  # fmt: skip
                joints[:, self.robot.leg_joint_index[f]] = leg_q
                reachable &= reach
        return configurations(self, p_base_m, yaw_rad, pitch, joints), reachable

    def trunk_frames(self, yaw_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Trunk rotations (N, 3, 3) :func:`rotations` and quaternions (N, 4)
        :func:`trunk_quaternions` at the headings ``yaw_rad`` (N,) and the configured
        pitch; read-only, and the last result is kept (every ``f_IK`` of a sequential
        solve with the same stage durations has the same headings)."""
        key = yaw_rad.tobytes()
        if self._frames is None or self._frames[0] != key:
            pitch = self.config.trunk_pitch_rad
            rot, quat = rotations(yaw_rad, pitch), trunk_quaternions(yaw_rad, pitch)
            rot.flags.writeable = quat.flags.writeable = False
            self._frames = (key, rot, quat)
        return self._frames[1], self._frames[2]

    def place_trunk(
        self,
        p_base_m: np.ndarray,
        yaw_rad: np.ndarray,
        p_foot_m: np.ndarray,
        foot_yaw_rad: np.ndarray | None,
        p_com_target_m: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The trunk placement of :func:`~gaitnet_mpc.kinematics.reference._place_trunk`
        (``config.com_iterations`` corrections of the first guess ``p_base_m``) in one
        compiled call: ``(q, p_base, reachable)``; None where it has no kernel (the planar
        biped, a model without :attr:`tree`). Arguments as :meth:`trunk_configurations`."""
        tree, legs = self.tree, self._leg_arrays
        if tree is None or legs is None:  # legs: None on the planar biped
            return None
        rot, quat = self.trunk_frames(yaw_rad)
        n = p_base_m.shape[0]
        has_yaw = foot_yaw_rad is not None
        yaws = np.ascontiguousarray(foot_yaw_rad) if has_yaw else np.zeros((n, _N_FEET))
        return place_trunk_rows(  # type: ignore[no-any-return]
            np.ascontiguousarray(p_base_m), rot, quat, np.ascontiguousarray(p_foot_m), yaws,
            has_yaw, np.ascontiguousarray(p_com_target_m), self.com_gain,
            self.config.com_iterations, *legs, tree.parent, tree.kind, tree.idx_q, tree.rot,
            tree.trans, tree.mass, tree.lever,
        )  # fmt: skip

    def momentum(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 6) centroidal momentum ``A_G(q) v`` (eq. 11) and (N, 3) CoM [m] of
        configurations ``q`` (N, nq) with velocities ``v`` (N, nv)."""
        if self.tree is not None:
            return self.tree.momentum(q, v)
        h = np.empty((q.shape[0], 6))
        com = np.empty((q.shape[0], 3))
        for k in range(q.shape[0]):
            h[k] = pin.computeCentroidalMomentum(self.model, self.data, q[k], v[k]).vector
            com[k] = self.data.com[0]
        return h, com

    def _com(self, q: np.ndarray) -> np.ndarray:
        """(N, 3) CoM of configurations q (N, nq) [m]."""
        if self.tree is not None:
            return self.tree.com(q)
        out = np.empty((q.shape[0], 3))
        for k in range(q.shape[0]):
            out[k] = pin.centerOfMass(self.model, self.data, q[k], False)
        return out


# ------------------------------------------------------------------------- the result
@dataclass(eq=False)
class CentroidalReference:
    """Reference trajectory at the ``h + 1`` stage boundaries (Alg. 1 ``x^ref``, ``p_f^ref``).

    Attributes:
        q_ref: (h+1, nq) Pinocchio configurations.
        v_ref: (h+1, nv) Pinocchio velocities (local free-flyer frame).
        h_ref: (h+1, 6) spatial momentum ``A_G(q_ref) v_ref`` (eq. 11), ``[linear [kg m/s];
            angular about the CoM [kg m^2/s]]``, world axes.
        H_ref: (h+1, 6) centroidal pose (eq. 12 / 30, see the module docstring),
            ``[linear [kg m]; angular [kg m^2]]``.
        p_foot_ref: (h+1, 2, 3) foot-centre (foothold point) targets [m], ``FEET`` order;
            the IK targets, which ``q_ref`` reaches where ``reachable``.
        p_com_ref: (h+1, 3) CoM of ``q_ref`` [m] (``pin.centerOfMass``).
        reachable: (h+1,) bool, True where both foot targets were reached exactly.
        dts_s: (h,) stage durations [s].
        times_s: (h+1,) boundary times from now [s].
        p_base_ref: (h+1, 3) trunk positions [m].
        rot_base_ref: (h+1, 3, 3) trunk rotations (world <- trunk).
        yaw_ref_rad: (h+1,) trunk heading [rad].
        foot_yaw_ref_rad: (h+1, 2) desired foot headings [rad] (zeros for the biped).
        footholds_m: foot -> (n_f, 3) footholds ``F_0, F_1, ...`` [m] (``F_0`` = position at
            the start of the horizon or lift-off point, then touchdown targets).
        foothold_yaw_rad: foot -> (n_f,) heading of each foothold [rad].
        foothold_index: (h+1, 2) int, foothold ``j`` the foot stands on / lifted off from.
        swing_phase: (h+1, 2) normalised swing time in [0, 1] from ``F_j`` to ``F_{j+1}``
            (0 while standing on ``F_j``).
        timing: the timing the reference was built with.
        time_in_swing_s: (2,) time since lift-off of a foot swinging in stage 0 [s] (0 if
            standing, or if its lift-off point was not given and the swing restarts now).
        yaw_rate_radps: commanded yaw rate [rad/s] (trunk heading ``yaw_ref_rad[0] +
            yaw_rate * t``).
        pose0_angular_kgm2: (3,) angular centroidal pose at boundary 0 [kg m^2].
        workspace: the :class:`ReferenceWorkspace` used (reused by :func:`update_reference`).
    """

    q_ref: np.ndarray
    v_ref: np.ndarray
    h_ref: np.ndarray
    H_ref: np.ndarray
    p_foot_ref: np.ndarray
    p_com_ref: np.ndarray
    reachable: np.ndarray
    dts_s: np.ndarray
    times_s: np.ndarray
    p_base_ref: np.ndarray
    rot_base_ref: np.ndarray
    yaw_ref_rad: np.ndarray
    foot_yaw_ref_rad: np.ndarray
    footholds_m: dict[str, np.ndarray]
    foothold_yaw_rad: dict[str, np.ndarray]
    foothold_index: np.ndarray
    swing_phase: np.ndarray
    timing: ReferenceTiming
    time_in_swing_s: np.ndarray
    yaw_rate_radps: float
    pose0_angular_kgm2: np.ndarray
    workspace: ReferenceWorkspace = field(repr=False, compare=False)

    @property
    def horizon(self) -> int:
        """Number of stages ``h``."""
        return int(self.dts_s.size)

    @property
    def all_reachable(self) -> bool:
        """True iff every stage's IK reached its foot targets."""
        return bool(np.all(self.reachable))


# ------------------------------------------------------------------- kinematic helpers
def rotations(yaw_rad: np.ndarray, pitch_rad: float) -> np.ndarray:
    """(N, 3, 3) ``R_z(yaw) R_y(pitch)``."""
    cy, sy = np.cos(yaw_rad), np.sin(yaw_rad)
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    rot = np.zeros((yaw_rad.shape[0], 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 0, 2] = cy * cp, -sy, cy * sp
    rot[:, 1, 0], rot[:, 1, 1], rot[:, 1, 2] = sy * cp, cy, sy * sp
    rot[:, 2, 0], rot[:, 2, 2] = -sp, cp
    return rot


def configurations(
    ws: ReferenceWorkspace,
    p_base_m: np.ndarray,
    yaw_rad: np.ndarray,
    pitch_rad: float,
    joint_pos_rad: np.ndarray,
) -> np.ndarray:
    """(N, nq) Pinocchio configurations for trunk ``R_z(yaw) R_y(pitch)`` at ``p_base_m``.

    Humanoid ``[p, quat_xyzw, joints]``, biped ``[x, z, pitch, joints]``; the quaternion of
    ``R_z(psi) R_y(theta)`` is ``(x, y, z, w) = (-s_psi s_th, c_psi s_th, s_psi c_th,
    c_psi c_th)`` with half-angle sines/cosines.
    """
    n = p_base_m.shape[0]
    q = np.empty((n, ws.model.nq))
    root = ws.robot.n_root_q
    q[:, root:] = joint_pos_rad
    if ws.planar:
        q[:, 0], q[:, 1], q[:, 2] = p_base_m[:, 0], p_base_m[:, 2], pitch_rad
        return q
    q[:, 0:3] = p_base_m
    q[:, 3:7] = trunk_quaternions(yaw_rad, pitch_rad)
    return q


def trunk_quaternions(yaw_rad: np.ndarray, pitch_rad: float) -> np.ndarray:
    """(N, 4) quaternions ``x y z w`` of ``R_z(yaw) R_y(pitch)`` (:func:`configurations`)."""
    cz, sz = np.cos(0.5 * yaw_rad), np.sin(0.5 * yaw_rad)
    ct, st = math.cos(0.5 * pitch_rad), math.sin(0.5 * pitch_rad)
    quat = np.empty((yaw_rad.shape[0], 4))
    quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3] = -sz * st, cz * st, sz * ct, cz * ct
    return quat
