"""Controller settings from TOML: presets, ``--set`` overrides, the run's ``config.toml``."""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from gaitnet_mpc.config import apply, dumps, load_preset, parse_overrides, preset_names
from gaitnet_mpc.control.kd_walk_config import KDWalkConfig, preview_walk_config
from gaitnet_mpc.control.registry import controller_config
from gaitnet_mpc.control.srbm_walk import SRBMWalkConfig
from gaitnet_mpc.dt_policy import DtPolicyConfig, GaitNetPolicyConfig
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.preview import PreviewConfig
from gaitnet_mpc.mpc.contact import ContactParams
from gaitnet_mpc.mpc.implicit_kd import KDConfig
from gaitnet_mpc.mpc.sequential import SequentialConfig


def _paper_walk_config(planar: bool) -> KDWalkConfig:
    """``kd --preset paper`` written out: Table VIII (planar: Table V) read per unit of
    motion, Table X, H_ref by eq. 30, no disturbance observer, no reach rows, no step
    re-timing under way and (humanoid) the net taught by this preset's ``kd``, over the
    default preset (its other robot-level rows and low level)."""
    default = _default_walk_config(planar)
    if planar:
        kd = KDConfig(
            weight_units="motion",
            w_momentum=(20.0,) * 6,
            w_pose=(200.0, 200.0, 200.0, 300.0, 300.0, 300.0),
            w_p_foot=(0.01, 0.01, 0.01),
            w_p_com=(100.0, 100.0, 300.0),
            contact=ContactParams(fz_max_n=250.0),
        )
    else:
        kd = KDConfig(weight_units="motion")  # Table VIII
    net = None if planar else "humanoid3d-kd-paper"  # taught by this preset's kd
    return replace(
        default,
        sequential=SequentialConfig(kd=kd, reference_pose="eq30"),
        dt_policy=DtPolicyConfig(
            gaitnet_weights=net, gaitnet=GaitNetPolicyConfig(retime_steps=None)
        ),
        disturbance_observer=None,
        keep_feet_in_reach=False,
    )


def _default_walk_config(planar: bool) -> KDWalkConfig:
    """The default preset: ``KDWalkConfig()``; on a planar robot with the biped's foothold
    margin (its 0.02 m point foot + 5 mm) and without the humanoid's trunk settings
    (roll / pitch pose weight 6000, trunk roll / pitch feedback, the disturbance observer;
    kd-default.planar.toml)."""
    config = KDWalkConfig()
    if not planar:
        return config
    kd = replace(config.sequential.kd, w_pose=(1.0, 1.0, 1.0, 2000.0, 2000.0, 2000.0))
    return replace(
        config,
        foothold_margin_m=0.025,
        sequential=replace(config.sequential, kd=kd),
        low_level=replace(
            config.low_level, stance_tilt_kp_nm_per_rad=0.0, stance_tilt_kd_nms_per_rad=0.0
        ),
        disturbance_observer=None,
    )


@pytest.mark.parametrize("planar", [False, True])
def test_preset_files_give_the_configs_of_the_former_factories(planar: bool) -> None:
    assert preset_names("kd") == ["blind", "default", "fastdt", "paper", "realtime"]
    assert preset_names("srbm") == ["default"]
    default = _default_walk_config(planar)
    assert load_preset(KDWalkConfig, "kd", "default", planar) == default
    realtime = load_preset(KDWalkConfig, "kd", "realtime", planar)
    assert realtime == replace(
        default, replan_j_max=1, warm_start_replans=True, converge_new_stages=True
    )
    assert load_preset(KDWalkConfig, "kd", "blind", planar) == replace(default, blind=True)
    fast = replace(default.dt_policy, bounds_s=(0.035, 0.07))
    assert load_preset(KDWalkConfig, "kd", "fastdt", planar) == replace(default, dt_policy=fast)
    assert load_preset(KDWalkConfig, "kd", "paper", planar) == _paper_walk_config(planar)
    assert load_preset(SRBMWalkConfig, "srbm", "default", planar) == SRBMWalkConfig()


@pytest.mark.parametrize("planar", [False, True])
def test_registry_configs_equal_todays(planar: bool) -> None:
    assert controller_config("kd", planar) == _default_walk_config(planar)
    assert controller_config("kd", planar, preset="paper", preview=True) == preview_walk_config(
        _paper_walk_config(planar)
    )
    assert controller_config("srbm", planar, dt_s=0.05) == SRBMWalkConfig(dt_s=0.05)
    assert controller_config("stand", planar) is None


@pytest.mark.parametrize(
    "config",
    [
        KDWalkConfig(),
        _paper_walk_config(True),
        preview_walk_config(),
        replace(KDWalkConfig(), lip_anchor_max_m=0.02, preview=PreviewConfig(n_steps=4)),
        SRBMWalkConfig(com_height_m=0.6),
    ],
)
def test_a_whole_config_round_trips_through_toml(config: object) -> None:
    text = dumps(config, header="a header\nover two lines")
    assert text.startswith("# a header\n# over two lines\n")
    assert apply(type(config)(), tomllib.loads(text)) == config
    # also over another starting point (a run's config.toml is complete)
    start = _paper_walk_config(False) if isinstance(config, KDWalkConfig) else None
    if start is not None:
        assert apply(start, tomllib.loads(text)) == config


def test_overrides_are_typed_and_nested() -> None:
    data = parse_overrides(
        [
            "sequential.kd.w_force=1e-3",
            "sequential.kd.horizon=12",
            "sequential.kd.w_p_com=[1, 2, 3]",
            "sequential.kd.qp_options={check_problem = true}",
            "lateral_reference=lip",
            "lateral_return_time_s=none",
            "keep_feet_apart=false",
            "preview.n_steps=4",
        ]
    )
    config = apply(KDWalkConfig(), data)
    kd = config.sequential.kd
    assert kd.w_force == 1e-3 and kd.horizon == 12 and kd.w_p_com == (1.0, 2.0, 3.0)
    assert kd.qp_options == (("check_problem", True),)
    assert isinstance(kd.w_p_com[0], float)
    assert config.lateral_reference == "lip" and config.lateral_return_time_s is None
    assert config.keep_feet_apart is False
    assert config.preview == PreviewConfig(n_steps=4)  # a None dataclass starts at defaults
    assert config.sequential.kd.w_pose == KDWalkConfig().sequential.kd.w_pose  # untouched
    assert apply(config, parse_overrides(["preview=none"])).preview is None


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ("sequential.kd.w_force=abc", "sequential.kd.w_force: got 'abc', expected a number"),
        ("sequential.kd.w_force=true", "sequential.kd.w_force: got True, expected a number"),
        ("sequential.kd.horizon=2.5", "sequential.kd.horizon: got 2.5, expected an integer"),
        ("sequential.kd.horizon=0", "sequential.kd.horizon: got 0, expected an integer in [1, "),
        ("sequential.kd.w_p_com=[1, 2]", "w_p_com: got [1, 2], expected a list of 3 float"),
        ("sequential.kd.w_pose=[1, 2]", "sequential.kd.w_pose: got (1.0, 2.0), expected 6"),
        ("keep_feet_apart=1", "keep_feet_apart: got 1, expected true or false"),
        ("lateral_reference=zigzag", "lateral_reference: got 'zigzag', expected 'line'"),
        ("lateral_return_time_s=-1", "lateral_return_time_s: got -1, expected None or"),
        ("cop_fraction=0", "cop_fraction: got 0, expected a fraction in (0, 1]"),
        ("cop_fraction=1.5", "cop_fraction: got 1.5, expected a fraction in (0, 1]"),
        ("sequential.kd=3", "sequential.kd: got 3, expected a table of KDConfig"),
        ("sequential.kd.w_forse=1", "close matches: sequential.kd.w_force"),
        ("w_force=1", "w_force: got 1, expected a field of KDWalkConfig; close matches: "),
        ("nonsense_key_xyz=1", "expected a field of KDWalkConfig: one of replan_period_s"),
    ],
)
def test_bad_overrides_name_the_full_key_value_and_expectation(item: str, message: str) -> None:
    with pytest.raises(ConfigError) as exc:
        apply(KDWalkConfig(), parse_overrides([item]), "--set ")
    assert str(exc.value).startswith("--set ")
    assert message in str(exc.value)
    if item.startswith("w_force"):
        assert "sequential.kd.w_force" in str(exc.value)


@pytest.mark.parametrize("item", ["noequals", "=1", "a..b=1", "a.b="])
def test_malformed_set_is_refused(item: str) -> None:
    with pytest.raises(ConfigError, match="--set: got"):
        parse_overrides([item])


def test_config_files_and_presets_are_checked(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[sequential.kd\n")
    with pytest.raises(ConfigError, match=r"--config: got .*bad.toml.*expected a valid UTF-8"):
        controller_config("kd", False, config_file=bad)
    with pytest.raises(ConfigError, match=r"--config: got .*missing.toml"):
        controller_config("kd", False, config_file=tmp_path / "missing.toml")
    good = tmp_path / "good.toml"
    good.write_text("[sequential]\nj_max = 7\n")
    wrong = tmp_path / "wrong.toml"
    wrong.write_text("[sequential]\nj_max = 'x'\n")
    with pytest.raises(ConfigError, match=r"wrong.toml: sequential.j_max: got 'x'"):
        controller_config("kd", False, config_file=wrong)
    config = controller_config("kd", False, config_file=good, overrides=["replan_j_max=3"])
    assert config.sequential.j_max == 7 and config.replan_j_max == 3
    with pytest.raises(ConfigError, match="--preset: got 'paper', expected one of"):
        controller_config("srbm", False, preset="paper")
    with pytest.raises(ConfigError, match=r"--set: got .*the stand controller has no settings"):
        controller_config("stand", False, overrides=["a=1"])
