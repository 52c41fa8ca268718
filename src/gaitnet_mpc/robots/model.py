"""Load one MJCF into MuJoCo, Pinocchio and adam-robotics, and convert states between them.

Conventions (the rest of the package uses Pinocchio's):

* MuJoCo ``qpos`` of the humanoid: ``[p_base_world (3), quat_wxyz (4), joints (18)]``;
  ``qvel``: ``[v_base_world (3), omega_base_body (3), joint rates (18)]``.
* Pinocchio ``q``: ``[p_base_world (3), quat_xyzw (4), joints]``;
  ``v``: ``[v_base_body (3), omega_base_body (3), joint rates]`` (free-flyer, local frame).
* The planar biped has the same root in all three: ``[x, z, pitch]`` slide/slide/hinge,
  so ``q == qpos`` and ``v == qvel``.

Pinocchio reads the MJCF ``freejoint`` as its free-flyer root, so
``pin.buildModelFromMJCF(path)`` already yields a free-flyer model.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import mujoco
import numpy as np
import pinocchio as pin

from gaitnet_mpc.robots.spec import FEET, RobotSpec

_XYZW_OF_WXYZ = np.array([4, 5, 6, 3])  # qpos entries of Pinocchio's (x, y, z, w)


def quat_xyzw_to_wxyz(quat_xyzw: np.ndarray) -> np.ndarray:
    """Reorder a quaternion from Pinocchio's (x, y, z, w) to MuJoCo's (w, x, y, z)."""
    return np.asarray(quat_xyzw)[..., [3, 0, 1, 2]]


def quat_wxyz_to_matrix(quat_wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a unit quaternion in (w, x, y, z) order."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat_wxyz, dtype=float))
    return mat.reshape(3, 3)


@dataclass
class RobotModel:
    """A robot loaded from its single MJCF file by MuJoCo, Pinocchio and (lazily) adam."""

    spec: RobotSpec

    def __post_init__(self) -> None:
        path = str(self.spec.mjcf_path)
        self.mj_model: mujoco.MjModel = mujoco.MjModel.from_xml_path(path)
        self.pin_model: pin.Model = pin.buildModelFromMJCF(path)
        m = self.mj_model
        # Actuated joints in actuator order; the MJCFs list actuators in tree order,
        # which is also Pinocchio's joint order (checked below).
        self.joint_names: tuple[str, ...] = tuple(
            m.joint(int(m.actuator_trnid[a, 0])).name for a in range(m.nu)
        )
        pin_joint_names = tuple(self.pin_model.names[i] for i in range(self.pin_model.njoints))
        self.n_root_dofs: int = 3 if self.spec.planar else 6
        self.n_root_q: int = 3 if self.spec.planar else 7
        if pin_joint_names[-len(self.joint_names) :] != self.joint_names:
            raise RuntimeError(
                f"{self.spec.name}: actuator order {self.joint_names} differs from the "
                f"kinematic tree order {pin_joint_names}"
            )
        jids = [m.joint(n).id for n in self.joint_names]
        self.joint_qpos_adr = np.array([m.jnt_qposadr[j] for j in jids])
        self.joint_dof_adr = np.array([m.jnt_dofadr[j] for j in jids])
        self.joint_lower_rad = np.array([m.jnt_range[j, 0] for j in jids])
        self.joint_upper_rad = np.array([m.jnt_range[j, 1] for j in jids])
        self.torque_limit_nm = np.array([m.actuator_ctrlrange[a, 1] for a in range(m.nu)])
        self._nominal_joint_pos = np.array(
            [self.spec.nominal_joint_pos_rad.get(n, 0.0) for n in self.joint_names]
        )
        self.trunk_body_id: int = m.body(self.spec.trunk_body).id
        self.foot_site_ids = {f: m.site(self.spec.foot_sites[f]).id for f in FEET}
        self.foot_geom_ids = {f: tuple(m.geom(g).id for g in self.spec.foot_geoms[f]) for f in FEET}
        self.leg_joint_index = {
            f: np.array([self.joint_names.index(j) for j in self.spec.leg_joints[f]]) for f in FEET
        }
        self.pin_foot_frame_ids = {
            f: self.pin_model.getFrameId(self.spec.foot_sites[f]) for f in FEET
        }

    # ------------------------------------------------------------------ sizes
    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def n_joints(self) -> int:
        """Number of actuated joints."""
        return len(self.joint_names)

    @property
    def nv(self) -> int:
        """Degrees of freedom, root included (24 for the humanoid, 7 for the biped)."""
        return int(self.mj_model.nv)

    @cached_property
    def total_mass_kg(self) -> float:
        return float(np.sum(self.mj_model.body_mass))

    @cached_property
    def min_foot_separation_m(self) -> float | None:
        """Smallest lateral distance between the foot centres that keeps the lower legs
        apart [m]: the two widest lower-leg lateral half-widths (capsule/sphere radius, box
        half-width along y) plus ``spec.leg_clearance_m`` (humanoid3d: 2 x 0.02 m shank
        radius + 0.02 m = 0.06 m). None where the spec sets no clearance (planar robot)."""
        spec = self.spec
        if spec.leg_clearance_m is None:
            return None
        m = self.mj_model
        half = []
        for foot in FEET:
            widths = []
            for name in spec.lower_leg_geoms[foot]:
                g = m.geom(name)
                box = int(g.type[0]) == int(mujoco.mjtGeom.mjGEOM_BOX)
                widths.append(float(g.size[1] if box else g.size[0]))
            half.append(max(widths))
        return sum(half) + spec.leg_clearance_m

    def foot_separation_m(self, yaw_offset_rad: float) -> float | None:
        """:attr:`min_foot_separation_m` plus the lateral sweep of a foot yawed by
        ``yaw_offset_rad`` against the other, ``max(toe, heel) |sin(yaw_offset)|`` [m]."""
        d = self.min_foot_separation_m
        if d is None:
            return None
        return d + max(self.spec.foot_toe_m, self.spec.foot_heel_m) * abs(np.sin(yaw_offset_rad))

    @cached_property
    def standing_inertia_kgm2(self) -> tuple[float, float, float]:
        """Diagonal of the centroidal composite inertia at :meth:`standing_qpos` [kg m^2]
        (humanoid3d 0.642, 0.576, 0.094): the body's rotational inertia about its CoM."""
        q, v = self.mj_to_pin(self.standing_qpos(), np.zeros(self.nv))
        data = self.pin_model.createData()
        pin.ccrba(self.pin_model, data, q, v)
        ixx, iyy, izz = (float(x) for x in np.diag(data.Ig.inertia))
        return ixx, iyy, izz

    # ------------------------------------------------------------ conversions
    def mj_to_pin(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """MuJoCo (qpos, qvel) -> Pinocchio (q, v); see the module docstring."""
        if self.spec.planar:
            return np.array(qpos, dtype=float), np.array(qvel, dtype=float)
        q = self.mj_to_pin_q(qpos)
        v = np.array(qvel, dtype=float)
        rot = quat_wxyz_to_matrix(qpos[3:7])
        v[0:3] = rot.T @ qvel[0:3]
        return q, v

    def mj_to_pin_q(self, qpos: np.ndarray) -> np.ndarray:
        """MuJoCo qpos -> Pinocchio q: :meth:`mj_to_pin` without the velocity."""
        q = np.array(qpos, dtype=float)
        if not self.spec.planar:
            q[3:7] = qpos[_XYZW_OF_WXYZ]
        return q

    def pin_to_mj(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pinocchio (q, v) -> MuJoCo (qpos, qvel)."""
        if self.spec.planar:
            return np.array(q, dtype=float), np.array(v, dtype=float)
        qpos = np.array(q, dtype=float)
        qpos[3:7] = quat_xyzw_to_wxyz(q[3:7])
        qvel = np.array(v, dtype=float)
        qvel[0:3] = quat_wxyz_to_matrix(qpos[3:7]) @ v[0:3]
        return qpos, qvel

    def base_pose(self, qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation matrix (3, 3) of the trunk from MuJoCo qpos."""
        if self.spec.planar:
            x, z, pitch = qpos[0:3]
            c, s = np.cos(pitch), np.sin(pitch)
            return np.array([x, 0.0, z]), np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        return np.array(qpos[0:3], dtype=float), quat_wxyz_to_matrix(qpos[3:7])

    def qpos_of(self, p_base_m: np.ndarray, rot_base: np.ndarray, joints: np.ndarray) -> np.ndarray:
        """MuJoCo qpos of a trunk pose (position (3,), rotation (3, 3)) and joint angles in
        actuator order: the inverse of :meth:`base_pose` (the planar biped keeps x, z and
        the pitch of ``rot_base``)."""
        if self.spec.planar:
            pitch = np.arctan2(rot_base[0, 2], rot_base[0, 0])
            return np.concatenate([[p_base_m[0], p_base_m[2], pitch], joints])
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rot_base, dtype=float).ravel())
        return np.concatenate([p_base_m, quat, joints])  # quat: (w, x, y, z)

    # ---------------------------------------------------------------- poses
    def nominal_joint_pos(self) -> np.ndarray:
        """Standing joint angles [rad] in actuator order."""
        return self._nominal_joint_pos.copy()

    def standing_qpos(
        self, x_m: float = 0.0, y_m: float = 0.0, ground_z_m: float = 0.0
    ) -> np.ndarray:
        """MuJoCo qpos of the nominal pose with both feet resting on ground at ``ground_z_m``."""
        m = self.mj_model
        data = mujoco.MjData(m)
        qpos = np.zeros(m.nq)
        if not self.spec.planar:
            qpos[3] = 1.0
        qpos[self.joint_qpos_adr] = self.nominal_joint_pos()
        data.qpos[:] = qpos
        mujoco.mj_kinematics(m, data)
        foot_z = min(data.site_xpos[self.foot_site_ids[f], 2] for f in FEET)
        lift = ground_z_m + self.spec.foot_contact_radius_m - foot_z
        if self.spec.planar:
            qpos[0], qpos[1] = x_m, lift
        else:
            qpos[0], qpos[1], qpos[2] = x_m, y_m, lift
        return qpos

    # -------------------------------------------------------------- adam
    @cached_property
    def adam(self) -> Any:
        """adam-robotics NumPy ``KinDynComputations`` built from the same MuJoCo model.

        adam treats the root as a 6-DoF floating base in mixed representation (world-frame
        linear and angular base velocity); for the planar biped use :meth:`adam_base`.
        """
        from adam.numpy import KinDynComputations

        return KinDynComputations.from_mujoco_model(self.mj_model)

    def adam_base(self, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Base transform (4, 4) and mixed-representation base twist (6,) for adam."""
        p, rot = self.base_pose(qpos)
        h = np.eye(4)
        h[:3, :3], h[:3, 3] = rot, p
        if self.spec.planar:
            twist = np.array([qvel[0], 0.0, qvel[1], 0.0, qvel[2], 0.0])
        else:
            twist = np.concatenate([qvel[0:3], rot @ qvel[3:6]])
        return h, twist
