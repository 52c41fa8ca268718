"""One run, described once: :class:`Scenario` (``scenario/model.py``), and the one function
that runs it, :func:`run_scenario` (``scenario/run.py``).

A scenario is a frozen, typed description of an episode: the robot, the course and its
layout seed, the controller with its full settings (for the kino-dynamic controllers the
dt policy too, ``KDWalkConfig.dt_policy``), the velocity command, the disturbances (pushes,
an unknown payload) and the duration. It is made from Python (:func:`make_scenario`),
from CLI arguments (``gaitnet-mpc run``, which calls :func:`make_scenario`), or from a TOML
file (:meth:`Scenario.from_toml`); :func:`run_scenario` writes it into the run folder as
``scenario.toml``, and ``gaitnet-mpc run --scenario runs/x/scenario.toml`` replays run
``x``: the simulation is deterministic, so the replay's ``summary.json`` is identical
(wall-clock figures live in ``timing.json``).

Every command that simulates builds its episodes here (:func:`build_episode`), so a
benchmark, a data-collection set and ``gaitnet-mpc run`` with the same scenario run the
same thing. :class:`EpisodeStepper` (``scenario/stepper.py``) runs the same loop in
pieces (ticks or footsteps) for a caller that looks at the robot between them
(``examples/step_loop.py``; the Gymnasium environment ``gaitnet_mpc.envs.gym_env``).

TOML layout of ``scenario.toml``::

    robot = "humanoid3d"
    controller = "gaitnet"
    course = "stepping-stones"   # a built-in name, or a course JSON file
    course_seed = 3              # "none": the built-in layout
    duration_s = 8.0
    payload_kg = 0.0
    [cart]                       # optional: a cart the hands push (Fig. 10), see sim.cart
    [command]                    # vx_mps, vy_mps, yaw_rate_radps
    [[pushes]]                   # t_s, force_world_n = [fx, fy, fz], duration_s
    [origin]                     # how the settings were made (preset, --set, ...): a record
    [config]                     # the controller's full settings (see gaitnet_mpc.config)
"""

from gaitnet_mpc.scenario.model import (
    MAX_DURATION_S,
    MIN_DURATION_S,
    Episode,
    Scenario,
    build_episode,
    load_scenario_course,
    make_scenario,
    scenario_meta,
    scenario_warnings,
)
from gaitnet_mpc.scenario.run import (
    CONFIG_FILE,
    SCENARIO_FILE,
    run_scenario,
    simulate_episode,
    write_scenario_files,
)
from gaitnet_mpc.scenario.stepper import EpisodeOverError, EpisodeStepper, StepResult

__all__ = [
    "CONFIG_FILE",
    "MAX_DURATION_S",
    "MIN_DURATION_S",
    "SCENARIO_FILE",
    "Episode",
    "EpisodeOverError",
    "EpisodeStepper",
    "Scenario",
    "StepResult",
    "build_episode",
    "load_scenario_course",
    "make_scenario",
    "run_scenario",
    "scenario_meta",
    "scenario_warnings",
    "simulate_episode",
    "write_scenario_files",
]
