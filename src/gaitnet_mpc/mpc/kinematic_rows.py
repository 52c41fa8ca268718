"""Rows that keep the CMPC's plan kinematically possible, beyond the paper: the feet's
lateral separation (``KDConfig.min_foot_separation_m``, stated in
:mod:`~gaitnet_mpc.mpc.implicit_kd`) and the legs' reach (``KDConfig.leg_reach_m``, below).

Reach rows: every planned touchdown within its leg's length of the hip.

The CMPC QP of eq. 18 moves the CoM and the footholds with no kinematic limit between
them (the paper leaves reach to ``f_IK``, which only reports it). After a push the plan
then asks for footholds the leg cannot reach: under a 100 N forward push at 0.5 m/s the
plan put the next touchdown 0.40 m ahead of the CoM at 0.55 m height, where the hip is
0.57 m from the foot and the leg is 0.44 m long; ``f_IK`` flagged the stages unreachable,
the swing knee went straight and the foot scuffed (``docs/design/leg_reach.md``).

The rows (not in the paper). For a foot ``i`` that touches down at stage ``k`` (stance at
``k``, swing at ``k - 1``), with the hip pitch joint at ``p_c,k + R_z(psi) o_i`` (``o_i``:
the hip's offset from the CoM at the standing pose in the foot's heading frame ``psi``,
less the foot centre's offset from the ankle), the leg reaches the ball
``||d|| <= l``, ``d = p_f,k,i - p_c,k - R_z(psi) o_i``. The QP bounds ``d`` by four faces
of a pyramid around the ball, fixed in the heading frame: forward, backward, left and
right, each tilted by ``alpha`` from the downward vertical,

    n_m^T d <= l,   n_m = R_z(psi) (sx sin(alpha), sy sin(alpha), -cos(alpha)),

with ``(sx, sy)`` in ``(1, 0), (-1, 0), (0, 1), (0, -1)``. Each face is tangent to the
ball where the straight leg points ``alpha`` away from the vertical; ``alpha = acos(z_0 /
l)``, ``z_0`` the hip's height above the ankle at the standing pose, is where a straight
leg lands at the standing hip height (humanoid3d: acos(0.413 / 0.44) = 20 deg, a
horizontal reach of 0.15 m from the hip). The pyramid contains the ball: it is exact at
that height and lets a lower hip reach somewhat further than the ball does. The faces are
fixed, so the rows are linear in the search directions, ``n_m^T (delta p_f,k,i - delta
p_c,k) <= l - n_m^T d^j``, with no re-linearisation: tangent planes re-taken at each
iterate made the sequential iteration cycle (a 2-cycle of 2.6 cm in a touchdown's lateral
position after a 100 N push), and planes held from a solve's first iterate bound nothing
when that iterate's foot is under the hip. Only touchdowns are bounded: later in its
stance the CoM passes over the foot, and how far it may go before the next touchdown is
the step timing's business (bounding every stance stage cost 3 of 20 tuning stone
layouts).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from gaitnet_mpc.jit import njit_cached
from gaitnet_mpc.kinematics.leg_ik import LegGeometry, leg_geometries
from gaitnet_mpc.mpc.kd_config import KDConfig
from gaitnet_mpc.mpc.kd_inputs import KDInputs
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.robots.model import RobotModel

FEET = ("left", "right")


def separation_rows(
    it: KDIterate, contact: np.ndarray, foot_yaw_rad: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Leftward axes ``n_y(psi_k)`` (h, 2) of the separation rows (``psi_k``: the heading
    of the foot in swing at stage ``k``, the right foot's where both or neither stand) and
    the iterate's separation ``n_y^T (p_left - p_right)`` (h,) [m]."""
    h = contact.shape[0]
    swing = np.where(contact[:, 1] & ~contact[:, 0], 0, 1)
    yaw = foot_yaw_rad[np.arange(h), swing]
    n_y = np.stack([-np.sin(yaw), np.cos(yaw)], axis=1)  # left = +y of the heading
    d = it.p_foot[:, 0, :2] - it.p_foot[:, 1, :2]
    return n_y, np.einsum("kj,kj->k", n_y, d)


def reach_geometry(robot: RobotModel) -> tuple[tuple[float, ...], float, float]:
    """``(o, l, alpha)``: the hip pitch joints' offsets from the CoM at the standing pose
    in the heading frame, less the foot centre's offset from the ankle (6 values, left
    then right) [m]; the leg's length from the hip pitch joint to the ankle [m]; the
    faces' tilt ``acos(z_0 / l)`` [rad] (humanoid3d: (0.009, +-0.065, -0.132), 0.44 m,
    0.35 rad)."""
    legs = leg_geometries(robot)
    if not all(isinstance(legs[f], LegGeometry) for f in FEET):
        raise ValueError(f"{robot.name}: reach rows need the 5-DoF legs of a 3-D humanoid")
    q, _ = robot.mj_to_pin(robot.standing_qpos(), np.zeros(robot.nv))
    data = robot.pin_model.createData()
    com = pin.centerOfMass(robot.pin_model, data, q)
    pin.framesForwardKinematics(robot.pin_model, data, q)
    offsets: list[float] = []
    lengths, heights = [], []
    for f in FEET:
        g = legs[f]
        assert isinstance(g, LegGeometry)
        hip = q[:3] + g.p_yaw_trunk_m + g.p_roll_yaw_m + g.p_pitch_roll_m
        offsets.extend(hip - com + g.p_foot_ankle_m)
        lengths.append(g.thigh_m + g.shank_m)
        ankle = data.oMf[robot.pin_model.getFrameId(robot.spec.foot_sites[f])].translation
        heights.append(hip[2] - ankle[2])
    leg_m = float(min(lengths))
    return tuple(float(x) for x in offsets), leg_m, float(np.arccos(max(heights) / leg_m))


#: ``(sx, sy)`` of the four faces: forward, backward, left, right (heading frame).
_FACES = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])


def qp_reach_rows(
    config: KDConfig, it: KDIterate, a: KDInputs, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reach rows of one QP about ``it`` (module docstring): ``active`` (h, 2), the
    touchdowns; ``normal`` (h, 2, 4, 3), the faces ``n_m``; ``bound`` (h, 2, 4), the row
    ``n_m^T (delta p_f - delta p_c) <= bound`` with ``bound = l - n_m^T d^j``, or what the
    foot's bounds ``lo, hi`` (h, 2, 3) let ``n_m^T delta p_f`` reach if that is more (a
    foot boxed out of reach keeps the QP feasible). None active without
    ``config.leg_reach_m``. The trigonometry here, the rows in :func:`_reach_kernel`."""
    contact = a.contact
    h = contact.shape[0]
    if config.leg_reach_m is None:
        return np.zeros((h, 2), dtype=bool), np.zeros((h, 2, 4, 3)), np.zeros((h, 2, 4))
    alpha = config.reach_tilt_rad
    return _reach_kernel(
        contact,
        np.cos(a.foot_yaw_rad),
        np.sin(a.foot_yaw_rad),
        _FACES[:, 0] * np.sin(alpha),
        _FACES[:, 1] * np.sin(alpha),
        float(np.cos(alpha)),
        np.reshape(np.asarray(config.hip_offset_m, dtype=float), (2, 3)),
        float(config.leg_reach_m),
        it.p_foot,
        it.p_com,
        lo,
        hi,
    )


@njit_cached()
def _reach_kernel(
    contact: np.ndarray,
    cos_yaw: np.ndarray,
    sin_yaw: np.ndarray,
    face_x: np.ndarray,
    face_y: np.ndarray,
    cos_alpha: float,
    hips: np.ndarray,
    leg_m: float,
    p_foot: np.ndarray,
    p_com: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`qp_reach_rows`'s rows, touchdown by touchdown (the rest stay zero)."""
    h = contact.shape[0]
    active = np.zeros((h, 2), dtype=np.bool_)
    normal = np.zeros((h, 2, 4, 3))
    bound = np.zeros((h, 2, 4))
    d = np.empty(3)
    for k in range(1, h):
        for i in range(2):
            if not (contact[k, i] and not contact[k - 1, i]):
                continue
            active[k, i] = True
            c, s = cos_yaw[k, i], sin_yaw[k, i]
            d[0] = p_foot[k, i, 0] - p_com[k, 0] - (c * hips[i, 0] - s * hips[i, 1])
            d[1] = p_foot[k, i, 1] - p_com[k, 1] - (s * hips[i, 0] + c * hips[i, 1])
            d[2] = p_foot[k, i, 2] - p_com[k, 2] - hips[i, 2]
            for m in range(4):
                normal[k, i, m, 0] = c * face_x[m] - s * face_y[m]
                normal[k, i, m, 1] = s * face_x[m] + c * face_y[m]
                normal[k, i, m, 2] = -cos_alpha
                n = normal[k, i, m]
                # the order of numpy's einsum here, so that results stay bitwise those of
                # the vectorised form this replaced
                dot = (n[0] * d[0] + n[2] * d[2]) + n[1] * d[1]
                closest = 0.0
                for ax in range(3):
                    n_a = n[ax]
                    if n_a > 0.0:
                        closest += (lo[k, i, ax] - p_foot[k, i, ax]) * n_a
                    elif n_a < 0.0:
                        closest += (hi[k, i, ax] - p_foot[k, i, ax]) * n_a
                bound[k, i, m] = max(leg_m - dot, closest)
    return active, normal, bound


__all__ = ["qp_reach_rows", "reach_geometry", "separation_rows"]
