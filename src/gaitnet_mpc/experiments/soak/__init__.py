"""Soak test: many random short episodes, looking for crashes rather than for good walking.

Each episode is drawn from ``(--seed, episode index)`` alone, so episode K of a seed is
the same whatever ``--episodes`` or ``--workers`` were: a controller (weights favour the
cheap ones), a robot, a course (seeded courses mostly with a random layout), a velocity
command in the allowed range, 0-3 random pushes, a payload (half the episodes) and a
duration of 1-5 s (``--profile long``: 20 s on seeded stones, gaps or uneven tiles, with
1-3 pushes). It runs through the library path of ``gaitnet-mpc run`` (no output folder, no
video) on a spawn process pool or on Ray (``--backend ray``).

Per episode it records: any exception (type, message, where; caught in the worker),
non-finite torques, a diverged simulation, QP failures the controller handled, unconverged
MPC solves, Python and MuJoCo warnings, the fall and the wall time.

Finished episodes are appended to ``<work-dir>/<report stem>.episodes.jsonl``. Re-running
the same command skips them; Ctrl-C / SIGTERM stops the workers and writes the report of
what was done. The report lists every failing episode with the command replaying it in
this process (``--replay K``, which lets the exception propagate with its full traceback).

Run::

    MUJOCO_GL=egl .venv/bin/python benchmarks/soak.py --episodes 1000 --workers 2 \
        [--backend process|ray] [--seed 0] [--out benchmarks/results/soak.md]

The modules, in the order an episode goes through them:

* :mod:`~gaitnet_mpc.experiments.soak.draw`: what an episode is (:class:`EpisodeSpec`) and
  how episode K of a seed is drawn (:class:`DrawSettings`, :func:`draw_episode`).
* :mod:`~gaitnet_mpc.experiments.soak.worker`: one episode in a worker process, every
  failure caught and summed up in a JSON record (:func:`run_spec`).
* :mod:`~gaitnet_mpc.experiments.soak.engine`: the soak (:class:`SoakOptions`,
  :func:`soak`): the episodes not yet done on the pool, the resumable episode log.
* :mod:`~gaitnet_mpc.experiments.soak.report`: the Markdown report of the records
  (:func:`make_report`).
* :mod:`~gaitnet_mpc.experiments.soak.cli`: the command line of ``benchmarks/soak.py``
  (:func:`main`; ``--replay K``: :func:`replay`).
"""

from gaitnet_mpc.experiments.soak.cli import main, replay
from gaitnet_mpc.experiments.soak.draw import (
    CONTROLLER_WEIGHTS,
    LONG_COURSES,
    LONG_DURATION_S,
    PROFILES,
    DrawSettings,
    EpisodeSpec,
    draw_episode,
)
from gaitnet_mpc.experiments.soak.engine import RESULTS, SoakOptions, soak
from gaitnet_mpc.experiments.soak.report import FAILURE_HANDLING, make_report
from gaitnet_mpc.experiments.soak.worker import run_spec, simulate, worker_died_record

__all__ = [
    "CONTROLLER_WEIGHTS",
    "FAILURE_HANDLING",
    "LONG_COURSES",
    "LONG_DURATION_S",
    "PROFILES",
    "RESULTS",
    "DrawSettings",
    "EpisodeSpec",
    "SoakOptions",
    "draw_episode",
    "main",
    "make_report",
    "replay",
    "run_spec",
    "simulate",
    "soak",
    "worker_died_record",
]
