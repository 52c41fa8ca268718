"""Kinematics for the kino-dynamic MPC: analytic leg IK (paper Appendix B) and the
centroidal momentum map / centroidal pose (eqs. 6, 11, 12 and Appendix A)."""

from gaitnet_mpc.kinematics.centroidal import (
    centroidal_map,
    centroidal_map_dot,
    centroidal_map_euler,
    centroidal_map_euler_dot,
    centroidal_pose_eq30,
    centroidal_pose_riemann,
    euler_coordinate_rates,
    euler_coordinates,
    f_j2m,
)
from gaitnet_mpc.kinematics.leg_ik import (
    LegGeometry,
    LegIKSolution,
    PlanarLegGeometry,
    WholeBodyIKSolution,
    leg_geometries,
    leg_geometry,
    leg_ik,
    pin_configuration,
    planar_leg_geometry,
    planar_leg_ik,
    trunk_yaw_rad,
    whole_body_ik,
)

__all__ = [
    "LegGeometry",
    "LegIKSolution",
    "PlanarLegGeometry",
    "WholeBodyIKSolution",
    "centroidal_map",
    "centroidal_map_dot",
    "centroidal_map_euler",
    "centroidal_map_euler_dot",
    "centroidal_pose_eq30",
    "centroidal_pose_riemann",
    "euler_coordinate_rates",
    "euler_coordinates",
    "f_j2m",
    "leg_geometries",
    "leg_geometry",
    "leg_ik",
    "pin_configuration",
    "planar_leg_geometry",
    "planar_leg_ik",
    "trunk_yaw_rad",
    "whole_body_ik",
]

# Reference trajectories f_ref / f_IK (Algorithm 1 lines 2-3 and 9).
from gaitnet_mpc.kinematics.reference import (
    CentroidalReference,
    ReferenceConfig,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    swing_profile,
    update_reference,
)

__all__ += [
    "CentroidalReference",
    "ReferenceConfig",
    "ReferenceTiming",
    "ReferenceWorkspace",
    "make_reference",
    "swing_profile",
    "update_reference",
]
