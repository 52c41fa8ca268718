"""MuJoCo simulation of one robot on one terrain course at 1 kHz.

Joint torques are saturated at the actuator limits. The simulator applies pushes and an
unknown payload, reads out :class:`RobotState`, detects falls and divergence of the
simulation, counts self-collisions and logs every touchdown.

(Over 500 lines because those read-outs share one pass over MuJoCo's contact list per
tick; split, each would walk it again.)
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.sim.cart import CART_JOINT, CART_PLATE, Cart, cart_xml
from gaitnet_mpc.sim.disturbances import Push
from gaitnet_mpc.state import RobotState
from gaitnet_mpc.terrain import Course, course_geoms_xml

_SCENE_XML = """
    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true" diffuse="0.8 0.8 0.8"
           castshadow="false"/>
    <geom name="pit_floor" type="plane" size="60 10 0.1" pos="10 0 -0.6" rgba="0.12 0.12 0.14 1"
          contype="0" conaffinity="0"/>
"""
_VISUAL_XML = """
  <visual>
    <global offwidth="1280" offheight="720"/>
    <quality offsamples="0"/>
    <headlight ambient="0.4 0.4 0.4" diffuse="0.4 0.4 0.4"/>
  </visual>
  <asset>
    <texture type="skybox" builtin="gradient" rgb1="0.55 0.7 0.85" rgb2="0.95 0.95 1.0"
             width="256" height="256"/>
  </asset>
"""


#: Largest payload any :class:`SimConfig` accepts [kg]; :class:`Simulator` further limits it
#: to the robot's own mass (16 kg humanoid3d, 10 kg biped2d).
MAX_PAYLOAD_KG = 50.0

#: MuJoCo warnings that mean the state became non-finite or huge (|x| > 1e10). MuJoCo then
#: resets ``mjData`` (time included) and goes on, so they are detected by their counters.
#: CONTACTFULL / CNSTRFULL (arena full) and INERTIA / BADCTRL are not divergence.
_DIVERGENCE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)


def tilt_rad(rot: np.ndarray) -> float:
    """Angle between a body's z axis (third column of its rotation ``rot`` (3, 3)) and the
    world's vertical [rad]."""
    return float(np.arccos(np.clip(rot[2, 2], -1.0, 1.0)))


def check_payload(
    payload_kg: float, robot_mass_kg: float | None = None, field: str = "payload_kg"
) -> None:
    """Raise :class:`ConfigError` unless ``0 <= payload_kg <= min(robot_mass_kg, 50 kg)``.

    A payload as heavy as the robot itself is already far beyond the unknown loads a
    controller is expected to carry (a few kg); more would make the actuators, not the
    controller, the limit. Without ``robot_mass_kg`` only :data:`MAX_PAYLOAD_KG` applies.
    """
    if robot_mass_kg is None or robot_mass_kg >= MAX_PAYLOAD_KG:
        bound, why = MAX_PAYLOAD_KG, ""
    else:
        bound, why = robot_mass_kg, " (at most the robot's own mass)"
    if not (np.isfinite(payload_kg) and 0 <= payload_kg <= bound):
        raise ConfigError(field, payload_kg, f"a mass in [0, {bound:g}] kg{why}")


@dataclass(frozen=True)
class SimConfig:
    """Simulator settings.

    Attributes:
        timestep_s: physics and control period [s] (1 kHz).
        payload_kg: mass added to the trunk at its CoM that no controller is told about
            [kg], in [0, 50] (and at most the robot's own mass, checked by the simulator).
        pushes: impulses applied at the trunk CoM.
        cart: a cart ahead of the robot that its hands can push (Fig. 10); None: no cart.
        fall_com_height_ratio: a fall is declared when the CoM height above the start ground
            drops below this fraction of its nominal standing height.
        fall_tilt_rad: a fall is declared when the trunk's z axis tilts more than this.
        touchdown_min_air_s: a foot must have been airborne this long for a new contact
            to count as a touchdown (debounces contact chatter) [s].
        max_trunk_speed_mps: a trunk linear speed above this means the simulation diverged
            [m/s]. 20 m/s is the speed of a free fall from 20 m, 13x the fastest command
            (1.5 m/s) and 5x the speed of a 0.65 m trunk falling to the ground; the largest
            accepted push (100 N s) adds 6 m/s to the 16 kg humanoid.
        max_joint_speed_radps: a joint speed, or a trunk angular speed, above this means
            the simulation diverged [rad/s]. 500 rad/s (4800 rpm at the joint) is 12-25x
            the no-load speed of legged-robot actuators (20-40 rad/s) and 2.5x the fastest
            joint seen in this simulator, whose motors have no torque-speed limit: 200 rad/s
            at the knee or elbow under torques switching between the limits.
    """

    timestep_s: float = 0.001
    payload_kg: float = 0.0
    pushes: tuple[Push, ...] = ()
    cart: Cart | None = None
    fall_com_height_ratio: float = 0.5
    fall_tilt_rad: float = 1.0
    touchdown_min_air_s: float = 0.03
    max_trunk_speed_mps: float = 20.0
    max_joint_speed_radps: float = 500.0

    def __post_init__(self) -> None:
        if not (0 < self.timestep_s <= 0.01):
            raise ConfigError("timestep_s", self.timestep_s, "a value in (0, 0.01] s")
        check_payload(self.payload_kg)
        for name, value in (
            ("max_trunk_speed_mps", self.max_trunk_speed_mps),
            ("max_joint_speed_radps", self.max_joint_speed_radps),
        ):
            if not (np.isfinite(value) and value > 0):
                raise ConfigError(name, value, "a finite bound > 0")


@dataclass(frozen=True)
class Foothold:
    """One touchdown: when, which foot, where, on which patch, and whether it was allowed."""

    t_s: float
    foot: str
    pos_world_m: tuple[float, float, float]
    patch: int | None
    allowed: bool

    def to_dict(self) -> dict[str, object]:
        return {
            "t_s": round(self.t_s, 4),
            "foot": self.foot,
            "pos_m": [round(v, 4) for v in self.pos_world_m],
            "patch": self.patch,
            "allowed": self.allowed,
        }


@dataclass
class FallStatus:
    """Whether and when the episode ended early, and why.

    ``diverged`` marks a numerical divergence of the simulation (reason
    ``"simulation diverged: ..."``) rather than a fall of the robot.
    """

    fell: bool = False
    t_s: float | None = None
    reason: str = ""
    diverged: bool = False

    def __bool__(self) -> bool:
        """True once the episode fell: ``if sim.fall:`` reads as it says (a dataclass
        without this would be true always, even at t = 0)."""
        return self.fell


@dataclass
class SelfCollisionStats:
    """Contacts between two robot geoms over an episode.

    Attributes:
        ticks: simulation ticks with at least one self-contact.
        first_t_s: time of the first such tick [s]; None if there was none.
        max_depth_m: largest penetration depth of a self-contact [m] (0 if none).
        body_pairs: the pairs of bodies that touched, each as a name-sorted tuple.
    """

    ticks: int = 0
    first_t_s: float | None = None
    max_depth_m: float = 0.0
    body_pairs: set[tuple[str, str]] = field(default_factory=set)

    def to_dict(self) -> dict[str, object]:
        """The ``self_collision*`` fields of ``summary.json``."""
        return {
            "self_collisions": self.ticks,
            "self_collision_first_t_s": self.first_t_s,
            "self_collision_max_depth_m": self.max_depth_m,
            "self_collision_pairs": sorted(f"{a}/{b}" for a, b in self.body_pairs),
        }


def hand_geoms(robot: RobotModel) -> tuple[str, ...]:
    """The geoms a robot pushes with (its forearms); raises :class:`ConfigError` for a robot
    without arms."""
    if not robot.spec.arm_joints:
        raise ConfigError("cart", robot.name, "a robot with arms (humanoid3d)")
    return tuple(f"{f}_forearm" for f in FEET)


def build_scene_xml(robot: RobotModel, course: Course, cart: Cart | None = None) -> str:
    """The robot's MJCF with the course's geoms, a light, a skybox and the cart added."""
    xml = robot.spec.mjcf_path.read_text()
    xml = re.sub(r"(<mujoco[^>]*>)", r"\1" + _VISUAL_XML, xml, count=1)
    xml = xml.replace("<worldbody>", "<worldbody>" + _SCENE_XML + course_geoms_xml(course), 1)
    if cart is not None:  # after the robot: its qpos and qvel come after the robot's
        x0, y0 = course.start_xy
        ground = course.ground_height_at(x0, y0) or 0.0
        body, contact = cart_xml(cart, (x0, y0, ground), hand_geoms(robot))
        xml = xml.replace("</worldbody>", body + "</worldbody>", 1)
        xml = xml.replace("</mujoco>", contact + "</mujoco>", 1)
    return xml


@dataclass
class Simulator:
    """One episode of MuJoCo simulation; create a new one per episode."""

    robot: RobotModel
    course: Course
    config: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        check_payload(self.config.payload_kg, self.robot.total_mass_kg)
        cart = self.config.cart
        self.model = mujoco.MjModel.from_xml_string(build_scene_xml(self.robot, self.course, cart))
        self.model.opt.timestep = self.config.timestep_s
        trunk = self.model.body(self.robot.spec.trunk_body).id
        self.model.body_mass[trunk] += self.config.payload_kg
        self.data = mujoco.MjData(self.model)
        mujoco.mj_setConst(self.model, self.data)
        m = self.model
        self._trunk_id = trunk
        self._terrain_geoms = frozenset(
            g for g in range(m.ngeom) if m.geom_bodyid[g] == 0 and m.geom_contype[g] != 0
        )
        self._foot_of_geom = {
            m.geom(name).id: f for f in FEET for name in self.robot.spec.foot_geoms[f]
        }
        self._foot_sites = {f: m.site(self.robot.spec.foot_sites[f]).id for f in FEET}
        # _contacts() of the data, keyed by the time and qpos it was read at
        self._contact_cache: tuple[bytes, _Contacts] | None = None
        #: geom id -> whether it belongs to the robot (its body hangs from the trunk)
        self._robot_geom = m.body_rootid[m.geom_bodyid] == trunk
        self._cart_plate = m.geom(CART_PLATE).id if cart is not None else -1
        slide = m.joint(CART_JOINT).id if cart is not None else -1
        self._cart_adr = (int(m.jnt_qposadr[slide]), int(m.jnt_dofadr[slide]))
        #: the robot's own coordinates (the cart's slide joint, if any, comes after them)
        self._nq, self._nv = self.robot.mj_model.nq, self.robot.mj_model.nv
        self._body_names = [m.body(b).name for b in range(m.nbody)]
        self._act_limit = m.actuator_ctrlrange[:, 1].copy()
        r = self.robot
        self._lin_dofs = slice(0, 2) if r.spec.planar else slice(0, 3)
        self._ang_dofs = slice(2, 3) if r.spec.planar else slice(3, 6)
        self._joint_dofs = np.asarray(r.joint_dof_adr)
        self._warn_ids = np.array([int(w) for w in _DIVERGENCE_WARNINGS])
        self._good_qpos = np.zeros(m.nq)
        self._good_qvel = np.zeros(m.nv)
        self._good_act = np.zeros(m.na)
        self.footholds: list[Foothold] = []
        self.fall = FallStatus()
        self.self_collisions = SelfCollisionStats()
        #: whether the current state has a self-contact (for the per-tick log)
        self.self_contact = False
        self._last_contact_t = dict.fromkeys(FEET, -np.inf)
        self._in_contact = dict.fromkeys(FEET, True)
        self.reset()

    # ------------------------------------------------------------------ episode
    def reset(self, qpos: np.ndarray | None = None) -> RobotState:
        """Put the robot in ``qpos`` (default: nominal standing pose at the course start)."""
        mujoco.mj_resetData(self.model, self.data)
        x0, y0 = self.course.start_xy
        ground = self.course.ground_height_at(x0, y0) or 0.0
        self.data.qpos[: self._nq] = (
            self.robot.standing_qpos(x0, y0, ground) if qpos is None else np.asarray(qpos)
        )
        mujoco.mj_forward(self.model, self.data)
        self._ground0_m = ground
        self._com_height0_m = float(self.data.subtree_com[self._trunk_id, 2] - ground)
        self.footholds.clear()
        self.fall = FallStatus()
        self.self_collisions = SelfCollisionStats()
        self.self_contact = self._self_contacts() is not None
        self._save_good_state()
        self._in_contact = dict.fromkeys(FEET, True)
        self._last_contact_t = dict.fromkeys(FEET, 0.0)
        return self.state()

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    @property
    def com_height_m(self) -> float:
        """CoM height above the ground under the start position [m] (the fall check's)."""
        return float(self.data.subtree_com[self._trunk_id, 2] - self._ground0_m)

    @property
    def diverged(self) -> bool:
        """Whether the simulation diverged (which also ended the episode as a fall)."""
        return self.fall.diverged

    def set_pushes(self, pushes: tuple[Push, ...]) -> None:
        """Replace the pushes to come, e.g. in a copy of an episode that was simulated
        without them (:mod:`~gaitnet_mpc.experiments.forked_episode`). Each must start
        after the last step already simulated began (the current time less a timestep):
        a push would have acted on that step."""
        last_step_s = self.time_s - self.config.timestep_s
        for i, push in enumerate(pushes):
            if push.t_s <= last_step_s + 1e-9:
                expected = f"a start after {last_step_s:.6g} s (the last step simulated)"
                raise ConfigError(f"pushes[{i}].t_s", push.t_s, expected)
        self.config = replace(self.config, pushes=tuple(pushes))

    def step(self, tau_nm: np.ndarray) -> None:
        """Apply joint torques (saturated at the limits) for one timestep.

        If the step diverges (see :meth:`_divergence`), the episode ends as a fall with
        reason ``"simulation diverged: ..."`` at the tick's end time, and ``qpos``, ``qvel``
        and ``act`` are rolled back to the last state that passed the checks (normally the
        one before the step), so that the summary's distance and speed stay meaningful.
        """
        tau = np.asarray(tau_nm, dtype=float)
        if tau.shape != (self.model.nu,):
            raise ConfigError("tau_nm", tau.shape, f"shape ({self.model.nu},)")
        if not np.all(np.isfinite(tau)):
            raise ConfigError("tau_nm", tau, "finite torques (a controller produced NaN/inf)")
        self.data.ctrl[:] = np.clip(tau, -self._act_limit, self._act_limit)
        t = self.time_s
        force = np.zeros(3)
        for push in self.config.pushes:
            if push.active(t):
                force += push.force_world_n
        self.data.xfrc_applied[self._trunk_id, :3] = force
        warnings0 = self.data.warning.number[self._warn_ids].copy()
        mujoco.mj_step(self.model, self.data)
        t_end = t + self.model.opt.timestep
        reason = self._divergence(t, warnings0)
        if reason is None:
            self._save_good_state()
            self._update_contacts_and_falls()
        elif not self.fall.fell:
            self._roll_back(t_end)
            self.fall = FallStatus(True, t_end, f"simulation diverged: {reason}", diverged=True)

    # -------------------------------------------------------------- divergence
    def _divergence(self, t_before_s: float, warnings_before: np.ndarray) -> str | None:
        """Why the step that started at ``t_before_s`` diverged, or None if it did not.

        Checks MuJoCo's BADQPOS / BADQVEL / BADQACC counters (MuJoCo resets the state when
        it raises them, so the clock going back is checked too), non-finite ``qpos`` /
        ``qvel`` / ``qacc``, and the speed bounds of :class:`SimConfig`.
        """
        d, cfg = self.data, self.config
        raised = np.flatnonzero(d.warning.number[self._warn_ids] != warnings_before)
        if raised.size:
            w = mujoco.mjtWarning(int(self._warn_ids[raised[0]]))
            info = int(d.warning.lastinfo[int(w)])
            name = w.name.removeprefix("mjWARN_")
            return f"MuJoCo warning {name} (DOF {info}) at t = {t_before_s:.3f} s"
        if d.time < t_before_s + 0.5 * self.model.opt.timestep:
            return f"MuJoCo reset the state at t = {t_before_s:.3f} s"
        qvel = d.qvel
        if not np.isfinite(d.qpos.sum() + qvel.sum() + d.qacc.sum()):  # fast path first
            for name, x in (("qpos", d.qpos), ("qvel", qvel), ("qacc", d.qacc)):
                if not np.all(np.isfinite(x)):
                    return f"non-finite {name} at t = {t_before_s:.3f} s"
        lin, ang = qvel[self._lin_dofs], qvel[self._ang_dofs]
        v = float(np.sqrt(lin @ lin))
        if v > cfg.max_trunk_speed_mps:
            return f"trunk speed {v:.3g} m/s above {cfg.max_trunk_speed_mps:g} m/s"
        w_max = max(float(np.sqrt(ang @ ang)), float(np.abs(qvel[self._joint_dofs]).max()))
        if w_max > cfg.max_joint_speed_radps:
            bound = cfg.max_joint_speed_radps
            return f"joint or trunk angular speed {w_max:.3g} rad/s above {bound:g} rad/s"
        return None

    def _save_good_state(self) -> None:
        """Keep the current state as the last one that passed the divergence checks."""
        d = self.data
        np.copyto(self._good_qpos, d.qpos)
        np.copyto(self._good_qvel, d.qvel)
        np.copyto(self._good_act, d.act)

    def _roll_back(self, t_s: float) -> None:
        """Restore the last state that passed the checks, with the clock at ``t_s``."""
        d = self.data
        d.qpos[:] = self._good_qpos
        d.qvel[:] = self._good_qvel
        d.act[:] = self._good_act
        d.time = t_s
        d.xfrc_applied[:] = 0.0
        mujoco.mj_forward(self.model, d)
        self.self_contact = self._self_contacts() is not None

    # ---------------------------------------------------------------- read-out
    def _contacts(self) -> _Contacts:
        """Per-foot ground wrench, feet in contact, and whether a non-foot body touches terrain."""
        m, d = self.model, self.data
        wrench = {f: np.zeros(6) for f in FEET}
        touching: set[str] = set()
        other = False
        c6 = np.zeros(6)
        for i in range(d.ncon):
            con = d.contact[i]
            g1, g2 = int(con.geom1), int(con.geom2)
            if g1 in self._terrain_geoms:
                robot_geom, sign = g2, 1.0  # force on geom2 from geom1 is +frame normal
            elif g2 in self._terrain_geoms:
                robot_geom, sign = g1, -1.0
            else:
                continue
            foot = self._foot_of_geom.get(robot_geom)
            if foot is None:
                other = True
                continue
            touching.add(foot)
            mujoco.mj_contactForce(m, d, i, c6)
            frame = con.frame.reshape(3, 3)
            f_world = sign * frame.T @ c6[:3]
            r = con.pos - d.site_xpos[self._foot_sites[foot]]
            wrench[foot][:3] += f_world
            wrench[foot][3:] += _cross3(r, f_world)
        return wrench, touching, other

    def _contacts_now(self) -> _Contacts:
        """:meth:`_contacts` of the current MuJoCo data, computed once per state (the
        step's fall checks and the next :meth:`state` read the same contacts); the cache
        is keyed by the time and ``qpos``, so a state set from outside is read afresh."""
        d = self.data
        key = np.float64(d.time).tobytes() + d.qpos.tobytes()
        if self._contact_cache is None or self._contact_cache[0] != key:
            self._contact_cache = (key, self._contacts())
        wrench, touching, other = self._contact_cache[1]
        return {f: w.copy() for f, w in wrench.items()}, set(touching), other

    def _self_contacts(self) -> np.ndarray | None:
        """Indices into ``data.contact`` of active contacts between two robot geoms."""
        d = self.data
        if d.ncon == 0:
            return None
        con = d.contact
        mask = self._robot_geom[con.geom].all(axis=1) & (con.exclude == 0)
        return np.flatnonzero(mask) if mask.any() else None

    def _update_self_collisions(self) -> None:
        """Record this tick's self-contacts in :attr:`self_collisions`."""
        idx = self._self_contacts()
        self.self_contact = idx is not None
        if idx is None:
            return
        stats = self.self_collisions
        stats.ticks += 1
        if stats.first_t_s is None:
            stats.first_t_s = self.time_s
        con = self.data.contact
        depth = -float(con.dist[idx].min())
        stats.max_depth_m = max(stats.max_depth_m, depth)
        bodies = self.model.geom_bodyid[con.geom[idx]]
        for b1, b2 in bodies:
            n1, n2 = sorted((self._body_names[b1], self._body_names[b2]))
            stats.body_pairs.add((n1, n2))

    def _update_contacts_and_falls(self) -> None:
        d = self.data
        t = self.time_s
        self._update_self_collisions()
        _, touching, other = self._contacts_now()
        for foot in FEET:
            now = foot in touching
            if now and not self._in_contact[foot]:
                if t - self._last_contact_t[foot] >= self.config.touchdown_min_air_s:
                    self._log_touchdown(foot)
            if now:
                self._last_contact_t[foot] = t
            self._in_contact[foot] = now
        if self.fall.fell:
            return
        com_z = self.com_height_m
        tilt = tilt_rad(d.xmat[self._trunk_id].reshape(3, 3))
        if other:
            self.fall = FallStatus(True, t, "a body other than a foot touched the terrain")
        elif com_z < self.config.fall_com_height_ratio * self._com_height0_m:
            self.fall = FallStatus(True, t, f"CoM height {com_z:.3f} m below threshold")
        elif tilt > self.config.fall_tilt_rad:
            self.fall = FallStatus(True, t, f"trunk tilt {tilt:.2f} rad above threshold")

    def _log_touchdown(self, foot: str) -> None:
        p = self.data.site_xpos[self._foot_sites[foot]].copy()
        self.footholds.append(
            Foothold(
                t_s=self.time_s,
                foot=foot,
                pos_world_m=(float(p[0]), float(p[1]), float(p[2])),
                patch=self.course.patch_at(p[0], p[1]),
                allowed=self.course.foot_allowed(p[0], p[1], foot),
            )
        )

    def cart_reading(self) -> tuple[float, float, np.ndarray]:
        """The cart's x position of its plate's rear face [m], its speed [m/s], and the
        force the plate puts on the hands (world frame, (3,)) [N]; needs ``config.cart``."""
        cart = self.config.cart
        if cart is None:
            raise ConfigError("cart", None, "a simulator made with SimConfig(cart=...)")
        m, d = self.model, self.data
        force = np.zeros(3)
        c6 = np.zeros(6)
        for i in range(d.ncon):
            con = d.contact[i]
            if self._cart_plate not in (con.geom1, con.geom2):
                continue
            mujoco.mj_contactForce(m, d, i, c6)
            # force on geom2 from geom1 is +frame normal; the hand is the other geom
            f_world = con.frame.reshape(3, 3).T @ c6[:3]
            force += f_world if con.geom1 == self._cart_plate else -f_world
        x0 = self.course.start_xy[0] + cart.plate_ahead_m
        q_adr, v_adr = self._cart_adr
        return x0 + float(d.qpos[q_adr]), float(d.qvel[v_adr]), force

    def _site_yaw(self, site_id: int) -> float:
        x_axis = self.data.site_xmat[site_id].reshape(3, 3)[:, 0]
        return float(np.arctan2(x_axis[1], x_axis[0]))

    def state(self) -> RobotState:
        """Read the current state (no side effects on the simulation)."""
        m, d, r = self.model, self.data, self.robot
        mujoco.mj_subtreeVel(m, d)
        root = self._trunk_id
        wrench, touching, _ = self._contacts_now()
        p_base, rot = r.base_pose(d.qpos)
        if r.spec.planar:
            v_base = np.array([d.qvel[0], 0.0, d.qvel[1]])
            w_base = np.array([0.0, d.qvel[2], 0.0])
        else:
            v_base = d.qvel[0:3].copy()
            w_base = rot @ d.qvel[3:6]
        mass = float(m.body_subtreemass[root])
        return RobotState(
            t_s=float(d.time),
            qpos=d.qpos[: self._nq].copy(),
            qvel=d.qvel[: self._nv].copy(),
            base_pos_world_m=p_base,
            base_rot_world=rot,
            base_lin_vel_world_mps=v_base,
            base_ang_vel_world_radps=w_base,
            joint_pos_rad=d.qpos[r.joint_qpos_adr].copy(),
            joint_vel_radps=d.qvel[r.joint_dof_adr].copy(),
            com_world_m=d.subtree_com[root].copy(),
            com_vel_world_mps=d.subtree_linvel[root].copy(),
            h_measured=np.concatenate([mass * d.subtree_linvel[root], d.subtree_angmom[root]]),
            foot_pos_world_m={f: d.site_xpos[self._foot_sites[f]].copy() for f in FEET},
            foot_yaw_rad={f: self._site_yaw(self._foot_sites[f]) for f in FEET},
            foot_contact={f: f in touching for f in FEET},
            foot_wrench_world=wrench,
        )


#: Per-foot ground wrench, the feet in contact, and whether a non-foot body touches terrain.
_Contacts = tuple[dict[str, np.ndarray], set[str], bool]


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two 3-vectors, without its general-shape overhead (same result)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )
