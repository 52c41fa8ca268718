"""24-DoF, 16 kg humanoid with 5-DoF legs and line feet (paper Appendix C, Table IV)."""

from gaitnet_mpc.robots.spec import RobotSpec

_LEG = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch")
_ARM = ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow")

HIP_PITCH_STAND_RAD = -0.35
KNEE_STAND_RAD = 0.70

SPEC = RobotSpec(
    name="humanoid3d",
    package_dir="humanoid3d",
    mjcf_file="humanoid3d.xml",
    planar=False,
    leg_joints={f: tuple(f"{f}_{j}" for j in _LEG) for f in ("left", "right")},
    arm_joints={f: tuple(f"{f}_{j}" for j in _ARM) for f in ("left", "right")},
    foot_sites={"left": "left_foot_center", "right": "right_foot_center"},
    foot_geoms={"left": ("left_foot",), "right": ("right_foot",)},
    trunk_body="trunk",
    nominal_joint_pos_rad={
        **{f"{f}_hip_pitch": HIP_PITCH_STAND_RAD for f in ("left", "right")},
        **{f"{f}_knee": KNEE_STAND_RAD for f in ("left", "right")},
        **{f"{f}_ankle_pitch": -(HIP_PITCH_STAND_RAD + KNEE_STAND_RAD) for f in ("left", "right")},
        "left_shoulder_roll": 0.1,
        "right_shoulder_roll": -0.1,
        "left_elbow": -0.3,
        "right_elbow": -0.3,
    },
    foot_toe_m=0.075,
    foot_heel_m=0.075,
    foot_contact_radius_m=0.01,
    lower_leg_geoms={f: (f"{f}_shank", f"{f}_foot") for f in ("left", "right")},
    leg_clearance_m=0.02,
)
