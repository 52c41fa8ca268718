"""Build the dt policy of a kino-dynamic controller from its settings
(:class:`~gaitnet_mpc.dt_policy.DtPolicyConfig`): a fixed dt, Gait-Net, the grid-search
oracle or the dt of an NLP (``kd-optdt``), all behind
:class:`~gaitnet_mpc.mpc.sequential.DtPolicy`; and :class:`ExternalDt`, the dt a caller
sets before each step start (no setting names it: it is handed to the controller,
``build_episode(..., dt_policy=...)``)."""

from __future__ import annotations

import math
from pathlib import Path

from gaitnet_mpc.dataset.protocol import STAGES_PER_STEP
from gaitnet_mpc.dt_policy import (
    ACCEPTED_DT_RANGE_S,
    NOMINAL_DT_S,
    DtPolicyConfig,
    oracle_grid_s,
)
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.step_durations import StepDurations
from gaitnet_mpc.gaitnet import WEIGHTS_DIR, WEIGHTS_FILE, GaitNet, default_weights_path
from gaitnet_mpc.gaitnet.policy import GaitNetDt
from gaitnet_mpc.mpc.dt_nlp import NLPDt, NLPDtConfig
from gaitnet_mpc.mpc.dt_oracle import OracleConfig, OracleDt
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.mpc.sequential import (
    DtPolicy,
    FixedDt,
    KDProblem,
    ScheduledDt,
    SequentialConfig,
    SequentialKDMPC,
)
from gaitnet_mpc.robots import RobotModel


def shipped_weights() -> list[str]:
    """Names of the Gait-Net weights shipped with the package (``humanoid3d-wbmpc``, ...)."""
    return sorted(p.stem for p in WEIGHTS_DIR.glob("*.npz"))


def weights_path(robot: RobotModel, weights: str | Path | None) -> Path:
    """The file of ``weights``: a shipped name, a weights file, a model folder of
    ``gaitnet-mpc train --out DIR`` (its :data:`WEIGHTS_FILE`), or None for the robot's
    default.

    Raises:
        ConfigError: a folder without :data:`WEIGHTS_FILE` (naming what it holds).
    """
    if weights is None:
        return default_weights_path(robot.name)
    if str(weights) in shipped_weights():
        return WEIGHTS_DIR / f"{weights}.npz"
    path = Path(weights)
    if path.is_dir():
        if (path / WEIGHTS_FILE).is_file():
            return path / WEIGHTS_FILE
        names = sorted(p.name for p in path.iterdir())
        held = f"it holds {', '.join(names[:4])}{', ...' if len(names) > 4 else ''}"
        raise ConfigError(
            "--gaitnet-weights",
            str(weights),
            f"a model folder of `gaitnet-mpc train --out DIR`, with {WEIGHTS_FILE} in it "
            f"({f'{held}, no {WEIGHTS_FILE}' if names else 'it is empty'})",
        )
    return path


def load_gaitnet(robot: RobotModel, weights: str | Path | None) -> GaitNet:
    """The network of ``weights`` (see :func:`weights_path`), checked to be ``robot``'s;
    a :class:`ConfigError` names ``--gaitnet-weights``."""
    path = weights_path(robot, weights)
    if not path.is_file():
        raise ConfigError(
            "--gaitnet-weights",
            str(weights if weights is not None else path),
            f"a shipped name ({', '.join(shipped_weights())}), a weights file or the model "
            "folder DIR of `gaitnet-mpc train --out DIR`",
        )
    try:
        net = GaitNet.load(path)
    except ConfigError as exc:  # GaitNetWeights.load's, under this option's name
        if exc.field == "Gait-Net weights":
            raise ConfigError("--gaitnet-weights", exc.value, exc.expected) from None
        if exc.field == str(path):  # an entry missing
            expected = f"{exc.expected} ({exc.value})"
            raise ConfigError("--gaitnet-weights", str(path), expected) from None
        raise ConfigError(f"--gaitnet-weights {exc.field}", exc.value, exc.expected) from None
    if net.spec.robot and net.spec.robot != robot.name:
        raise ConfigError("--gaitnet-weights", str(path), f"weights for {robot.name}")
    return net


def make_dt_policy(
    config: DtPolicyConfig, robot: RobotModel, sequential: SequentialConfig
) -> DtPolicy:
    """The policy ``config`` names, for ``robot``; the oracle searches with its own
    solver of the ``sequential`` settings (so its grid solves leave the controller's
    workspaces alone)."""
    planar = robot.spec.planar
    if config.kind == "fixed":
        return FixedDt(config.dt_s if config.dt_s is not None else NOMINAL_DT_S)
    if config.kind == "drawn":
        durations = StepDurations(
            duration_range_s=config.drawn_step_range_s,
            stages_per_step=STAGES_PER_STEP,
            seed=config.drawn_seed,
        )
        return ScheduledDt(durations)
    if config.kind == "gaitnet":
        return GaitNetDt(
            load_gaitnet(robot, config.gaitnet_weights),
            planar,
            config.gaitnet,
            bounds_s=config.bounds_for(planar),
            nominal_dt_s=config.dt_s if config.dt_s is not None else NOMINAL_DT_S,
        )
    if config.kind == "optdt":
        nlp = NLPDt(
            NLPDtConfig(
                bounds_s=config.bounds_for(planar),
                nominal_dt_s=config.dt_s if config.dt_s is not None else NOMINAL_DT_S,
            )
        )
        nlp.attach(SequentialKDMPC(robot, sequential))
        return nlp
    grid = oracle_grid_s(config.bounds_for(planar), config.oracle_grid_step_s)
    oracle = OracleDt(
        OracleConfig(dts_s=grid, nominal_dt_s=grid[0] if config.dt_s is None else config.dt_s)
    )
    oracle.attach(SequentialKDMPC(robot, sequential))
    return oracle


class ExternalDt:
    """The dt of each step set from outside: :attr:`dt_s` as the caller last set it, read
    by every iteration of the step-start solve (Algorithm 1, line 8) as a fixed dt would
    be. A caller that decides step by step (the Gymnasium environment's action,
    :mod:`gaitnet_mpc.envs.gym_env`) sets it before the tick that starts the step; the
    steps' dts it set are kept in :attr:`history_s`.

    Args:
        nominal_dt_s: ``dt^0`` of the first step and the value of :attr:`dt_s` until it
            is set [s].
    """

    def __init__(self, nominal_dt_s: float = NOMINAL_DT_S) -> None:
        self._nominal_dt_s = self._checked(nominal_dt_s, "nominal_dt_s")
        self._dt_s = self._nominal_dt_s
        self.history_s: list[float] = []

    @staticmethod
    def _checked(dt_s: float, name: str) -> float:
        lo, hi = ACCEPTED_DT_RANGE_S
        value = float(dt_s)
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ConfigError(name, dt_s, f"a sampling time in [{lo}, {hi}] s")
        return value

    @property
    def nominal_dt_s(self) -> float:
        return self._nominal_dt_s

    @property
    def dt_s(self) -> float:
        """The dt [s] the next step start takes."""
        return self._dt_s

    @dt_s.setter
    def dt_s(self, value: float) -> None:
        self._dt_s = self._checked(value, "dt_s")
        self.history_s.append(self._dt_s)

    def __call__(self, problem: KDProblem, iterate: KDIterate, dt_s: float) -> float:
        return self._dt_s
