"""MuJoCo simulation of one robot on one terrain course at 1 kHz.

Joint torques are saturated at the actuator limits. The simulator applies pushes and an
unknown payload, reads out :class:`RobotState`, detects falls and logs every touchdown.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import mujoco
import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots import FEET, RobotModel
from gaitnet_mpc.sim.disturbances import Push
from gaitnet_mpc.sim.state import RobotState
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


@dataclass(frozen=True)
class SimConfig:
    """Simulator settings.

    Attributes:
        timestep_s: physics and control period [s] (1 kHz).
        payload_kg: mass added to the trunk at its CoM that no controller is told about [kg].
        pushes: impulses applied at the trunk CoM.
        fall_com_height_ratio: a fall is declared when the CoM height above the start ground
            drops below this fraction of its nominal standing height.
        fall_tilt_rad: a fall is declared when the trunk's z axis tilts more than this.
        touchdown_min_air_s: a foot must have been airborne this long for a new contact
            to count as a touchdown (debounces contact chatter) [s].
    """

    timestep_s: float = 0.001
    payload_kg: float = 0.0
    pushes: tuple[Push, ...] = ()
    fall_com_height_ratio: float = 0.5
    fall_tilt_rad: float = 1.0
    touchdown_min_air_s: float = 0.03

    def __post_init__(self) -> None:
        if not (0 < self.timestep_s <= 0.01):
            raise ConfigError("timestep_s", self.timestep_s, "a value in (0, 0.01] s")
        if not (np.isfinite(self.payload_kg) and self.payload_kg >= 0):
            raise ConfigError("payload_kg", self.payload_kg, "a finite mass >= 0 kg")


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
    fell: bool = False
    t_s: float | None = None
    reason: str = ""


def build_scene_xml(robot: RobotModel, course: Course) -> str:
    """The robot's MJCF with the course's geoms, a light and a skybox added."""
    xml = robot.spec.mjcf_path.read_text()
    xml = re.sub(r"(<mujoco[^>]*>)", r"\1" + _VISUAL_XML, xml, count=1)
    return xml.replace("<worldbody>", "<worldbody>" + _SCENE_XML + course_geoms_xml(course), 1)


@dataclass
class Simulator:
    """One episode of MuJoCo simulation; create a new one per episode."""

    robot: RobotModel
    course: Course
    config: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        self.model = mujoco.MjModel.from_xml_string(build_scene_xml(self.robot, self.course))
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
        self._act_limit = m.actuator_ctrlrange[:, 1].copy()
        self.footholds: list[Foothold] = []
        self.fall = FallStatus()
        self._last_contact_t = dict.fromkeys(FEET, -np.inf)
        self._in_contact = dict.fromkeys(FEET, True)
        self.reset()

    # ------------------------------------------------------------------ episode
    def reset(self, qpos: np.ndarray | None = None) -> RobotState:
        """Put the robot in ``qpos`` (default: nominal standing pose at the course start)."""
        mujoco.mj_resetData(self.model, self.data)
        x0, y0 = self.course.start_xy
        ground = self.course.ground_height_at(x0, y0) or 0.0
        self.data.qpos[:] = (
            self.robot.standing_qpos(x0, y0, ground) if qpos is None else np.asarray(qpos)
        )
        mujoco.mj_forward(self.model, self.data)
        self._ground0_m = ground
        self._com_height0_m = float(self.data.subtree_com[self._trunk_id, 2] - ground)
        self.footholds.clear()
        self.fall = FallStatus()
        self._in_contact = dict.fromkeys(FEET, True)
        self._last_contact_t = dict.fromkeys(FEET, 0.0)
        return self.state()

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    def step(self, tau_nm: np.ndarray) -> None:
        """Apply joint torques (saturated at the limits) for one timestep."""
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
        mujoco.mj_step(self.model, self.data)
        self._update_contacts_and_falls()

    # ---------------------------------------------------------------- read-out
    def _contacts(self) -> tuple[dict[str, np.ndarray], set[str], bool]:
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
            wrench[foot][3:] += np.cross(r, f_world)
        return wrench, touching, other

    def _update_contacts_and_falls(self) -> None:
        d = self.data
        t = self.time_s
        _, touching, other = self._contacts()
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
        com_z = d.subtree_com[self._trunk_id, 2] - self._ground0_m
        z_axis = d.xmat[self._trunk_id].reshape(3, 3)[:, 2]
        tilt = float(np.arccos(np.clip(z_axis[2], -1.0, 1.0)))
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

    def _site_yaw(self, site_id: int) -> float:
        x_axis = self.data.site_xmat[site_id].reshape(3, 3)[:, 0]
        return float(np.arctan2(x_axis[1], x_axis[0]))

    def state(self) -> RobotState:
        """Read the current state (no side effects on the simulation)."""
        m, d, r = self.model, self.data, self.robot
        mujoco.mj_subtreeVel(m, d)
        root = self._trunk_id
        wrench, touching, _ = self._contacts()
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
            qpos=d.qpos.copy(),
            qvel=d.qvel.copy(),
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
