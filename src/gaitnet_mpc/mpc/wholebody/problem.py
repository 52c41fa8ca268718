"""Whole-body NMPC problem data (Sec. III-A, eqs. 1-3; weights and limits of Table VI).

A :class:`WBProblem` holds everything that changes from one MPC call to the next: the
measured state, the contact schedule, the per-stage sampling times and the reference.
:class:`WBConfig` holds what does not: horizon, weights, friction and force limits.

Contact schedule: the gait is periodic with a step every ``h' = stages_per_step`` stages
(h = 2 h'); every stage of one step uses that step's ``dt`` (Sec. III-A: variable-frequency
walking adjusts ``dt_k`` per step). Walking is alternating single support; standing is
double support on every stage.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gaitnet_mpc.command import Command
from gaitnet_mpc.config import bounded, check_ranges, weight
from gaitnet_mpc.dt_policy import ACCEPTED_DT_INTERVAL, ACCEPTED_DT_REASON
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.robots.spec import FEET

_MU = "> 0 to walk; 2 is past rubber on concrete (about 1)"
_FZ_MAX = "2000 N is 13 times the 16 kg humanoid's weight"


@dataclass(frozen=True)
class WBWeights:
    """Diagonal weights of eq. (2), Table VI (humanoid; the planar biped keeps x, z, pitch).

    Base pose order ``[x, y, z, roll, pitch, yaw]``; base rate order ``[vx, vy, vz,
    omega_x, omega_y, omega_z]``.
    """

    q_base: tuple[float, ...] = weight((100.0, 100.0, 100.0, 150.0, 150.0, 250.0))  # Q1^{q_fb}
    q_joint: float = weight(50.0)  # Q1^{q_f,i}, every joint
    tau_joint: float = weight(1e-3)  # Q2
    force: float = weight(1e-4)  # Q3^f, per force component
    moment: float = weight(1e-3)  # Q3^tau, per foot moment component
    v_base: tuple[float, ...] = weight((1.0, 1.0, 1.0, 1.0, 1.0, 5.0))  # Q4^{q_fb}
    v_joint: float = weight(1.0)  # Q4^{q_f,i}
    # The last node's state cost is scaled by this (beyond Table VI, which has no terminal
    # weight): without it the plan lets the robot sink and fall back at the horizon end,
    # where a fall costs little.
    terminal_scale: float = bounded(1.0, "[0, 1000]", "a scale", "wbmpc runs with 10")

    def __post_init__(self) -> None:
        check_ranges(self)
        for name in ("q_base", "v_base"):
            value = getattr(self, name)
            if len(value) != 6:
                raise ConfigError(name, value, "6 weights, one per base coordinate")


@dataclass(frozen=True)
class WBConfig:
    """Fixed settings of the whole-body NMPC (Table VI)."""

    horizon_stages: int = bounded(10, "[1, 100]", "an integer", "stages; h = 10 in Table VI")
    stages_per_step: int = bounded(5, "[1, 20]", "an integer", "stages of a step; h' = 5")
    friction_coef: float = bounded(0.7, "(0, 2]", "a friction coefficient", _MU)  # mu
    # minimum and maximum normal force of a stance foot [N]
    f_min_n: float = bounded(10.0, "[0, 2000] N", "a normal force", "a foot cannot pull")
    f_max_n: float = bounded(500.0, "(0, 2000] N", "a normal force", _FZ_MAX)
    # Not in Table VI: apex of the swing-foot height lower bound [m] (3c, clearance).
    swing_clearance_m: float = bounded(
        0.04, "[0, 0.3] m", "a height", "0.3 m is above the humanoid's knee, 0.22 m high"
    )
    # Accepted per-step sampling times [s]; Table VI uses 0.045-0.07 s.
    dt_min_s: float = bounded(0.03, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON)
    dt_max_s: float = bounded(0.08, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON)
    weights: WBWeights = field(default_factory=WBWeights)

    def __post_init__(self) -> None:
        check_ranges(self)
        if not self.f_min_n < self.f_max_n:
            raise ConfigError("f_min_n/f_max_n", (self.f_min_n, self.f_max_n), "0 <= min < max")
        if not self.dt_min_s <= self.dt_max_s:
            raise ConfigError("dt_min_s/dt_max_s", (self.dt_min_s, self.dt_max_s), "0 < min <= max")


@dataclass(frozen=True)
class WBProblem:
    """One NMPC instance: state x_0, schedule, sampling times, reference (eqs. 1-3).

    Attributes:
        qpos0, qvel0: measured MuJoCo state (nq,), (nv,).
        stance: (h, 2) bool, foot ``FEET[i]`` in contact during stage k.
        dt_stage_s: (h,) sampling time of each stage [s].
        qpos_ref: (h, nq) reference configuration of nodes 1..h.
        qvel_ref: (h, nv) reference velocity of nodes 1..h.
        swing_height_min_m: (h,) lower bound on the swing-foot height above the ground
            at node k+1 for a foot in swing during stage k [m].
        ground_z_m: ground height [m].
    """

    qpos0: np.ndarray
    qvel0: np.ndarray
    stance: np.ndarray
    dt_stage_s: np.ndarray
    qpos_ref: np.ndarray
    qvel_ref: np.ndarray
    swing_height_min_m: np.ndarray
    ground_z_m: float = 0.0

    @property
    def horizon_stages(self) -> int:
        return int(self.stance.shape[0])

    @property
    def schedule_key(self) -> tuple[tuple[bool, ...], ...]:
        """Hashable contact schedule; one transcription is built and cached per key."""
        return tuple(tuple(bool(s) for s in row) for row in self.stance)

    def validate(self, nq: int, nv: int) -> None:
        """Check shapes and values against a model with ``nq``/``nv`` coordinates."""
        h = self.horizon_stages
        expected = {
            "qpos0": (nq,),
            "qvel0": (nv,),
            "stance": (h, len(FEET)),
            "dt_stage_s": (h,),
            "qpos_ref": (h, nq),
            "qvel_ref": (h, nv),
            "swing_height_min_m": (h,),
        }
        for name, shape in expected.items():
            got = np.shape(getattr(self, name))
            if got != shape:
                raise ConfigError(f"WBProblem.{name}", f"shape {got}", f"shape {shape}")
            if not np.all(np.isfinite(np.asarray(getattr(self, name), dtype=float))):
                raise ConfigError(f"WBProblem.{name}", "non-finite values", "finite values")
        if np.any(np.asarray(self.dt_stage_s) <= 0.0):
            raise ConfigError("WBProblem.dt_stage_s", self.dt_stage_s, "positive times [s]")


def contact_schedule(config: WBConfig, phase_stage: int, stance_foot: str) -> np.ndarray:
    """(h, 2) stance flags of alternating single support.

    ``stance_foot`` is in stance for the remaining ``h' - phase_stage`` stages of the
    current step, then the feet swap every ``h'`` stages.
    """
    hp = config.stages_per_step
    if not 0 <= phase_stage < hp:
        raise ConfigError("phase_stage", phase_stage, f"an integer in [0, {hp})")
    if stance_foot not in FEET:
        raise ConfigError("stance_foot", stance_foot, f"one of {FEET}")
    first = FEET.index(stance_foot)
    out = np.zeros((config.horizon_stages, len(FEET)), dtype=bool)
    for k in range(config.horizon_stages):
        step = (k + phase_stage) // hp
        out[k, (first + step) % 2] = True
    return out


def stage_dt(config: WBConfig, phase_stage: int, step_dt_s: Sequence[float]) -> np.ndarray:
    """(h,) sampling time of each stage from the per-step times (current step first).

    Stages of the same step share one ``dt``; the last given value repeats if the horizon
    reaches further steps.
    """
    if len(step_dt_s) == 0:
        raise ConfigError("step_dt_s", step_dt_s, "at least one step time [s]")
    for dt in step_dt_s:
        if not config.dt_min_s <= dt <= config.dt_max_s:
            raise ConfigError(
                "step_dt_s", dt, f"a time in [{config.dt_min_s}, {config.dt_max_s}] s"
            )
    hp = config.stages_per_step
    steps = [(k + phase_stage) // hp for k in range(config.horizon_stages)]
    return np.array([step_dt_s[min(s, len(step_dt_s) - 1)] for s in steps], dtype=float)


def swing_height_profile(config: WBConfig, phase_stage: int) -> np.ndarray:
    """(h,) swing-foot height lower bound at node k+1: ``clearance sin(pi s)``, where
    ``s = (j + 1) / h'`` is the fraction of the swing elapsed at that node and j the
    stage's index inside its step: zero at the touchdown node (s = 1), where the
    transcription puts the foot on the ground (:mod:`.nlp`)."""
    hp = config.stages_per_step
    j = (np.arange(config.horizon_stages) + phase_stage) % hp
    return config.swing_clearance_m * np.sin(np.pi * (j + 1) / hp)


def reference_trajectory(
    qpos0: np.ndarray,
    nominal_qpos: np.ndarray,
    dt_stage_s: np.ndarray,
    command: Command,
    planar: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """(qpos_ref (h, nq), qvel_ref (h, nv)): the nominal posture carried at the command.

    The base starts at the measured horizontal position and heading, keeps the nominal
    height, zero roll and pitch, moves at ``(vx, vy)`` in the heading frame and turns at
    the yaw rate; joints keep the nominal posture.
    """
    t_s = np.cumsum(dt_stage_s)
    h = len(t_s)
    qpos_ref = np.tile(np.asarray(nominal_qpos, dtype=float), (h, 1))
    if planar:
        qpos_ref[:, 0] = qpos0[0] + command.vx_mps * t_s
        qvel_ref = np.zeros((h, len(nominal_qpos)))
        qvel_ref[:, 0] = command.vx_mps
        return qpos_ref, qvel_ref
    w, x, y, z = qpos0[3:7]
    yaw0 = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    yaw = yaw0 + command.yaw_rate_radps * t_s
    # Position: integrate the heading-frame velocity along the turning heading.
    t_prev = np.concatenate([[0.0], t_s[:-1]])
    yaw_mid = yaw0 + command.yaw_rate_radps * 0.5 * (t_prev + t_s)
    dx = (command.vx_mps * np.cos(yaw_mid) - command.vy_mps * np.sin(yaw_mid)) * dt_stage_s
    dy = (command.vx_mps * np.sin(yaw_mid) + command.vy_mps * np.cos(yaw_mid)) * dt_stage_s
    qpos_ref[:, 0] = qpos0[0] + np.cumsum(dx)
    qpos_ref[:, 1] = qpos0[1] + np.cumsum(dy)
    qpos_ref[:, 3:7] = np.column_stack([np.cos(yaw / 2), np.zeros(h), np.zeros(h), np.sin(yaw / 2)])
    qvel_ref = np.zeros((h, len(nominal_qpos) - 1))
    qvel_ref[:, 0] = command.vx_mps * np.cos(yaw) - command.vy_mps * np.sin(yaw)
    qvel_ref[:, 1] = command.vx_mps * np.sin(yaw) + command.vy_mps * np.cos(yaw)
    qvel_ref[:, 5] = command.yaw_rate_radps
    return qpos_ref, qvel_ref


def make_problem(
    config: WBConfig,
    qpos0: np.ndarray,
    qvel0: np.ndarray,
    nominal_qpos: np.ndarray,
    command: Command,
    planar: bool,
    step_dt_s: Sequence[float] = (0.05,),
    phase_stage: int = 0,
    stance_foot: str | None = None,
    ground_z_m: float = 0.0,
) -> WBProblem:
    """A standing (``stance_foot=None``: double support) or walking problem.

    ``nominal_qpos`` is the standing configuration (e.g. ``RobotModel.standing_qpos()``);
    its base height is the reference height.
    """
    dt = stage_dt(config, phase_stage, step_dt_s)
    if stance_foot is None:
        stance = np.ones((config.horizon_stages, len(FEET)), dtype=bool)
        swing_min = np.zeros(config.horizon_stages)
    else:
        stance = contact_schedule(config, phase_stage, stance_foot)
        swing_min = swing_height_profile(config, phase_stage)
    qpos_ref, qvel_ref = reference_trajectory(qpos0, nominal_qpos, dt, command, planar)
    return WBProblem(
        qpos0=np.asarray(qpos0, dtype=float),
        qvel0=np.asarray(qvel0, dtype=float),
        stance=stance,
        dt_stage_s=dt,
        qpos_ref=qpos_ref,
        qvel_ref=qvel_ref,
        swing_height_min_m=swing_min,
        ground_z_m=ground_z_m,
    )
