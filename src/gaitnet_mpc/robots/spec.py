"""Static description of a robot: which MJCF, which joints form each leg, foot geometry.

Everything numeric that the MJCF already holds (masses, limits, torque limits) is read
from the MJCF at load time by :mod:`gaitnet_mpc.robots.model`; the spec only holds
names and the nominal pose, which the MJCF cannot express.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

FEET = ("left", "right")


@dataclass(frozen=True)
class RobotSpec:
    """Names and nominal configuration of one robot.

    Attributes:
        name: registry name (``humanoid3d`` or ``biped2d``).
        package_dir: sub-package holding the MJCF (``gaitnet_mpc.robots.<dir>``).
        mjcf_file: MJCF file name inside that package.
        planar: True for the sagittal-plane robot (root = slide x, slide z, hinge pitch).
        leg_joints: per foot, the leg joint names from hip to ankle.
        arm_joints: per side, the arm joint names from shoulder to elbow.
        foot_sites: per foot, the MJCF site at the foot centre (the foothold point p_f).
        foot_geoms: per foot, the MJCF geoms that may touch the ground.
        trunk_body: the floating-base body.
        nominal_joint_pos_rad: standing pose, joint name -> angle [rad]; others 0.
        foot_toe_m: distance from foot centre to toe along the foot axis [m] (0 = point foot).
        foot_heel_m: distance from foot centre to heel [m].
        foot_contact_radius_m: height of the foothold point above the ground in contact [m].
        lower_leg_geoms: per foot, the MJCF geoms of the shank and foot (their lateral
            half-widths set :attr:`RobotModel.min_foot_separation_m`).
        leg_clearance_m: lateral gap kept between the two lower legs by foot placement, on
            top of their half-widths, for swing tracking and landing errors [m]; None for a
            planar robot whose legs move in separate planes.
    """

    name: str
    package_dir: str
    mjcf_file: str
    planar: bool
    leg_joints: dict[str, tuple[str, ...]]
    arm_joints: dict[str, tuple[str, ...]]
    foot_sites: dict[str, str]
    foot_geoms: dict[str, tuple[str, ...]]
    trunk_body: str
    nominal_joint_pos_rad: dict[str, float] = field(default_factory=dict)
    foot_toe_m: float = 0.0
    foot_heel_m: float = 0.0
    foot_contact_radius_m: float = 0.0
    lower_leg_geoms: dict[str, tuple[str, ...]] = field(default_factory=dict)
    leg_clearance_m: float | None = None

    @property
    def mjcf_path(self) -> Path:
        """Absolute path of the MJCF file inside the installed package."""
        ref = resources.files(f"gaitnet_mpc.robots.{self.package_dir}") / self.mjcf_file
        return Path(str(ref))
