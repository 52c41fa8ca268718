"""Planar five-link biped: 7 DoF, 10 kg, trunk Iyy 0.15 kg m^2 (paper Appendix C, Table III)."""

from gaitnet_mpc.robots.spec import RobotSpec

SPEC = RobotSpec(
    name="biped2d",
    package_dir="biped2d",
    mjcf_file="biped2d.xml",
    planar=True,
    leg_joints={f: (f"{f}_hip_pitch", f"{f}_knee") for f in ("left", "right")},
    arm_joints={},
    foot_sites={"left": "left_foot_center", "right": "right_foot_center"},
    foot_geoms={"left": ("left_foot",), "right": ("right_foot",)},
    trunk_body="trunk",
    # Split stance (left foot 0.08 m ahead, right foot 0.08 m behind the hips, same
    # height): two point feet at one x would make standing an inverted pendulum.
    nominal_joint_pos_rad={
        "left_hip_pitch": -0.55,
        "right_hip_pitch": -0.15,
        "left_knee": 0.7,
        "right_knee": 0.7,
    },
    foot_contact_radius_m=0.02,
)
