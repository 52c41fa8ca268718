"""Compiled centre of mass and centroidal momentum (eq. 11) of many configurations at once.

``f_ref`` and ``f_IK`` evaluate the CoM and ``h = A_G(q) v`` of every stage boundary of
the horizon, several times per sequential iteration. Pinocchio does it one configuration
per call, and at ``h + 1 = 11`` boundaries the Python round trips cost more than the
arithmetic. These kernels do the same forward pass over a kinematic tree for all rows in
one call (numba, compiled on first use, cached by :mod:`gaitnet_mpc.jit`):

* joint ``i`` moves relative to its parent's frame by the fixed placement ``(R_i, t_i)``
  and then by its own motion: a free-flyer (``q = [p, quaternion x y z w]``, ``v``
  the joint frame's linear and angular velocity in that frame, as Pinocchio's), or a
  revolute joint about its x, y or z axis;
* the body of joint ``i`` has mass ``m_i``, its CoM at ``c_i`` and rotational inertia
  ``I_i`` about it, both in the joint frame;
* ``com = sum m_i c_i / m``; ``h = [sum m_i v_ci; sum R_i I_i R_i^T w_i + m_i (c_i - com)
  x v_ci]`` (world axes, about the CoM), as ``pinocchio.computeCentroidalMomentum``.

:func:`tree_of` reads these arrays from a Pinocchio model and returns None for a model
with another joint kind (the planar biped's composite root), which then keeps Pinocchio.
``tests/test_rigid_body_kernel.py`` checks both functions against Pinocchio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gaitnet_mpc.jit import njit_cached

_UNIVERSE, _FREE_FLYER = -1, 0  # kinds; 1, 2, 3: revolute about x, y, z
_REVOLUTE = {"JointModelRX": 1, "JointModelRY": 2, "JointModelRZ": 3}


@dataclass(frozen=True)
class KinematicTree:
    """A Pinocchio model's tree as arrays, joints in Pinocchio's order (parents first).

    Attributes:
        parent, kind, idx_q, idx_v: (nj,) int arrays per joint (index 0: the universe).
        rot, trans: (nj, 3, 3), (nj, 3) joint placements in the parent's frame.
        mass, lever, inertia: (nj,), (nj, 3), (nj, 3, 3) bodies, in the joint frame.
    """

    parent: np.ndarray
    kind: np.ndarray
    idx_q: np.ndarray
    idx_v: np.ndarray
    rot: np.ndarray
    trans: np.ndarray
    mass: np.ndarray
    lever: np.ndarray
    inertia: np.ndarray

    def com(self, q: np.ndarray) -> np.ndarray:
        """(n, 3) CoM [m] of configurations ``q`` (n, nq)."""
        return com_rows(
            np.ascontiguousarray(q), self.parent, self.kind, self.idx_q, self.rot, self.trans,
            self.mass, self.lever,
        )  # fmt: skip

    def momentum(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, 6) centroidal momentum ``[linear; angular]`` and (n, 3) CoM of ``q`` (n, nq)
        moving with ``v`` (n, nv)."""
        return momentum_rows(
            np.ascontiguousarray(q), np.ascontiguousarray(v), self.parent, self.kind,
            self.idx_q, self.idx_v, self.rot, self.trans, self.mass, self.lever, self.inertia,
        )  # fmt: skip


def tree_of(model: pin.Model) -> KinematicTree | None:
    """The arrays of ``model``, or None if it has a joint other than a free-flyer root
    and revolute x / y / z joints."""
    nj = model.njoints
    kind = np.full(nj, _UNIVERSE, dtype=np.int64)
    for i in range(1, nj):
        name = model.joints[i].shortname()
        if name == "JointModelFreeFlyer" and model.parents[i] == 0:
            kind[i] = _FREE_FLYER
        elif name in _REVOLUTE:
            kind[i] = _REVOLUTE[name]
        else:
            return None
    return KinematicTree(
        parent=np.array(model.parents, dtype=np.int64),
        kind=kind,
        idx_q=np.array([j.idx_q for j in model.joints], dtype=np.int64),
        idx_v=np.array([j.idx_v for j in model.joints], dtype=np.int64),
        rot=np.array([m.rotation for m in model.jointPlacements]),
        trans=np.array([m.translation for m in model.jointPlacements]),
        mass=np.array([b.mass for b in model.inertias]),
        lever=np.array([b.lever for b in model.inertias]),
        inertia=np.array([b.inertia for b in model.inertias]),
    )


@njit_cached(inline="always")
def _mat_vec(m: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """``out = m x`` for 3 x 3 ``m`` (scalar loops: numba's ``@`` calls BLAS)."""
    for a in range(3):
        out[a] = m[a, 0] * x[0] + m[a, 1] * x[1] + m[a, 2] * x[2]


@njit_cached(inline="always")
def _mat_t_vec(m: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """``out = m^T x`` for 3 x 3 ``m``."""
    for a in range(3):
        out[a] = m[0, a] * x[0] + m[1, a] * x[1] + m[2, a] * x[2]


@njit_cached(inline="always")
def _mat_mat(m: np.ndarray, n: np.ndarray, out: np.ndarray) -> None:
    """``out = m n`` for 3 x 3 matrices."""
    for a in range(3):
        for b in range(3):
            out[a, b] = m[a, 0] * n[0, b] + m[a, 1] * n[1, b] + m[a, 2] * n[2, b]


@njit_cached(inline="always")
def _cross_add(a: np.ndarray, b: np.ndarray, scale: float, out: np.ndarray) -> None:
    """``out += scale (a x b)``."""
    out[0] += scale * (a[1] * b[2] - a[2] * b[1])
    out[1] += scale * (a[2] * b[0] - a[0] * b[2])
    out[2] += scale * (a[0] * b[1] - a[1] * b[0])


@njit_cached()
def _forward(
    q: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray,
    idx_q: np.ndarray,
    rot: np.ndarray,
    trans: np.ndarray,
    r_out: np.ndarray,
    p_out: np.ndarray,
    rb: np.ndarray,
    rj: np.ndarray,
    offset: np.ndarray,
) -> None:
    """World rotation ``r_out`` (nj, 3, 3) and origin ``p_out`` (nj, 3) of every joint
    frame at one configuration ``q`` (nq,); ``rb``, ``rj`` (3, 3) and ``offset`` (3,) are
    scratch."""
    r_out[0] = 0.0
    for a in range(3):
        r_out[0, a, a] = 1.0
    p_out[0] = 0.0
    for i in range(1, parent.shape[0]):
        a = parent[i]
        _mat_mat(r_out[a], rot[i], rb)
        _mat_vec(r_out[a], trans[i], offset)
        for b in range(3):
            p_out[i, b] = p_out[a, b] + offset[b]
        k, iq = kind[i], idx_q[i]
        if k == _FREE_FLYER:
            x, y, z, w = q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]
            rj[0, 0], rj[0, 1], rj[0, 2] = (
                1 - 2 * (y * y + z * z),
                2 * (x * y - z * w),
                2 * (x * z + y * w),
            )
            rj[1, 0], rj[1, 1], rj[1, 2] = (
                2 * (x * y + z * w),
                1 - 2 * (x * x + z * z),
                2 * (y * z - x * w),
            )
            rj[2, 0], rj[2, 1], rj[2, 2] = (
                2 * (x * z - y * w),
                2 * (y * z + x * w),
                1 - 2 * (x * x + y * y),
            )
            _mat_vec(rb, q[iq : iq + 3], offset)
            for b in range(3):
                p_out[i, b] += offset[b]
        else:
            c, s = math.cos(q[iq]), math.sin(q[iq])
            rj[:] = 0.0
            axis = k - 1
            u, w2 = (axis + 1) % 3, (axis + 2) % 3  # the plane the joint turns in
            rj[axis, axis] = 1.0
            rj[u, u], rj[u, w2], rj[w2, u], rj[w2, w2] = c, -s, s, c
        _mat_mat(rb, rj, r_out[i])


@njit_cached()
def com_rows(
    q: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray,
    idx_q: np.ndarray,
    rot: np.ndarray,
    trans: np.ndarray,
    mass: np.ndarray,
    lever: np.ndarray,
) -> np.ndarray:
    """(n, 3) CoM of each configuration row of ``q`` (n, nq)."""
    nj = parent.shape[0]
    r = np.empty((nj, 3, 3))
    p = np.empty((nj, 3))
    arm = np.empty(3)
    rb, rj, tmp = np.empty((3, 3)), np.empty((3, 3)), np.empty(3)
    total = mass.sum()
    out = np.zeros((q.shape[0], 3))
    for row in range(q.shape[0]):
        _forward(q[row], parent, kind, idx_q, rot, trans, r, p, rb, rj, tmp)
        for i in range(1, nj):
            _mat_vec(r[i], lever[i], arm)
            for b in range(3):
                out[row, b] += mass[i] * (p[i, b] + arm[b])
        for b in range(3):
            out[row, b] /= total
    return out


@njit_cached()
def momentum_rows(
    q: np.ndarray,
    v: np.ndarray,
    parent: np.ndarray,
    kind: np.ndarray,
    idx_q: np.ndarray,
    idx_v: np.ndarray,
    rot: np.ndarray,
    trans: np.ndarray,
    mass: np.ndarray,
    lever: np.ndarray,
    inertia: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """(n, 6) centroidal momentum and (n, 3) CoM of each row of ``q`` (n, nq), ``v``
    (n, nv) (module docstring)."""
    nj = parent.shape[0]
    n = q.shape[0]
    r = np.empty((nj, 3, 3))
    p = np.empty((nj, 3))
    omega = np.zeros((nj, 3))  # world angular velocity of each joint frame
    vel = np.zeros((nj, 3))  # world velocity of each joint frame's origin
    c = np.empty((nj, 3))  # body CoMs
    vc = np.empty((nj, 3))  # their velocities
    arm = np.empty(3)
    tmp = np.empty(3)
    tmp2 = np.empty(3)
    rb, rj = np.empty((3, 3)), np.empty((3, 3))
    total = mass.sum()
    h = np.zeros((n, 6))
    com = np.zeros((n, 3))
    for row in range(n):
        _forward(q[row], parent, kind, idx_q, rot, trans, r, p, rb, rj, tmp)
        for i in range(1, nj):
            a, iv = parent[i], idx_v[i]
            if kind[i] == _FREE_FLYER:
                _mat_vec(r[i], v[row, iv : iv + 3], vel[i])
                _mat_vec(r[i], v[row, iv + 3 : iv + 6], omega[i])
            else:
                axis, qd = kind[i] - 1, v[row, iv]
                for b in range(3):
                    omega[i, b] = omega[a, b] + r[i, b, axis] * qd
                    vel[i, b] = vel[a, b]
                    tmp[b] = p[i, b] - p[a, b]
                _cross_add(omega[a], tmp, 1.0, vel[i])
            _mat_vec(r[i], lever[i], arm)
            for b in range(3):
                c[i, b] = p[i, b] + arm[b]
                vc[i, b] = vel[i, b]
                com[row, b] += mass[i] * c[i, b]
            _cross_add(omega[i], arm, 1.0, vc[i])
        for b in range(3):
            com[row, b] /= total
        for i in range(1, nj):
            _mat_t_vec(r[i], omega[i], tmp)
            _mat_vec(inertia[i], tmp, tmp2)
            _mat_vec(r[i], tmp2, tmp)
            for b in range(3):
                h[row, b] += mass[i] * vc[i, b]
                h[row, 3 + b] += tmp[b]
                arm[b] = c[i, b] - com[row, b]
            _cross_add(arm, vc[i], mass[i], h[row, 3:])
    return h, com
