"""Symbolic whole-body dynamics of the NMPC of Sec. III-A (eqs. 3a and 4), in CasADi.

State convention: MuJoCo's own ``(qpos, qvel)``, so a solution can be compared with and
sent to the simulator without conversion. For the humanoid ``qpos = [p_base_world (3),
quat_wxyz (4), joints]`` and ``qvel = [v_base_world (3), omega_base_body (3), joint
rates]``; for the planar biped ``qpos = qvel`` coordinates are ``[x, z, pitch, joints]``.

The rigid-body model (joint placements, link inertias, armature, damping) is Pinocchio's
model of the same MJCF (:class:`gaitnet_mpc.robots.RobotModel`); the installed ``pin`` wheel
has no ``pinocchio.casadi``, so the recursive Newton-Euler algorithm (RNEA) is written
here once over CasADi SX. With the joint accelerations ``a`` as decision variables, the
dynamics of eq. (4) become the inverse-dynamics equality

    M(q) a + b(q, v) - J_c(q)^T lambda = S^T tau_j,                       (4, first row)

evaluated in O(n) by one RNEA pass with the contact forces as external forces, instead of
building the (nv, nv) mass matrix symbolically. The discretisation of eq. (3a) is
semi-implicit Euler, exactly MuJoCo's ``Euler`` integrator (without implicit damping):

    v_{k+1} = v_k + dt_k a_k,    q_{k+1} = q_k (+) dt_k v_{k+1}.                    (3a)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.robots.spec import FEET

GRAVITY_MPS2 = 9.81

_AXES = {"X": 0, "Y": 1, "Z": 2}
# Common-subexpression elimination shrinks the RNEA graph that every stage expands.
_FUNCTION_OPTIONS = {"cse": True}


@dataclass(frozen=True)
class _Link:
    """One primitive joint (free, revolute or prismatic) and the body it carries."""

    parent: int  # index in the link list, -1 for the world
    rot_placement: np.ndarray  # (3, 3) joint frame in the parent frame
    pos_placement_m: np.ndarray  # (3,)
    kind: str  # "free", "R" (revolute) or "P" (prismatic)
    axis: int  # 0, 1, 2 for x, y, z (unused for "free")
    idx_q: int
    idx_v: int
    mass_kg: float
    com_m: np.ndarray  # (3,) in the link frame
    inertia_com_kgm2: np.ndarray  # (3, 3) about the centre of mass


@dataclass(frozen=True)
class ContactPoint:
    """A point on a foot where one contact force acts (toe, heel or the point foot).

    ``p = o_link + R_link offset_body_m + offset_world_m``: the line foot's toe and heel
    are fixed in the foot (box bottom); a sphere foot touches the ground straight below
    its centre, a world-frame offset of ``-radius e_z``.
    """

    foot: str
    link: int
    offset_body_m: np.ndarray  # (3,)
    offset_world_m: np.ndarray  # (3,)


def _rot_axis(axis: int, angle: ca.SX) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    if axis == 0:
        return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))
    if axis == 1:
        return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def quat_wxyz_to_rot(quat: ca.SX) -> ca.SX:
    """Rotation matrix (3, 3) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def quat_mul(p: ca.SX, q: ca.SX) -> ca.SX:
    """Hamilton product of two (w, x, y, z) quaternions."""
    pw, pv = p[0], p[1:4]
    qw, qv = q[0], q[1:4]
    return ca.vertcat(pw * qw - ca.dot(pv, qv), pw * qv + qw * pv + ca.cross(pv, qv))


def quat_exp(half_angle: ca.SX) -> ca.SX:
    """Unit quaternion of the rotation vector ``2 half_angle`` (3,), smooth at zero.

    cos and sinc of ``theta = |half_angle|`` as even series in theta^2 to theta^8; the
    truncation error is below 1e-12 for theta < 0.4 rad (|omega| dt / 2, e.g. 10 rad/s
    over 0.08 s).
    """
    t2 = ca.dot(half_angle, half_angle)
    cos_t = 1 - t2 / 2 + t2**2 / 24 - t2**3 / 720 + t2**4 / 40320
    sinc_t = 1 - t2 / 6 + t2**2 / 120 - t2**3 / 5040 + t2**4 / 362880
    return ca.vertcat(cos_t, sinc_t * half_angle)


def _links_from_pinocchio(robot: RobotModel) -> list[_Link]:
    """Flatten Pinocchio's joint tree (composite joints expanded) into primitive links."""
    model = robot.pin_model
    links: list[_Link] = []
    link_of_joint = {0: -1}
    for jid in range(1, model.njoints):
        jmodel = model.joints[jid]
        inertia = model.inertias[jid]
        parent = link_of_joint[model.parents[jid]]
        placement = model.jointPlacements[jid]
        name = jmodel.shortname()
        if name == "JointModelComposite":
            comp = jmodel.extract()
            subs = [
                (j.shortname(), j, pl)
                for j, pl in zip(comp.joints, comp.jointPlacements, strict=True)
            ]
        else:
            subs = [(name, jmodel, None)]
        for i, (sub_name, sub, sub_pl) in enumerate(subs):
            # A composite's sub-joint placements chain from the composite's own placement.
            if sub_pl is None:
                pl = placement
            else:
                pl = placement * sub_pl if i == 0 else sub_pl
            last = i == len(subs) - 1
            if sub_name == "JointModelFreeFlyer":
                kind, axis = "free", 0
            elif sub_name.startswith("JointModelR") and sub_name[-1] in _AXES:
                kind, axis = "R", _AXES[sub_name[-1]]
            elif sub_name.startswith("JointModelP") and sub_name[-1] in _AXES:
                kind, axis = "P", _AXES[sub_name[-1]]
            else:
                raise NotImplementedError(f"{robot.name}: joint type {sub_name} not supported")
            links.append(
                _Link(
                    parent=parent,
                    rot_placement=np.array(pl.rotation),
                    pos_placement_m=np.array(pl.translation),
                    kind=kind,
                    axis=axis,
                    idx_q=int(sub.idx_q),
                    idx_v=int(sub.idx_v),
                    mass_kg=float(inertia.mass) if last else 0.0,
                    com_m=np.array(inertia.lever) if last else np.zeros(3),
                    inertia_com_kgm2=np.array(inertia.inertia) if last else np.zeros((3, 3)),
                )
            )
            parent = len(links) - 1
        link_of_joint[jid] = parent
    return links


class WholeBodyDynamics:
    """CasADi functions of one robot's contact-constrained rigid-body dynamics.

    Functions (all SX, built once per robot and reused by every stage of the NLP):

    * ``inverse_dynamics(qpos, qvel, qacc, force_world) -> (nv,)``: the generalised force
      ``M a + b - J_c^T lambda`` (eq. 4) that the actuators must supply; its root rows
      must be zero, its joint rows equal the joint torques. ``force_world`` (3 n_c) stacks
      the world-frame forces at :attr:`contact_points`.
    * ``contact_kinematics(qpos, qvel) -> (p_world (3, n_c), v_world (3, n_c))``.
    * ``step(qpos, qvel, qacc, dt_s) -> (qpos_next, qvel_next)``: eq. (3a).

    Armature and joint damping of the MJCF enter as ``armature * a + damping * v`` on the
    joint rows, as in MuJoCo's forward dynamics.
    """

    def __init__(self, robot: RobotModel) -> None:
        self.robot = robot
        self.planar = robot.spec.planar
        self.nq = int(robot.mj_model.nq)
        self.nv = int(robot.mj_model.nv)
        self.n_joints = robot.n_joints
        self.n_root_dofs = robot.n_root_dofs
        self._links = _links_from_pinocchio(robot)
        self.armature = np.array(robot.pin_model.armature, dtype=float)
        self.damping = np.array(robot.pin_model.damping, dtype=float)
        self.contact_points = self._make_contact_points()
        self.n_contacts = len(self.contact_points)
        self.inverse_dynamics = self._build_inverse_dynamics()
        self.contact_kinematics = self._build_contact_kinematics()
        self.step = self._build_step()

    # ------------------------------------------------------------ contacts
    def _make_contact_points(self) -> tuple[ContactPoint, ...]:
        spec = self.robot.spec
        model = self.robot.pin_model
        link_of_joint = self._link_index_of_joints()
        points = []
        for foot in FEET:
            frame = model.frames[self.robot.pin_foot_frame_ids[foot]]
            link = link_of_joint[frame.parentJoint]
            site = np.array(frame.placement.translation)
            rot = np.array(frame.placement.rotation)
            if spec.foot_toe_m > 0.0 or spec.foot_heel_m > 0.0:
                for along in (spec.foot_toe_m, -spec.foot_heel_m):
                    off = site + rot @ np.array([along, 0.0, -spec.foot_contact_radius_m])
                    points.append(ContactPoint(foot, link, off, np.zeros(3)))
            else:
                down = np.array([0.0, 0.0, -spec.foot_contact_radius_m])
                points.append(ContactPoint(foot, link, site, down))
        return tuple(points)

    def _link_index_of_joints(self) -> dict[int, int]:
        model = self.robot.pin_model
        out, count = {}, 0
        for jid in range(1, model.njoints):
            jm = model.joints[jid]
            count += len(jm.extract().joints) if jm.shortname() == "JointModelComposite" else 1
            out[jid] = count - 1
        return out

    def contact_points_of(self, foot: str) -> list[int]:
        """Indices in :attr:`contact_points` of the points on ``foot``."""
        return [i for i, c in enumerate(self.contact_points) if c.foot == foot]

    # ------------------------------------------------------------ kinematics
    def _root_velocity(self, qpos: ca.SX, qvel: ca.SX, qacc: ca.SX | None):
        """Pinocchio-style joint velocities/accelerations (free root in its own frame)."""
        if self.planar:
            return qvel, qacc
        rot = quat_wxyz_to_rot(qpos[3:7])
        omega = qvel[3:6]
        v_lin = rot.T @ qvel[0:3]
        v = ca.vertcat(v_lin, qvel[3:])
        if qacc is None:
            return v, None
        a_lin = rot.T @ qacc[0:3] - ca.cross(omega, v_lin)
        return v, ca.vertcat(a_lin, qacc[3:])

    def _joint_q(self, qpos: ca.SX) -> ca.SX:
        """Pinocchio-indexed q (xyzw quaternion for the free root)."""
        if self.planar:
            return qpos
        return ca.vertcat(qpos[0:3], qpos[4:7], qpos[3], qpos[7:])

    def _forward(
        self, qpos: ca.SX, v: ca.SX, a: ca.SX | None
    ) -> tuple[list[tuple[Any, Any]], list[Any], list[Any], list[tuple[Any, Any]]]:
        """Forward pass of the RNEA: link poses (world), spatial velocities and accelerations
        (link frames), and each joint's transform from its parent (rotation, position)."""
        q = self._joint_q(qpos)
        poses: list[tuple[Any, Any]] = []
        vels: list[Any] = []
        accs: list[Any] = []
        sub: list[tuple[Any, Any]] = []
        r_rel: Any
        p_rel: Any
        s_qdd: Any
        v_par: Any
        a_par: Any
        gravity = ca.DM([0.0, 0.0, GRAVITY_MPS2, 0.0, 0.0, 0.0])  # a_world = -g
        for link in self._links:
            rp, pp = ca.DM(link.rot_placement), ca.DM(link.pos_placement_m)
            if link.kind == "free":
                quat_xyzw = q[link.idx_q + 3 : link.idx_q + 7]
                quat = ca.vertcat(quat_xyzw[3], quat_xyzw[0:3])
                r_rel = rp @ quat_wxyz_to_rot(quat)
                p_rel = pp + rp @ q[link.idx_q : link.idx_q + 3]
                s_qd = v[link.idx_v : link.idx_v + 6]
                s_qdd = None if a is None else a[link.idx_v : link.idx_v + 6]
            else:
                qi, e = q[link.idx_q], np.eye(3)[link.axis]
                if link.kind == "R":
                    r_rel, p_rel = rp @ _rot_axis(link.axis, qi), pp
                    s = np.concatenate([np.zeros(3), e])
                else:
                    r_rel, p_rel = rp, pp + rp @ ca.DM(e) * qi
                    s = np.concatenate([e, np.zeros(3)])
                s_qd = ca.DM(s) * v[link.idx_v]
                s_qdd = None if a is None else ca.DM(s) * a[link.idx_v]
            if link.parent < 0:
                o_rot, o_pos = r_rel, p_rel
                v_par, a_par = ca.DM.zeros(6), gravity
            else:
                par_rot, par_pos = poses[link.parent]
                o_rot, o_pos = par_rot @ r_rel, par_pos + par_rot @ p_rel
                v_par = vels[link.parent]
                a_par = accs[link.parent] if a is not None else None
            vi = (
                ca.vertcat(
                    r_rel.T @ (v_par[0:3] + ca.cross(v_par[3:6], p_rel)), r_rel.T @ v_par[3:6]
                )
                + s_qd
            )
            poses.append((o_rot, o_pos))
            vels.append(vi)
            sub.append((r_rel, p_rel))
            if a is not None:
                ai = (
                    ca.vertcat(
                        r_rel.T @ (a_par[0:3] + ca.cross(a_par[3:6], p_rel)), r_rel.T @ a_par[3:6]
                    )
                    + s_qdd
                )
                # v_i x_m (S qd), zero for the free root (S qd = v_i).
                if link.kind != "free":
                    ai += ca.vertcat(
                        ca.cross(vi[3:6], s_qd[0:3]) + ca.cross(vi[0:3], s_qd[3:6]),
                        ca.cross(vi[3:6], s_qd[3:6]),
                    )
                accs.append(ai)
        return poses, vels, accs, sub

    def _build_contact_kinematics(self) -> ca.Function:
        qpos, qvel = ca.SX.sym("qpos", self.nq), ca.SX.sym("qvel", self.nv)
        v, _ = self._root_velocity(qpos, qvel, None)
        poses, vels, _, _ = self._forward(qpos, v, None)
        p_cols, v_cols = [], []
        for c in self.contact_points:
            o_rot, o_pos = poses[c.link]
            r_body = ca.DM(c.offset_body_m) + o_rot.T @ ca.DM(c.offset_world_m)
            vi = vels[c.link]
            p_cols.append(o_pos + o_rot @ ca.DM(c.offset_body_m) + ca.DM(c.offset_world_m))
            v_cols.append(o_rot @ (vi[0:3] + ca.cross(vi[3:6], r_body)))
        return ca.Function(
            "contact_kinematics",
            [qpos, qvel],
            [ca.horzcat(*p_cols), ca.horzcat(*v_cols)],
            ["qpos", "qvel"],
            ["p_contact_world_m", "v_contact_world_mps"],
            _FUNCTION_OPTIONS,
        )

    # ------------------------------------------------------------ dynamics
    def _build_inverse_dynamics(self) -> ca.Function:
        """Eq. (4), first row, by the RNEA with the contact forces as external forces."""
        qpos, qvel = ca.SX.sym("qpos", self.nq), ca.SX.sym("qvel", self.nv)
        qacc = ca.SX.sym("qacc", self.nv)
        force = ca.SX.sym("force_world_n", 3 * self.n_contacts)
        v, a = self._root_velocity(qpos, qvel, qacc)
        poses, vels, accs, sub = self._forward(qpos, v, a)
        f_links = []
        for link, vi, ai in zip(self._links, vels, accs, strict=True):
            m, c, ic = link.mass_kg, ca.DM(link.com_m), ca.DM(link.inertia_com_kgm2)
            if m == 0.0:
                f_links.append(ca.SX.zeros(6))
                continue

            def momentum(mot: ca.SX, m: float = m, c: ca.DM = c, ic: ca.DM = ic) -> ca.SX:
                lin = m * (mot[0:3] - ca.cross(c, mot[3:6]))
                return ca.vertcat(lin, ic @ mot[3:6] + ca.cross(c, lin))

            h = momentum(vi)
            ha = momentum(ai)
            f_links.append(
                ca.vertcat(
                    ha[0:3] + ca.cross(vi[3:6], h[0:3]),
                    ha[3:6] + ca.cross(vi[3:6], h[3:6]) + ca.cross(vi[0:3], h[0:3]),
                )
            )
        for i, cp in enumerate(self.contact_points):
            o_rot, _ = poses[cp.link]
            f_body = o_rot.T @ force[3 * i : 3 * i + 3]
            r_body = ca.DM(cp.offset_body_m) + o_rot.T @ ca.DM(cp.offset_world_m)
            f_links[cp.link] = f_links[cp.link] - ca.vertcat(f_body, ca.cross(r_body, f_body))
        tau = [ca.SX(0)] * self.nv
        for i in reversed(range(len(self._links))):
            link, fi = self._links[i], f_links[i]
            if link.kind == "free":
                for k in range(6):
                    tau[link.idx_v + k] = fi[k]
            elif link.kind == "R":
                tau[link.idx_v] = fi[3 + link.axis]
            else:
                tau[link.idx_v] = fi[link.axis]
            if link.parent >= 0:
                r_rel, p_rel = sub[i]
                f_lin = r_rel @ fi[0:3]
                f_links[link.parent] = f_links[link.parent] + ca.vertcat(
                    f_lin, r_rel @ fi[3:6] + ca.cross(p_rel, f_lin)
                )
        tau_vec = ca.vertcat(*tau) + ca.DM(self.armature) * qacc + ca.DM(self.damping) * qvel
        return ca.Function(
            "inverse_dynamics",
            [qpos, qvel, qacc, force],
            [tau_vec],
            ["qpos", "qvel", "qacc", "force_world_n"],
            ["tau_generalised"],
            _FUNCTION_OPTIONS,
        )

    def _build_step(self) -> ca.Function:
        """Eq. (3a): semi-implicit Euler on MuJoCo's (qpos, qvel)."""
        qpos, qvel = ca.SX.sym("qpos", self.nq), ca.SX.sym("qvel", self.nv)
        qacc, dt = ca.SX.sym("qacc", self.nv), ca.SX.sym("dt_s")
        qvel_next = qvel + dt * qacc
        if self.planar:
            qpos_next = qpos + dt * qvel_next
        else:
            quat_next = quat_mul(qpos[3:7], quat_exp(0.5 * dt * qvel_next[3:6]))
            qpos_next = ca.vertcat(
                qpos[0:3] + dt * qvel_next[0:3], quat_next, qpos[7:] + dt * qvel_next[6:]
            )
        return ca.Function(
            "step",
            [qpos, qvel, qacc, dt],
            [qpos_next, qvel_next],
            ["qpos", "qvel", "qacc", "dt_s"],
            ["qpos_next", "qvel_next"],
            _FUNCTION_OPTIONS,
        )

    # ------------------------------------------------------------ numeric helpers
    def forward_dynamics(
        self, qpos: np.ndarray, qvel: np.ndarray, tau_nm: np.ndarray, force_world_n: np.ndarray
    ) -> np.ndarray:
        """Numeric qacc solving eq. (4) for given joint torques and contact forces."""
        zero = np.zeros(self.nv)
        b = np.array(self.inverse_dynamics(qpos, qvel, zero, force_world_n)).ravel()
        mass = np.column_stack(
            [
                np.array(self.inverse_dynamics(qpos, qvel, e, force_world_n)).ravel() - b
                for e in np.eye(self.nv)
            ]
        )
        rhs = -b
        rhs[self.n_root_dofs :] += tau_nm
        return np.linalg.solve(mass, rhs)
