"""A simulation that diverges ends the episode and says so (``diverged`` in the summary)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gaitnet_mpc.command import Command
from gaitnet_mpc.control.stand import StandController
from gaitnet_mpc.runner.episode import run_episode
from gaitnet_mpc.sim.simulator import SimConfig, Simulator
from gaitnet_mpc.terrain import load_course

INJECT_AT_S = 0.2


@pytest.fixture(autouse=True)
def _mujoco_log_in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """MuJoCo appends its instability warnings to ./MUJOCO_LOG.TXT: keep it out of the repo."""
    monkeypatch.chdir(tmp_path)


class _Sabotaged(StandController):
    """The standing controller, plus a corruption of the simulation at ``INJECT_AT_S``."""

    def __init__(self, robot, sim: Simulator, how: str) -> None:
        super().__init__(robot)
        self.sim = sim
        self.how = how

    def compute(self, state):
        tau = super().compute(state)
        if abs(state.t_s - INJECT_AT_S) < 1e-6:
            d = self.sim.data
            if self.how == "nan_qvel":
                d.qvel[7] = np.nan
            else:  # a force no Push may apply, on a body the pushes do not touch
                d.xfrc_applied[self.sim.model.body("left_shank").id, 0] = 1e9
        return tau


@pytest.mark.parametrize("how", ["nan_qvel", "huge_force"])
def test_injected_divergence_ends_the_episode_as_diverged(
    humanoid, how: str, tmp_path: Path
) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    summary = run_episode(
        sim, _Sabotaged(humanoid, sim, how), Command(), 1.0, tmp_path, progress=False
    )
    assert summary["diverged"] is True
    assert summary["fell"] is True
    assert summary["fall_reason"].startswith("simulation diverged")
    assert summary["fall_time_s"] == pytest.approx(INJECT_AT_S + 0.001, abs=1e-6)
    # the state is rolled back to the last good one: distance and speed stay physical
    assert summary["duration_s"] == pytest.approx(summary["fall_time_s"])
    assert abs(summary["distance_m"]) < 0.01 and abs(summary["mean_speed_mps"]) < 0.1
    assert np.all(np.isfinite(sim.data.qpos)) and np.all(np.isfinite(sim.data.qvel))
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["diverged"] is True


def test_nan_velocity_is_reported_with_mujocos_warning(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    sim.step(np.zeros(humanoid.n_joints))
    sim.data.qvel[0] = np.nan
    sim.step(np.zeros(humanoid.n_joints))
    assert sim.diverged and sim.fall.fell
    assert sim.fall.reason.startswith("simulation diverged: MuJoCo warning BADQVEL")
    assert sim.fall.t_s == pytest.approx(0.002)
    assert sim.time_s == pytest.approx(0.002)  # MuJoCo reset the clock; it was restored


def test_impossible_trunk_speed_is_divergence(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    sim.data.qvel[0] = 25.0  # above max_trunk_speed_mps = 20
    sim.step(np.zeros(humanoid.n_joints))
    assert sim.diverged
    assert "trunk speed" in sim.fall.reason


def test_divergence_takes_precedence_over_a_fall_at_the_same_tick(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    qpos = humanoid.standing_qpos()
    qpos[2] = 0.1  # trunk in the ground: a fall by CoM height and body contact ...
    sim.reset(qpos)
    sim.data.qvel[0] = 25.0  # ... and an impossible speed at the same tick
    sim.step(np.zeros(humanoid.n_joints))
    assert sim.diverged
    assert sim.fall.reason.startswith("simulation diverged")


def test_normal_stand_run_has_not_diverged(humanoid) -> None:
    sim = Simulator(humanoid, load_course("flat"))
    summary = run_episode(sim, StandController(humanoid), Command(), 0.3, progress=False)
    assert summary["diverged"] is False
    assert summary["fell"] is False and summary["fall_reason"] is None


@pytest.mark.parametrize("field", ["max_trunk_speed_mps", "max_joint_speed_radps"])
def test_speed_bounds_must_be_positive(field: str) -> None:
    from gaitnet_mpc.errors import ConfigError

    with pytest.raises(ConfigError, match=field):
        SimConfig(**{field: 0.0})
