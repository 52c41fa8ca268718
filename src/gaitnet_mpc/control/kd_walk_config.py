"""Settings of ``kd`` (:class:`KDWalkConfig`), its named presets and the terrain view it
needs. The tuned values are the dataclass defaults (each says why it has its value); the
paper's settings are the shipped preset ``presets/kd-paper.toml``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import partial

from gaitnet_mpc.config import bounded, check_ranges, load_preset, preset_names
from gaitnet_mpc.control.disturbance_observer import DisturbanceObserverConfig
from gaitnet_mpc.control.lowlevel import LowLevelConfig
from gaitnet_mpc.control.terrain_view import TerrainKnowledge, TerrainView
from gaitnet_mpc.control.walking import (
    ACCEL_INTERVAL,
    ACCEL_REASON,
    DEPTH_INTERVAL,
    DEPTH_REASON,
    RETURN_INTERVAL,
    RETURN_REASON,
)
from gaitnet_mpc.dt_policy import PERIOD_INTERVAL, PERIOD_REASON, DtPolicyConfig
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait import SwingConfig
from gaitnet_mpc.gait.preview import PreviewConfig
from gaitnet_mpc.mpc.implicit_kd import KDConfig
from gaitnet_mpc.mpc.kinematic_rows import reach_geometry
from gaitnet_mpc.mpc.sequential import SequentialConfig
from gaitnet_mpc.robots.model import RobotModel
from gaitnet_mpc.terrain import Course


def walking_kd_config() -> KDConfig:
    """Sub-problem weights used for walking (deviation from Table VIII, measured).

    With ``H = [m p_c; angular pose]`` in kg m and kg m^2, Table VIII's uniform ``L^H = 200``
    and ``L^{p_c} = (100, 100, 250)`` make a 2 cm lateral CoM shift cost ~60x more than a
    0.1 rad trunk roll, so from single support the plan rolled the trunk (k_G,x up to 1.7
    kg m^2/s) instead of swaying, and the robot tipped over within 0.7 s. Weighting the
    angular pose and momentum 10x more and the linear pose and lateral CoM less keeps the
    trunk upright; the robot then steps in place and walks (see the issue notes).

    Roll and pitch take 3x that (6000): read as angles, ``w I_G^2`` with the standing
    centroidal inertia (0.64, 0.58 kg m^2), about 2500 and 2000 per rad^2. With 2000 the plan
    brakes a push by pitching the trunk (+0.58 rad before the next touchdown after 100 N
    forward) and tips on seeded stones; chosen with the low level's trunk feedback
    (``walking_low_level_config``) on tuning seeds, docs/design/trunk_attitude.md. Yaw
    stays at 2000 (18 per rad^2): the stance hip-yaw feedback holds the heading, and 110x
    more in the MPC was no better on the probe.
    """
    return KDConfig(
        w_pose=(1.0, 1.0, 1.0, 6000.0, 6000.0, 2000.0),
        w_momentum=(10.0, 10.0, 10.0, 100.0, 100.0, 100.0),
        w_p_com=(10.0, 1.0, 250.0),
        # The sub-problem checks its inputs itself; skip the QP layer's second check.
        qp_options=(("check_problem", False),),
    )


def walking_low_level_config() -> LowLevelConfig:
    """Low-level gains of ``kd`` (measured, docs/design/walking_low_level.md).

    * Swing inertial feedforward 0.75: the swing foot lands within +-0.4 cm of its aim
      instead of 3.7-5.2 cm beyond it (flat, 0.75 m/s, dt 0.045), and the biped's solves
      hitting j_max drop from 16 % to 0.1 % (flat, 0.5 m/s, 20 s).
    * Trunk-yaw feedback on the stance hip yaw (kp 10 N m/rad, kd 1 N m s/rad). With the
      feedforward alone the 20 s flat run (0.75 m/s, dt 0.045) drifted 1.85 m sideways
      and fell at 9.6 s; with both it ran the 20 s (speed RMSE 0.010 m/s). With the
      feet beside the CoM (LIP reference) sagittal forces yaw the trunk (rms 0.35 rad
      on flat without the feedback, 0.10 rad with it).
    * Trunk roll / pitch feedback on the stance hip roll / pitch (kp 20 N m/rad, kd 2 N m
      s/rad). Nothing else in the loop holds the trunk's attitude: the MPC tracks the
      centroidal momentum, whose angular part mixes the trunk's rotation with the legs',
      and the stance legs map its wrench by ``J^T``. Traced on seeded stones (kd, seed
      101): the trunk rolled to -0.23 rad over four steps before it fell. Chosen with the
      MPC's roll / pitch weight (``walking_kd_config``), docs/design/trunk_attitude.md.
    """
    return LowLevelConfig(
        swing_accel_ff=0.75,
        stance_yaw_kp_nm_per_rad=10.0,
        stance_yaw_kd_nms_per_rad=1.0,
        stance_tilt_kp_nm_per_rad=20.0,
        stance_tilt_kd_nms_per_rad=2.0,
    )


#: Time constant of the lateral return to the commanded path [s] (KDWalkConfig and
#: ``--preview``; chosen on the built-in stepping stones, docs/design/lateral_return.md).
LATERAL_RETURN_TIME_S = 0.7


#: Fields of ``sequential.kd`` the controller sets from the robot, left at their defaults
#: in a configuration (setting one would silently have no effect).
ROBOT_FIELDS = (
    "mass_kg",
    "inertia_kgm2",
    "toe_m",
    "heel_m",
    "yaw_cone_half_m",
    "min_foot_separation_m",
    "leg_reach_m",
    "hip_offset_m",
    "reach_tilt_rad",
)


@dataclass(frozen=True)
class KDWalkConfig:
    """Settings of the kino-dynamic walking controller."""

    replan_period_s: float = bounded(0.02, PERIOD_INTERVAL, "a period", PERIOD_REASON)
    # QPs at most per replan within a step (a step start always runs up to
    # ``sequential.j_max``). 1: the real-time-iteration replan (one QP from the new state,
    # benchmarks/results/replan_outcomes.md and perf.md measure what it costs and saves).
    replan_j_max: int = bounded(50, "[1, 1000]", "an integer", "1: one QP per replan")
    # A replan starts its iterations from the last plan shifted to the new horizon
    # (mpc/kd_iterate.py shift_iterate), not from the references (KDIterate.initial).
    warm_start_replans: bool = False
    # A replan whose horizon reaches past the last plan's (a stage was added at its end)
    # runs up to ``sequential.j_max`` QPs, not ``replan_j_max``: the added stage has no
    # planned values to start from. docs/design/realtime.md, item 28.
    converge_new_stages: bool = False
    # the command is ramped up from rest at this rate
    max_accel_mps2: float = bounded(1.0, ACCEL_INTERVAL, "an acceleration", ACCEL_REASON)
    sequential: SequentialConfig = field(
        default_factory=lambda: SequentialConfig(kd=walking_kd_config())
    )
    low_level: LowLevelConfig = field(default_factory=walking_low_level_config)
    # clearance_m: 2 cm above an obstacle's top for the sole, plus the 1 cm from the
    # foot point (the foot box's centre) down to the sole (SwingConfig's rule). With 2 cm
    # for the foot point the heel of a 0.3 m step clipped the built-in obstacle's far
    # corner (sole 1 cm above the top on the plan, 1 cm tracking lag along x).
    swing: SwingConfig = field(
        default_factory=lambda: SwingConfig(
            touchdown_speed_mps=0.1, foot_half_length_m=0.075, clearance_m=0.03
        )
    )
    # Eq. 24 boxes shrink by this inside each patch: the whole foot (toe and heel 0.075 m
    # from its centre) on the patch, plus 5 mm for the landing error (within +-4 mm with
    # the swing feedforward). With 0.05 the heel or toe overhung an edge and the foot
    # slid off it during stance (gap at dt 0.045 / 0.055 / 0.065: 1 violation each).
    # At most 0.09 m: a larger margin leaves no box on the shortest built-in stones (0.18 m
    # long, seeded stepping-stones; terrain/builtin_courses.py). The planar biped's point
    # foot (radius 0.02 m) takes 0.025 m by the same rule (presets/kd-default.planar.toml).
    foothold_margin_m: float = bounded(
        0.08, "[0, 0.09] m", "a margin", "under half the shortest built-in stone, 0.18 m"
    )
    # One-step preview (reach rule, below): the box's margin across the patch [m]. The
    # foot is 2 cm wide, so 0.03 m keeps it on the patch with 2 cm to spare (the multi-step
    # preview's PreviewConfig.foothold_margin_y_m is the same). With 0.08 (until 2026-12,
    # foothold_margin_m in both axes) the lateral box on a 0.22 m stone was 6 cm wide and
    # the MPC's touchdowns pressed its inner edge. Chosen with foothold_reach_m on tuning
    # seeds 100-109 (docs/design/foothold_margin.md): 0.02 / 0.03 / 0.04 / 0.05 m gave
    # 8 (with 5 violations) / 8 / 6 / 5 of 10 stone layouts clean for gaitnet.
    foothold_margin_y_m: float = bounded(
        0.03, "[0, 0.1] m", "a margin", "under half the narrowest built-in stone, 0.20 m"
    )
    # The eq. 24 box keeps this much more from a known obstacle's side than from a patch's
    # edge (terrain/landing.py): at an edge the toe may overhang by the landing error, at
    # an obstacle it would press on its side. 2 cm: the swing's clearance above a top.
    foothold_obstacle_clearance_m: float = bounded(
        0.02, "[0, 0.3] m", "a margin", "0.3 m is longer than a step"
    )
    # |x_foot - x_com| at touchdown within which the reach rule considers a patch [m].
    # 0.2 (until 2026-12) left the next stone out of reach behind a platform's edge, so the
    # robot took a zero-length step there and then a long one it could not stop from.
    # Tuning seeds 100-109, stone layouts clean for gaitnet: 1/10 with 0.2 m (0.08 m across),
    # 4/10 with 0.3 m alone; with a 0.04 m lateral margin 0.25 / 0.3 / 0.35 m gave 3 / 6 / 6.
    foothold_reach_m: float = bounded(0.3, "[0, 1] m", "a distance", "1 m is past any step")
    # ... and behind the CoM at touchdown (None: foothold_reach_m). 0.05 kept the rule from
    # re-stepping onto the stone behind (docs/design/stone_failures.md) but forced a step
    # beyond the leg's reach before the built-in gap (docs/design/trunk_attitude.md).
    foothold_reach_back_m: float | None = bounded(
        None, "[0, 1] m", "a distance", "None: the same as foothold_reach_m"
    )
    # swing targets end this far below the planned foothold
    touchdown_depth_m: float = bounded(0.003, DEPTH_INTERVAL, "a depth", DEPTH_REASON)
    # The swing foot follows each replan's touchdown until this fraction of the step; later
    # it keeps its aim, so that a last-moment change does not jerk the foot just before it
    # lands. Set when the retargeting was written, not tuned.
    retarget_until_phase: float = bounded(0.85, "(0, 1]", "a phase", "a fraction of the step")
    # The one-step preview holds the heights of the obstacles between lift-off and
    # touchdown; False: as on the paper's hardware (Fig. 1(e), "the obstacle's height is
    # unknown to the robot"). Where an obstacle stands is known either way (touchdown
    # boxes keep off it). Recorded as terrain_knowledge.obstacle_heights.
    obstacle_heights: bool = True
    # Blind (--blind, the paper's unknown terrain): the controller is told no terrain at
    # all. Footholds are planned at the stance foot's height, without eq. 24 boxes; the
    # swing aims blind_search_depth_m below that height, and its first contact in the
    # second half of the step ends it (the foot is held where it landed until its stance
    # begins). Recorded as terrain_knowledge.blind.
    blind: bool = False
    blind_search_depth_m: float = bounded(
        0.04, "[0, 0.1] m", "a depth", "0.1 m: the humanoid's shin is 0.2 m long"
    )
    # With obstacle_heights off, swings clear each obstacle as if it were this high: the
    # stated height up to which unknown obstacles are stepped over (docs/design/obstacles.md).
    unknown_obstacle_height_m: float = bounded(
        0.04, "[0, 0.2] m", "a height", "0.2 m is above the humanoid's shin"
    )
    # Toe strike (the swing foot's contact sensor turns on while the foot is over or
    # against a known obstacle footprint): the obstacle is taken as this much higher than
    # the foot stands then, or than it was taken before, whichever is higher, and the rest
    # of the swing lifts the foot over that top to the same foothold. 0: off.
    # One strike on a 10 cm box taken as 4 cm high then clears it (docs/design/obstacles.md).
    toe_strike_raise_m: float = bounded(
        0.04, "[0, 0.2] m", "a height", "0.2 m is above the humanoid's shin"
    )
    # Least height of the swing leg's shank capsule above an obstacle along the planned
    # swing; a plan that passes lower is recorded (SwingObstacles.check_shank). The
    # foot's own margin is swing.clearance_m.
    shank_clearance_m: float = bounded(0.01, "[0, 0.1] m", "a margin", "0.1 m is a shin")
    # Obstacles the swing trajectory clears: those from this far behind the lift-off to
    # this far beyond the target, along x [m] (behind, ahead); the foot is 0.15 m long.
    swing_obstacle_window_m: tuple[float, float] = bounded(
        (0.1, 0.2), "[0, 1] m", "a distance", "1 m is past any step"
    )
    # Lateral CoM reference of eq. 18: "line" = f_ref's straight command line from the
    # path start with zero lateral momentum; "lip" = the periodic LIP sway orbit of a gait
    # with feet at +-lip_half_width_m beside a centre line (control/lip_reference.py). "line"
    # plans a near-tightrope (feet 2-7 cm apart); "lip" a 0.19 m wide gait, but then the
    # feet at patch edges fail more often (docs/design/lateral_reference.md).
    lateral_reference: str = "line"
    lip_half_width_m: float = bounded(0.07, "[0, 0.3] m", "a distance", "the hips are 0.13 m apart")
    # Lowest CoM height [m] the LIP sway orbit's frequency sqrt(g / z) is computed with, a
    # guard against a reference height near 0 (the humanoid stands at 0.55 m; never active
    # in a walk measured here).
    lip_min_com_height_m: float = bounded(
        0.2, "(0, 1] m", "a height", "> 0 for sqrt(g / z); the humanoid stands at 0.55 m"
    )
    # Clamp of the orbit centre line's lateral correction toward the commanded path [m];
    # None: the centre is the commanded path itself.
    lip_anchor_max_m: float | None = bounded(None, "[0, 1] m", "a distance", "None: no clamp")
    # With the "line" reference: the CoM's lateral offset from the commanded path decays
    # along the horizon with this time constant [s] (None: the line starts at the CoM and
    # nothing pulls the robot back to its path). With the feet kept apart the robot
    # drifts sideways without it (gap, dt 0.045: 0.62 m, then a fall); the 0.7 s value was
    # chosen on the built-in stepping stones (docs/design/lateral_return.md).
    lateral_return_time_s: float | None = bounded(
        LATERAL_RETURN_TIME_S, RETURN_INTERVAL, "a time constant", RETURN_REASON
    )
    # Multi-step footstep preview (gait/preview.py): a LIP plan of the next steps chooses
    # the swing foot's patch (eq. 24 box) and the touchdown x, and gives the CoM x
    # reference of eq. 18. None: one-step preview (patch by reach).
    preview: PreviewConfig | None = None
    # Keep the feet apart (beyond the paper): a lateral-separation row per stage in the QP
    # (KDConfig.min_foot_separation_m = RobotModel.min_foot_separation_m) and swing targets
    # held on the swing foot's own side of the stance foot. False: the paper's QP.
    keep_feet_apart: bool = True
    # Keep each planned touchdown within its leg's reach of the hip (beyond the paper; row 26
    # of docs/deviations.md): reach rows in the QP (mpc/kinematic_rows.py; KDConfig.leg_reach_m,
    # hip_offset_m and reach_tilt_rad from the robot; docs/design/leg_reach.md). A planar
    # robot's 2-DoF legs get none. False: no such rows, as the paper.
    keep_feet_in_reach: bool = True
    # Fraction of the foot's toe and heel distances the MPC may move the centre of pressure
    # to (the wrench rows of mpc/contact.py; 1: the whole foot, as the paper). At the toe
    # or heel the box foot tips onto one edge, loses its yaw friction and spins (2 pivots
    # and 2 slips in 6 s of flat walking with 1.0, none with 0.6). 0.6 was chosen on
    # tuning seeds 100-109 (docs/design/cop_margin.md).
    cop_fraction: float = bounded(0.6, "(0, 1]", "a fraction", "of toe and heel; 1: the whole foot")
    # dt^0 of a step (Algorithm 1 line 3: the dt its first iteration plans with, and the
    # dt of the horizon's next step): False: the policy's nominal dt, as the paper
    # (f_ref with "a nominal sampling duration dt^0"); True: the dt the previous step
    # chose.
    carry_dt: bool = False
    # Which policy chooses each step's dt (fixed, gaitnet, oracle) and its settings; the
    # controller's name sets ``kind`` (gaitnet_mpc/dt_policy.py owns the numbers).
    dt_policy: DtPolicyConfig = field(default_factory=DtPolicyConfig)
    # The disturbance observer (control/disturbance_observer.py): its estimate of the
    # external wrench (an unknown payload, a push) enters the MPC's dynamics, eqs. 14-15,
    # as an affine term. None: off (the paper's MPC). docs/design/disturbance_observer.md.
    disturbance_observer: DisturbanceObserverConfig | None = field(
        default_factory=DisturbanceObserverConfig
    )

    def __post_init__(self) -> None:
        j = self.replan_j_max
        if isinstance(j, bool) or not isinstance(j, int):
            raise ConfigError("replan_j_max", j, "an integer")
        check_ranges(self)
        if self.lateral_reference not in ("line", "lip"):
            raise ConfigError("lateral_reference", self.lateral_reference, "'line' or 'lip'")
        kd, default = self.sequential.kd, KDConfig()
        for name in ROBOT_FIELDS:  # KDWalkController sets them from the robot
            if getattr(kd, name) != getattr(default, name):
                raise ConfigError(
                    f"sequential.kd.{name}", getattr(kd, name),
                    f"its default {getattr(default, name)}: the controller takes it from the "
                    "robot (cop_fraction scales the foot, keep_feet_apart sets the separation, "
                    "keep_feet_in_reach the reach)",
                )  # fmt: skip
        lo, hi = self.sequential.dt_bounds_s
        policy = self.dt_policy
        for name, value in (("bounds_s", policy.bounds_s), ("dt_s", policy.dt_s)):
            values = value if isinstance(value, tuple) else (value,)
            if any(v is not None and not lo <= v <= hi for v in values):
                raise ConfigError(
                    f"dt_policy.{name}", value,
                    f"within sequential.dt_bounds_s [{lo:g}, {hi:g}] s (every dt is clipped "
                    "into those)",
                )  # fmt: skip


def robot_kd_config(config: KDWalkConfig, robot: RobotModel) -> KDConfig:
    """``config.sequential.kd`` with the :data:`ROBOT_FIELDS` taken from ``robot``."""
    kd = config.sequential.kd
    if config.keep_feet_in_reach and not robot.spec.planar:
        hips, leg_m, tilt_rad = reach_geometry(robot)
        kd = replace(kd, hip_offset_m=hips, leg_reach_m=leg_m, reach_tilt_rad=tilt_rad)
    return replace(
        kd,
        mass_kg=robot.total_mass_kg,
        inertia_kgm2=robot.standing_inertia_kgm2,
        toe_m=config.cop_fraction * robot.spec.foot_toe_m,
        heel_m=config.cop_fraction * robot.spec.foot_heel_m,
        yaw_cone_half_m=0.5 * (robot.spec.foot_toe_m + robot.spec.foot_heel_m),
        min_foot_separation_m=robot.min_foot_separation_m if config.keep_feet_apart else None,
    )


def preview_walk_config(base: KDWalkConfig | None = None) -> KDWalkConfig:
    """``kd --preview``: ``base`` (default: :class:`KDWalkConfig`) with the multi-step
    footstep preview, and a lateral return to the path (0.7 s) where ``base`` has none.

    The one-foot lanes of the stepping stones need the CoM between them; without a pull
    back to the path it drifts 0.3-0.7 m over the course and a foot cannot reach the other
    lane (``benchmarks/results/kd_stones_rate.md``).
    """
    base = base or KDWalkConfig()
    tau = base.lateral_return_time_s or LATERAL_RETURN_TIME_S
    return replace(base, preview=PreviewConfig(), lateral_return_time_s=tau)


def paper_walk_config(planar: bool = False) -> KDWalkConfig:
    """``kd --preset paper``: the paper's numbers (Table VIII, or for a planar robot Table V
    from ``kd-paper.planar.toml``; Table X) read as ``docs/design/paper_weights.md``
    derives, over the default's robot-level rows and low level; ``presets/kd-paper.toml``
    lists them."""
    return load_preset(KDWalkConfig, "kd", "paper", planar)


#: Named presets of ``kd`` (``gaitnet-mpc run --controller kd --preset NAME``): the files
#: ``presets/kd-NAME.toml`` (the tuned default, the paper's settings), each a function of
#: ``planar`` (the robot).
KD_PRESETS = {name: partial(load_preset, KDWalkConfig, "kd", name) for name in preset_names("kd")}


def walk_terrain(course: Course, config: KDWalkConfig) -> TerrainView:
    """The terrain view ``config`` needs: the one-step preview, or with ``config.preview``
    the multi-step one."""
    knowledge = TerrainKnowledge(
        multi_step=config.preview is not None,
        obstacle_heights=config.obstacle_heights,
        blind=config.blind,
    )
    return TerrainView(course, knowledge)
