"""Kinematics for the kino-dynamic MPC: analytic leg IK (paper Appendix B), the centroidal
momentum map / centroidal pose (eqs. 6, 11, 12 and Appendix A), and the reference
trajectories ``f_ref`` / ``f_IK`` (Algorithm 1 lines 2-3 and 9) with their foot plan."""

from gaitnet_mpc.kinematics.centroidal import (
    centroidal_map,
    centroidal_map_dot,
    centroidal_map_euler,
    centroidal_pose_eq30,
    centroidal_pose_riemann,
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
    planar_leg_geometry,
    planar_leg_ik,
    whole_body_ik,
)
from gaitnet_mpc.kinematics.reference import (
    CentroidalReference,
    ReferenceConfig,
    ReferenceTiming,
    ReferenceWorkspace,
    make_reference,
    update_reference,
)

__all__ = [
    "CentroidalReference",
    "LegGeometry",
    "LegIKSolution",
    "PlanarLegGeometry",
    "ReferenceConfig",
    "ReferenceTiming",
    "ReferenceWorkspace",
    "WholeBodyIKSolution",
    "centroidal_map",
    "centroidal_map_dot",
    "centroidal_map_euler",
    "centroidal_pose_eq30",
    "centroidal_pose_riemann",
    "euler_coordinates",
    "f_j2m",
    "leg_geometries",
    "leg_geometry",
    "leg_ik",
    "make_reference",
    "planar_leg_geometry",
    "planar_leg_ik",
    "update_reference",
    "whole_body_ik",
]
