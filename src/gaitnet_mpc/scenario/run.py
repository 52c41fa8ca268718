"""Running a scenario: :func:`run_scenario` (into a run folder claimed by the rules of
``gaitnet-mpc run --out``) and :func:`simulate_episode`, the simulation of a built episode
into a folder the caller has claimed."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from gaitnet_mpc import config as configio
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.results.io import write_atomic
from gaitnet_mpc.results.outdir import check_output_path, claim_output_folder
from gaitnet_mpc.results.plots import make_plots
from gaitnet_mpc.results.rundir import RUN_ARTIFACTS
from gaitnet_mpc.robots import RobotModel
from gaitnet_mpc.runner.episode import VideoConfig, run_episode
from gaitnet_mpc.scenario.model import (
    Episode,
    Scenario,
    build_episode,
    scenario_meta,
    scenario_warnings,
)
from gaitnet_mpc.sim.simulator import Simulator

#: File names a run folder gets from :func:`run_scenario`.
SCENARIO_FILE = "scenario.toml"
CONFIG_FILE = "config.toml"


def write_scenario_files(scenario: Scenario, out_dir: Path) -> None:
    """``scenario.toml`` and (for a controller with settings) ``config.toml`` in ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    header = (
        f"`gaitnet-mpc run --scenario {SCENARIO_FILE}` replays this run (identical "
        'summary.json);\n"none" stands for None.'
    )
    write_atomic(out_dir / SCENARIO_FILE, scenario.to_toml(header))
    if scenario.config is not None:
        text = (
            f"Settings of the {scenario.controller} controller "
            f"({type(scenario.config).__name__}) on {scenario.robot}, after the preset,\n"
            "--config, the flags and --set. `--config config.toml` repeats them; "
            '"none" stands for None.'
        )
        if scenario.controller in ("kd", "gaitnet", "oracle"):
            text += "\nsequential.kd.mass_kg and min_foot_separation_m are set from the robot."
        write_atomic(out_dir / CONFIG_FILE, configio.dumps(scenario.config, text))


def run_scenario(
    scenario: Scenario,
    out_dir: str | Path | None = None,
    *,
    overwrite: bool = False,
    video: VideoConfig | bool | None = False,
    plots: bool = False,
    progress: bool = False,
    robot: RobotModel | None = None,
    episode: Episode | None = None,
    on_step: Callable[[Simulator], None] | None = None,
) -> dict[str, Any]:
    """Simulate ``scenario`` until its duration or a fall; return the summary.

    With ``out_dir``, write a run folder there (``scenario.toml``, ``config.toml``,
    ``summary.json``, ``timing.json``, logs, course) by the rules of ``gaitnet-mpc run
    --out`` (:func:`~gaitnet_mpc.results.outdir.claim_output_folder`): checked before the
    episode is built, locked while the run writes, new or empty, or with ``overwrite`` one
    holding only an earlier run, whose files (video and plots included) are removed first.

    Args:
        overwrite: replace the earlier run in ``out_dir`` (default False: refuse).
        video: ``video.mp4`` in ``out_dir``: True or a :class:`VideoConfig` (its camera);
            default False: none (rendering takes longer than simulating).
        plots: the PNGs of ``out_dir/plots/`` (default False: none; ``gaitnet-mpc plot``
            makes them later from the folder).
        robot: an already loaded model of ``scenario.robot``; None: load it.
        episode: ``build_episode(scenario)`` made by the caller; None: built here.
        on_step: called with the simulator after every physics step (``run_episode``'s
            hook: e.g. poses for a snapshot strip); it must not change the simulation.

    Raises:
        ConfigError: ``out_dir`` cannot be written, holds other files (or an earlier run
            without ``overwrite``), or another process writes there; ``video`` or
            ``plots`` without ``out_dir``.
    """
    if out_dir is not None:
        check_output_path(out_dir, "out_dir")
    for name, wanted in (("video", video), ("plots", plots)):
        if wanted and out_dir is None:
            raise ConfigError(name, wanted, "False without an out_dir to write into")
    if episode is None:
        episode = build_episode(scenario, robot=robot)
    elif episode.scenario is not scenario:
        raise ConfigError("episode", "another scenario's", "build_episode(scenario)")
    video_config = VideoConfig() if video is True else (video or None)
    if out_dir is None:
        return simulate_episode(episode, None, progress=progress, on_step=on_step)
    with claim_output_folder(
        out_dir,
        option="out_dir",
        default_prefix="",
        artifacts=RUN_ARTIFACTS,
        overwrite=overwrite,
        overwrite_hint="overwrite=True",
    ) as out:
        summary = simulate_episode(
            episode, out, video=video_config, progress=progress, on_step=on_step
        )
        if plots:
            make_plots(out)
    return summary


def simulate_episode(
    episode: Episode,
    out: Path | None,
    *,
    video: VideoConfig | None = None,
    progress: bool = False,
    viewer_factory: Any = None,
    extra_warnings: Sequence[str] = (),
    on_step: Callable[[Simulator], None] | None = None,
) -> dict[str, Any]:
    """:func:`run_scenario`'s simulation of a built episode, its run files (and video if
    ``video``) written into ``out``, a folder the caller has claimed (``gaitnet-mpc run``
    and the figure commands do; nothing is checked here).

    Args:
        viewer_factory: called with the simulator, returns an open MuJoCo passive viewer
            handle (``gaitnet-mpc run --viewer``); closed at the end. None: no viewer.
        extra_warnings: the caller's own notes on ineffective options (recorded with
            :func:`scenario_warnings` in the summary's ``warnings``).
    """
    scenario = episode.scenario
    if out is not None:
        write_scenario_files(scenario, out)
    warnings = [*scenario_warnings(scenario), *extra_warnings]
    meta = scenario_meta(episode, warnings)
    viewer = viewer_factory(episode.sim) if viewer_factory is not None else None
    try:
        return run_episode(
            episode.sim,
            episode.controller,
            scenario.command,
            scenario.duration_s,
            out,
            video if out is not None else None,
            progress=progress,
            meta=meta,
            viewer=viewer,
            on_step=on_step,
        )
    finally:
        if viewer is not None:
            viewer.close()
