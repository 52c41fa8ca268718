"""The one owner of the MPC sampling time ``dt``: nominal value, per-robot bounds, the
clip, the oracle grid, and the typed settings of every dt policy.

A step of the gait lasts ``h' = 5`` MPC stages, so a step lasts ``5 dt`` (paper Sec.
IV-B). A *dt policy* chooses each step's ``dt`` at the step start, inside the sequential
iterations (Algorithm 1, line 8). The policies (built by
:func:`gaitnet_mpc.control.dt_policies.make_dt_policy`, all behind the
:class:`~gaitnet_mpc.mpc.sequential.DtPolicy` interface):

* ``fixed``: the same dt for every step (the paper's baseline 1, Fig. 6a);
* ``gaitnet``: Gait-Net's dt from the step-start state and the iterate's touchdown, with
  the safeguards of :class:`GaitNetPolicyConfig`;
* ``oracle``: a grid search that solves the step once per dt of :func:`oracle_grid_s` and
  keeps the converged plan of lowest eq. 18 cost;
* ``drawn``: each step's duration drawn at random, blind to the state: the ``kd`` teacher
  of data collection (Sec. IV-A-1).

:class:`DtPolicyConfig` is part of a kino-dynamic controller's settings
(``KDWalkConfig.dt_policy``), so a run's ``config.toml`` and ``scenario.toml`` hold it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from gaitnet_mpc.config import SEED_INTERVAL, SEED_REASON, bounded, check_ranges
from gaitnet_mpc.errors import ConfigError

#: The paper's nominal sampling time ``dt^0`` [s]: a 0.225 s step (Table VIII).
NOMINAL_DT_S = 0.045

#: The range of a dt any controller accepts [s]: the gait schedule's clip and the check
#: of ``gaitnet-mpc run --dt``. 0.03 s is Table V's lower bound (the biped); 0.2 s (a 1 s
#: step) is past any walking gait of these robots.
ACCEPTED_DT_RANGE_S = (0.03, 0.2)

#: The control tick [s]: the simulator steps the physics and calls the controller at 1 kHz
#: (``SimConfig.timestep_s``, the robots' MJCF ``timestep``), so no period of a controller
#: can be shorter.
CONTROL_TICK_S = 1e-3
#: The declared range of a controller's period (:func:`~gaitnet_mpc.config.bounded`).
PERIOD_INTERVAL = f"[{CONTROL_TICK_S}, 1] s"
PERIOD_REASON = "at least one 1 kHz control tick; 1 s is several steps"

#: :data:`ACCEPTED_DT_RANGE_S` as the declared range of a dt field
#: (:func:`~gaitnet_mpc.config.bounded`), with its reason.
ACCEPTED_DT_INTERVAL = f"[{ACCEPTED_DT_RANGE_S[0]}, {ACCEPTED_DT_RANGE_S[1]}] s"
ACCEPTED_DT_REASON = "Table V's lowest dt; 0.2 s is a 1 s step"
#: The duration of a step of h' = 5 stages of an accepted dt.
_STEP_INTERVAL = f"[{5 * ACCEPTED_DT_RANGE_S[0]:g}, {5 * ACCEPTED_DT_RANGE_S[1]:g}] s"

#: The paper's bounds of a chosen dt [s], by robot kind (``RobotSpec.planar``): the
#: humanoid's [0.045, 0.07] s (Sec. V-E1, Fig. 9) and the planar biped's [0.03, 0.06] s
#: (Table V).
PAPER_DT_BOUNDS_S: dict[bool, tuple[float, float]] = {False: (0.045, 0.07), True: (0.03, 0.06)}

#: Spacing of the oracle's grid over the bounds [s].
ORACLE_GRID_STEP_S = 0.005

#: The dt policies, by the name :class:`DtPolicyConfig` ``kind`` takes.
DT_POLICIES = ("fixed", "gaitnet", "oracle", "optdt", "drawn")
#: The controller that runs each policy (``drawn``: ``kd`` as the data-collection teacher).
CONTROLLER_OF_POLICY = {
    "fixed": "kd",
    "drawn": "kd",
    "gaitnet": "gaitnet",
    "oracle": "oracle",
    "optdt": "kd-optdt",
}


def paper_dt_bounds_s(planar: bool) -> tuple[float, float]:
    """The paper's (min, max) dt [s] of a planar (Table V) or 3-D (Sec. V-E1) robot."""
    return PAPER_DT_BOUNDS_S[bool(planar)]


def clip_dt(dt_s: float, bounds_s: tuple[float, float]) -> float:
    """``dt_s`` clipped into ``bounds_s`` = (min, max) [s]."""
    lo, hi = bounds_s
    return min(max(dt_s, lo), hi)


def oracle_grid_s(
    bounds_s: tuple[float, float], step_s: float = ORACLE_GRID_STEP_S
) -> tuple[float, ...]:
    """The dts [s] the oracle tries: ``bounds_s`` in steps of ``step_s``, both ends in."""
    lo, hi = bounds_s
    n = round((hi - lo) / step_s) + 1
    return tuple(float(round(lo + i * (hi - lo) / max(n - 1, 1), 6)) for i in range(n))


@dataclass(frozen=True)
class StepRetimingConfig:
    """Settings of the capture-point re-timing of the step under way
    (:mod:`~gaitnet_mpc.control.step_retiming`, beyond the paper's Remark 4)."""

    # The shortest dt a re-timed step takes [s]: 5 x 0.03 = 0.15 s, the lower end of the
    # dts this project accepts (ACCEPTED_DT_RANGE_S). Set, not tuned.
    min_dt_s: float = bounded(
        ACCEPTED_DT_RANGE_S[0], ACCEPTED_DT_INTERVAL, "a sampling time", "the accepted dts"
    )
    # The candidate dts' spacing [s].
    grid_dt_s: float = bounded(0.0025, "(0, 0.01] s", "a spacing", "a tenth of the dt range")
    # The least swing time left after a re-timing [s]: the foot still has to reach its
    # foothold (0.1 m in 0.04 s is 2.5 m/s). Set, not tuned.
    min_remaining_s: float = bounded(0.04, "(0, 0.2] s", "a duration", "a fifth of a step")
    # Where no end is in reach and the foothold lies beyond the stance foot, across from
    # the swing leg (the swing foot would have to cross under the body), end the step as
    # early as allowed: the other foot catches next. False: keep the step there too.
    shortest_when_crossing: bool = True
    # A swing foot that lands in the second half of its step, carrying at least half the
    # robot's weight, on a patch it may use, ends the step at the next tick: the foot
    # becomes the MPC's stance foot where it landed, instead of being driven on along the
    # rest of its swing into the ground (which launched the robot:
    # docs/design/step_retiming.md; benchmarks/results/landing_and_box/).
    end_at_touchdown: bool = True

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class GaitNetPolicyConfig:
    """Safeguards of the Gait-Net dt policy (:class:`~gaitnet_mpc.gaitnet.policy.GaitNetDt`;
    paper Sec. VI names the failure they guard against: dts that do not settle).

    Attributes:
        max_spread_s: ensemble spread [s] above which the input counts as unknown.
        cycle_tolerance_s: dt changes smaller than this are not counted as a cycle [s].
        max_damped: damped iterations before a cycling solve falls back.
        safeguards: False: none of them (the network's clipped dt at every iteration,
            Algorithm 1 as printed; the ``paper`` preset).
        max_retimes: dt changes per step start before the dt is frozen; None: no limit
            (Algorithm 1 as printed). 2 on tuning gaps: 10/10 without a fall, against
            6/10 without a limit and 9/10 with 1 (gaitnet_runs_tuning.md).
        mirror_symmetric: each member's dt is the mean of its dts of the step start and
            of its left-right mirror image, so that mirror-image step starts get the same
            dt (docs/design/gaitnet_symmetry.md).
        retime_steps: at each replan within a step, a capture-point rule may shorten the
            rest of the step (beyond the paper's Remark 4; docs/design/step_retiming.md).
            Only ``gaitnet`` re-times: a fixed frequency keeps its timing. None: a step
            keeps the dt chosen at its start (the ``paper`` preset).
    """

    max_spread_s: float = bounded(0.006, "(0, 0.2] s", "a spread", "0.2 s spans every dt")
    cycle_tolerance_s: float = bounded(
        5e-4, "(0, 0.02] s", "a dt change", "20 ms is most of the paper's 0.045-0.07 s bounds"
    )
    max_damped: int = bounded(3, "[0, 100]", "an integer", "100 is twice Table X's j_max")
    safeguards: bool = True
    max_retimes: int | None = bounded(2, "[1, 100]", "an integer", "None: no limit")
    mirror_symmetric: bool = False
    retime_steps: StepRetimingConfig | None = field(default_factory=StepRetimingConfig)

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class DtPolicyConfig:
    """Which policy chooses each step's dt, and its settings.

    Attributes:
        kind: one of :data:`DT_POLICIES`; set by the controller's name (``kd``: fixed,
            or drawn for data collection; ``gaitnet``; ``oracle``; ``kd-optdt``: optdt, the
            dt a decision variable of an NLP, :mod:`~gaitnet_mpc.mpc.dt_nlp`).
        dt_s: fixed: every step's dt [s]; gaitnet, oracle and optdt: ``dt^0``, the dt of the
            first step before any decision and their fallback. None: :data:`NOMINAL_DT_S`,
            for the oracle the lower end of its grid.
        bounds_s: gaitnet, oracle and optdt: (min, max) of a chosen dt [s]; None: the paper's
            bounds of the robot (:data:`PAPER_DT_BOUNDS_S`).
        gaitnet_weights: gaitnet: the network, a shipped name (``humanoid3d-wbmpc``) or a
            path to a ``.npz`` of ``gaitnet-mpc train``; None: the default for the robot.
        gaitnet: gaitnet: the safeguards.
        oracle_grid_step_s: oracle: spacing of the grid over the bounds [s].
        drawn_step_range_s: drawn: (min, max) of a step's duration [s] (5 stages).
        drawn_seed: drawn: seed of the draws (one draw per step index).
    """

    kind: str = "fixed"
    dt_s: float | None = bounded(None, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON)
    bounds_s: tuple[float, float] | None = bounded(
        None, ACCEPTED_DT_INTERVAL, "a sampling time", ACCEPTED_DT_REASON, ordered=True
    )
    gaitnet_weights: str | None = None
    gaitnet: GaitNetPolicyConfig = field(default_factory=GaitNetPolicyConfig)
    oracle_grid_step_s: float = bounded(
        ORACLE_GRID_STEP_S, "[0.001, 0.1] s", "a grid step", "a solve per dt; 1 ms: 26 a step"
    )
    drawn_step_range_s: tuple[float, float] = bounded(
        (0.15, 0.40), _STEP_INTERVAL, "a step duration", "5 stages of a dt in [0.03, 0.2] s", True
    )
    drawn_seed: int = bounded(0, SEED_INTERVAL, "a seed", SEED_REASON)

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.kind not in DT_POLICIES:
            raise ConfigError("kind", self.kind, f"one of {', '.join(DT_POLICIES)}")

    def bounds_for(self, planar: bool) -> tuple[float, float]:
        """The (min, max) dt [s] of a chosen dt on a planar or 3-D robot."""
        return self.bounds_s if self.bounds_s is not None else paper_dt_bounds_s(planar)
