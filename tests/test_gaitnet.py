"""Gait-Net: PCA selection, training, NumPy inference against PyTorch, the weights file."""

from __future__ import annotations

import numpy as np
import pytest

from gaitnet_mpc.dataset.schema import FEATURE_NAMES
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gaitnet import GaitNet, GaitNetWeights
from gaitnet_mpc.gaitnet.data import GaitData, split_by_set
from gaitnet_mpc.gaitnet.features import pca_select
from gaitnet_mpc.gaitnet.fit import fit
from gaitnet_mpc.gaitnet.train import TrainConfig


def _synthetic(n_sets: int = 8, rows: int = 60, noise_s: float = 1e-3) -> GaitData:
    """dt depends on a step length over a speed (as a step's duration does) plus noise."""
    rng = np.random.default_rng(0)
    n = n_sets * rows
    x = rng.normal(size=(n, len(FEATURE_NAMES)))
    x[:, FEATURE_NAMES.index("com_vx_mps")] = rng.uniform(0.2, 1.0, n)
    step = rng.uniform(0.05, 0.3, n)
    x[:, FEATURE_NAMES.index("left_foot_x_m")] = step
    y = np.clip(0.01 + 0.05 * step / x[:, FEATURE_NAMES.index("com_vx_mps")], 0.03, 0.08)
    y = y + rng.normal(0.0, noise_s, n)
    return GaitData(
        x=x,
        y=y,
        set_id=np.repeat(np.arange(n_sets), rows),
        pushed=rng.random(n) < 0.3,
        dt_range_s=(0.03, 0.08),
        manifest_sha256="0" * 64,
        robot="biped2d",
        teacher="kd",
    )


def test_pca_picks_one_feature_per_axis_deterministically():
    rng = np.random.default_rng(1)
    base = rng.normal(size=(500, 4))
    x = np.column_stack([base, base[:, :2] @ rng.normal(size=(2, 12))])  # correlated columns
    x += 0.01 * rng.normal(size=x.shape)
    a = pca_select(x, FEATURE_NAMES)
    b = pca_select(x.copy(), FEATURE_NAMES)
    assert a.names == b.names and np.array_equal(a.loadings, b.loadings)
    assert len(a.indices) == 6 and len(set(a.indices)) == 6
    for k, i in enumerate(a.indices):
        # the pick is the largest loading among features no earlier axis took
        free = [j for j in range(16) if j not in a.indices[:k]]
        assert abs(a.loadings[k, i]) == pytest.approx(max(abs(a.loadings[k, free])))
    assert np.all(np.diff(a.explained) <= 1e-12)
    np.testing.assert_allclose(np.linalg.norm(a.loadings, axis=1), 1.0)


def test_split_holds_out_whole_sets():
    ids = np.repeat(np.arange(10), 5)
    s = split_by_set(ids, seed=3)
    assert set(s.train) | set(s.val) | set(s.test) == set(range(10))
    assert not (set(s.train) & set(s.test)) and not (set(s.val) & set(s.test))
    assert split_by_set(ids, seed=3) == s
    with pytest.raises(ConfigError, match="at least 6 sets"):
        split_by_set(np.repeat(np.arange(4), 5))


def test_training_learns_and_numpy_inference_matches_torch(tmp_path):
    pytest.importorskip("torch")
    from gaitnet_mpc.gaitnet.train import torch_predict

    data = _synthetic()
    cfg = TrainConfig(hidden=(16, 16), members=3, epochs=150, patience=30, seed=0)
    result, report, _ = fit(data, "full", cfg, progress=False)
    # the features carry the label: far better than always predicting the mean
    assert report.test_rmse_s < 0.5 * report.mean_predictor_rmse_s
    test = np.isin(data.set_id, report.split.test)
    net = GaitNet(result.weights)
    np.testing.assert_allclose(
        net.members_dt(data.x[test]).mean(axis=1), torch_predict(result, data.x[test]), atol=1e-6
    )
    # one vector at a time (the controller's call) equals the batch
    dt0, spread0 = net.predict(data.x[test][0])
    assert dt0 == pytest.approx(np.clip(net.members_dt(data.x[test][:1]).mean(), 0.03, 0.08))
    assert spread0 >= 0.0

    # repeatable: the same seed gives the same weights
    again, _, _ = fit(data, "full", cfg, progress=False)
    for w1, w2 in zip(result.weights.weights, again.weights.weights, strict=True):
        np.testing.assert_array_equal(w1, w2)

    path = tmp_path / "w.npz"
    result.weights.save(path)
    loaded = GaitNet.load(path)
    np.testing.assert_array_equal(loaded.members_dt(data.x[:5]), net.members_dt(data.x[:5]))
    with np.load(path, allow_pickle=False) as f:  # plain arrays only
        assert "feature_names" in f.files


def test_training_on_listed_features(tmp_path):
    """``--features a,b``: the net takes exactly those inputs, in that order; a name that is
    not a feature, or one listed twice, is refused before any training."""
    pytest.importorskip("torch")
    from gaitnet_mpc.gaitnet.fit import feature_subset

    names = ("left_foot_x_m", "com_vx_mps")
    cfg = TrainConfig(hidden=(8,), members=1, epochs=5, patience=5, seed=0)
    result, report, selection = fit(_synthetic(), ",".join(names), cfg, progress=False)
    assert selection is None and report.feature_names == names
    assert GaitNet(result.weights).feature_names == names
    for bad in ("com_vx_mps,nope", "com_vx_mps,com_vx_mps", ","):
        with pytest.raises(ConfigError, match="--features"):
            feature_subset(bad)
    assert feature_subset("pca") is None and feature_subset("full") is None


def test_spread_grows_outside_the_training_data():
    pytest.importorskip("torch")
    data = _synthetic()
    cfg = TrainConfig(hidden=(16, 16), members=4, epochs=100, patience=30, seed=0)
    result, _, _ = fit(data, "full", cfg, progress=False)
    net = GaitNet(result.weights)
    inside = np.median([net.predict(x)[1] for x in data.x[:50]])
    far = np.median([net.predict(8.0 * x)[1] for x in data.x[:50]])
    assert far > 3.0 * inside


def test_weights_file_errors_name_the_problem(tmp_path):
    with pytest.raises(ConfigError, match=r"existing \.npz"):
        GaitNetWeights.load(tmp_path / "missing.npz")
    with pytest.raises(ConfigError, match="activation"):
        GaitNetWeights(
            weights=(np.zeros((1, 2, 16)),),
            biases=(np.zeros((1, 2)),),
            feature_names=FEATURE_NAMES,
            x_mean=np.zeros(16),
            x_std=np.ones(16),
            y_mean=0.0,
            y_std=1.0,
            dt_clip_s=(0.03, 0.08),
            activation="sigmoid",
        )


@pytest.mark.slow
def test_gaitnet_controller_walks_flat_with_dts_from_the_net(humanoid, tmp_path):
    """The shipped weights in Algorithm 1's loop: the humanoid walks 4 s on flat, every
    step start asked the net inside its iterations, each step lasts h' of its dt and the
    dts stay inside the paper's bounds; mpc_log.csv records each step start's dt calls.
    No stance foot slips or spins (with the CoP over the whole foot, ``cop_fraction`` 1,
    this run had two pivots and two slips)."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.registry import ControllerContext, make_controller
    from gaitnet_mpc.results.rundir import read_csv_columns
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    course, command = load_course("flat"), Command(0.5)
    ctrl = make_controller("gaitnet", ControllerContext(humanoid, course, command))
    sim = Simulator(humanoid, course)
    summary = run_episode(sim, ctrl, command, 4.0, out_dir=tmp_path, progress=False)
    log = read_csv_columns(tmp_path / "mpc_log.csv")
    full = log["full_solve"] == 1
    steps = summary["dt_policy"]["steps"]
    np.testing.assert_array_equal(log["dt_calls"][full], [len(d["dts_s"]) for d in steps])
    np.testing.assert_allclose(log["dt_first_s"][full], [d["dts_s"][0] for d in steps])
    assert np.all(np.isnan(log["dt_calls"][~full])) and np.all(log["failed"] == 0)
    assert not summary["fell"], summary["fall_reason"]
    assert summary["distance_m"] > 1.2
    policy = summary["dt_policy"]
    assert policy["decisions"] == len(summary["step_durations_s"]) >= 10
    chosen = np.array([d["dts_s"][-1] for d in policy["steps"]])
    assert np.all((chosen >= 0.045 - 1e-12) & (chosen <= 0.07 + 1e-12))
    # each step lasts h' of its dt, or ends where its foot landed in its second half (the
    # landing rule, a logged event; on flat ground the re-timing never fires unpushed)
    planned, executed = 5 * chosen, np.array(summary["step_durations_s"])
    short = executed < planned - 1e-3
    assert np.all(executed <= planned + 1e-3) and np.all(executed >= 0.5 * planned)
    kinds = [e["kind"] for e in summary["swing_events"]]
    assert short.sum() <= kinds.count("landing") and "retime" not in kinds
    assert all(len(d["dts_s"]) >= 1 for d in policy["steps"])
    # each decision records the net's input: 16 features, the CoM above the stance foot
    feats = np.array([d["features"] for d in policy["steps"]])
    assert feats.shape == (len(steps), len(FEATURE_NAMES))
    assert np.all(np.abs(feats[:, FEATURE_NAMES.index("com_z_m")] - 0.54) < 0.05)
    events = (tmp_path / "events.csv").read_text().splitlines()
    assert not [e for e in events if ",slip," in e or ",pivot," in e]


class _DriftingNet:
    """A stand-in network whose answer grows by 5 ms per call (the drift of a fixed point
    that is not attracting), with a set ensemble spread."""

    feature_names = FEATURE_NAMES

    def __init__(self, spread_s: float = 1e-3, step_s: float = 0.005) -> None:
        self.dt_s, self.spread_s, self.step_s = 0.045, spread_s, step_s

    def predict(self, x: np.ndarray) -> tuple[float, float]:
        self.dt_s += self.step_s
        return self.dt_s, self.spread_s


class _ConstantNet:
    """A stand-in network that always answers ``dt_s`` with a small spread."""

    feature_names = FEATURE_NAMES

    def __init__(self, dt_s: float) -> None:
        from types import SimpleNamespace

        self.dt_s = dt_s
        self.spec = SimpleNamespace(teacher="stand-in", data_manifest_sha256="", members=1)

    def predict(self, x: np.ndarray) -> tuple[float, float]:
        return self.dt_s, 1e-4


@pytest.mark.parametrize("carry_dt", [False, True])
def test_each_step_starts_its_iterations_from_the_nominal_dt(humanoid, carry_dt: bool) -> None:
    """Algorithm 1 line 3: every step start's first iteration plans with the nominal dt^0
    (0.045 s), whatever the step before chose (here always 0.06 s); ``carry_dt`` starts
    it from the previous step's dt instead."""
    from dataclasses import replace

    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.kd_walk import KDWalkController
    from gaitnet_mpc.control.kd_walk_config import KDWalkConfig
    from gaitnet_mpc.control.terrain_view import TerrainView
    from gaitnet_mpc.gaitnet.policy import GaitNetDt
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    course, command = load_course("flat"), Command(0.5)
    config = replace(KDWalkConfig(), carry_dt=carry_dt)
    policy = GaitNetDt(_ConstantNet(0.06), planar=False)  # type: ignore[arg-type]
    ctrl = KDWalkController(humanoid, TerrainView(course), command, policy, config)
    sim = Simulator(humanoid, course)
    state = sim.state()
    ctrl.reset(state)
    while state.t_s < 1.0:
        sim.step(ctrl.compute(state))
        state = sim.state()
    starts = [d.start_dt_s for d in policy.decisions]
    assert len(starts) >= 3
    assert all(d.dts_s[-1] == pytest.approx(0.06) for d in policy.decisions)
    expected = [0.045] + [0.06 if carry_dt else 0.045] * (len(starts) - 1)
    np.testing.assert_allclose(starts, expected)


def _ask(policy, problem, calls: int) -> list[float]:
    """The dts the policy gives over ``calls`` iterations of one step start."""
    out, dt = [], 0.045
    for _ in range(calls):
        dt = policy(problem, None, dt)
        out.append(dt)
    return out


@pytest.fixture
def _step_start(monkeypatch):
    """A step-start problem whose features and touchdown do not matter to the stand-in."""
    from types import SimpleNamespace

    import gaitnet_mpc.gaitnet.policy as policy_module

    monkeypatch.setattr(policy_module, "planned_touchdowns", lambda it, c: {"left": [None]})
    monkeypatch.setattr(policy_module, "step_features", lambda *a: np.zeros(len(FEATURE_NAMES)))
    state = SimpleNamespace(state=SimpleNamespace(t_s=0.0), stance_foot="right", swing_foot="left")
    timing = SimpleNamespace(contact=None)
    return lambda: SimpleNamespace(state=state, timing=timing, heading_rad=0.0)


def test_policy_freezes_a_drifting_dt_after_max_retimes(_step_start):
    from gaitnet_mpc.gaitnet.policy import GaitNetDt, GaitNetPolicyConfig

    unlimited = GaitNetPolicyConfig(max_retimes=None)  # Algorithm 1 as printed
    free = GaitNetDt(_DriftingNet(), False, unlimited)  # type: ignore[arg-type]
    assert _ask(free, _step_start(), 6)[-1] == pytest.approx(0.07)  # drifts to the bound
    capped = GaitNetDt(_DriftingNet(), False, GaitNetPolicyConfig(max_retimes=2))  # type: ignore[arg-type]
    dts = _ask(capped, _step_start(), 6)
    assert dts == pytest.approx([0.05, 0.055, 0.055, 0.055, 0.055, 0.055])
    summary = capped.summary()
    assert summary["frozen"] == 1 and summary["fallbacks"] == {"spread": 0, "cycle": 0}


def test_policy_falls_back_on_a_wide_spread(_step_start):
    from gaitnet_mpc.gaitnet.policy import GaitNetDt, GaitNetPolicyConfig

    policy = GaitNetDt(_DriftingNet(spread_s=0.02), planar=False)  # type: ignore[arg-type]
    assert _ask(policy, _step_start(), 3) == pytest.approx([0.045] * 3)  # the nominal dt
    assert policy.summary()["fallbacks"]["spread"] == 1
    paper = GaitNetPolicyConfig(safeguards=False)  # Algorithm 1 as printed: the net's dt
    bare = GaitNetDt(_DriftingNet(spread_s=0.02), False, paper)  # type: ignore[arg-type]
    assert _ask(bare, _step_start(), 6) == pytest.approx([0.05, 0.055, 0.06, 0.065, 0.07, 0.07])
    assert bare.summary()["fallbacks"]["spread"] == 0


def test_spread_fallback_keeps_the_dt_the_previous_step_ran_with(_step_start):
    """A step re-timed under way ran with its new dt; the next step's spread fallback keeps
    that one (clipped into the bounds), not the dt first chosen for it."""
    from gaitnet_mpc.gaitnet.policy import GaitNetDt

    net = _DriftingNet(step_s=0.0)
    net.dt_s = 0.065
    policy = GaitNetDt(net, planar=False)  # type: ignore[arg-type]
    assert _ask(policy, _step_start(), 2) == pytest.approx([0.065] * 2)
    policy.step_retimed(0.05)  # the step under way now ends as a 5 x 0.05 s step
    net.spread_s = 0.02  # the next step start lies outside the data
    assert _ask(policy, _step_start(), 2) == pytest.approx([0.05] * 2)
    policy.step_retimed(0.03)  # below the policy's bounds
    assert _ask(policy, _step_start(), 1) == pytest.approx([0.045])  # clipped
    steps = policy.summary()["steps"]
    assert [s["retimed_dt_s"] for s in steps] == [0.05, 0.03, None]
    assert [s["fallback"] for s in steps] == [None, "spread", "spread"]


@pytest.mark.slow
def test_oracle_keeps_the_converged_plan_of_lowest_cost(biped):
    """The grid-search oracle on the biped: every step start tried the whole grid of the
    paper's 2-D bounds and kept the dt of lowest eq. 18 cost among converged plans; the
    robot walks."""
    from gaitnet_mpc.command import Command
    from gaitnet_mpc.control.registry import ControllerContext, make_controller
    from gaitnet_mpc.dt_policy import oracle_grid_s, paper_dt_bounds_s
    from gaitnet_mpc.runner.episode import run_episode
    from gaitnet_mpc.sim.simulator import Simulator
    from gaitnet_mpc.terrain import load_course

    course, command = load_course("flat"), Command(0.5)
    ctrl = make_controller("oracle", ControllerContext(biped, course, command))
    summary = run_episode(Simulator(biped, course), ctrl, command, 2.0, progress=False)
    assert not summary["fell"], summary["fall_reason"]
    grid = oracle_grid_s(paper_dt_bounds_s(planar=True))
    steps = summary["dt_policy"]["steps"]
    assert len(steps) == len(summary["step_durations_s"]) >= 5
    for d in steps:
        costs = np.array([np.nan if c is None else c for c in d["costs"]], dtype=float)
        assert costs.size == len(grid) and np.isfinite(costs).any()
        assert d["dts_s"][0] == pytest.approx(grid[int(np.nanargmin(costs))])
    np.testing.assert_allclose(
        summary["step_durations_s"], [5 * d["dts_s"][0] for d in steps], atol=1e-3
    )


def _state_from(rot, com, vel, omega, feet):
    from gaitnet_mpc.state import RobotState

    z = np.zeros(3)
    return RobotState(
        t_s=0.0, qpos=np.zeros(7), qvel=np.zeros(6), base_pos_world_m=com,
        base_rot_world=rot, base_lin_vel_world_mps=z, base_ang_vel_world_radps=omega,
        joint_pos_rad=np.zeros(0), joint_vel_radps=np.zeros(0), com_world_m=com,
        com_vel_world_mps=vel, h_measured=np.zeros(6), foot_pos_world_m=feet,
        foot_yaw_rad={"left": 0.0, "right": 0.0}, foot_contact={"left": True, "right": False},
        foot_wrench_world={"left": np.zeros(6), "right": np.zeros(6)},
    )  # fmt: skip


@pytest.mark.parametrize("heading", [0.0, 0.7])
def test_mirror_features_are_those_of_the_mirrored_step_start(heading: float) -> None:
    """The features of a step start reflected through the heading's x-z plane (legs
    swapped; the trunk's frame is the reflected one with its y axis turned back, ``F R S``)
    are ``mirror_features`` of its features; mirroring twice is the identity."""
    from scipy.spatial.transform import Rotation

    from gaitnet_mpc.dataset.step_features import mirror_features, step_features

    rng = np.random.default_rng(7)
    c, s = np.cos(heading), np.sin(heading)
    yaw = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # world <- heading
    flip = yaw @ np.diag([1.0, -1.0, 1.0]) @ yaw.T  # the reflection y -> -y of the heading
    rot = Rotation.from_euler("ZYX", [heading + 0.2, 0.1, -0.15]).as_matrix()
    com = rng.normal(size=3) + np.array([0.0, 0.0, 0.55])
    vel, omega = rng.normal(size=3), rng.normal(size=3)
    feet = {"left": rng.normal(size=3), "right": rng.normal(size=3)}
    touchdown = rng.normal(size=3)
    x = step_features(_state_from(rot, com, vel, omega, feet), "left", "right", touchdown, heading)
    mirrored = _state_from(
        flip @ rot @ np.diag([1.0, -1.0, 1.0]), flip @ com, flip @ vel, -flip @ omega,
        {"left": flip @ feet["right"], "right": flip @ feet["left"]},
    )  # fmt: skip
    x_m = step_features(mirrored, "right", "left", flip @ touchdown, heading)
    np.testing.assert_allclose(mirror_features(x), x_m, atol=1e-12)
    np.testing.assert_array_equal(mirror_features(mirror_features(x)), x)


def test_mirror_symmetric_prediction_is_the_members_mean_of_both():
    """``predict(x, x_mirror)``: each member averages its two answers, so the two orders
    give the same dt and spread."""
    rng = np.random.default_rng(1)
    f, hidden, k = len(FEATURE_NAMES), 8, 3
    net = GaitNet(
        GaitNetWeights(
            weights=(rng.normal(size=(k, hidden, f)), 0.01 * rng.normal(size=(k, 1, hidden))),
            biases=(rng.normal(size=(k, hidden)), np.zeros((k, 1))),
            feature_names=FEATURE_NAMES, x_mean=np.zeros(f), x_std=np.ones(f), y_mean=0.05,
            y_std=0.01, dt_clip_s=(0.03, 0.08), activation="tanh",
            data_manifest_sha256="0" * 64, robot="humanoid3d", teacher="kd",
        )
    )  # fmt: skip
    x, x_m = rng.normal(size=len(FEATURE_NAMES)), rng.normal(size=len(FEATURE_NAMES))
    members = 0.5 * (net.members_dt(x) + net.members_dt(x_m))
    dt, spread = net.predict(x, x_m)
    assert dt == pytest.approx(np.clip(members.mean(), *net.dt_clip_s))
    assert spread == pytest.approx(members.std())
    assert net.predict(x_m, x) == pytest.approx((dt, spread))
