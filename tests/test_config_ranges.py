"""Every number a controller's settings hold has a physical range (issue 37).

The settings reachable by ``--set`` (``--config FILE.toml``, presets, ``collect --set``)
are the config trees of the registry's controllers. Each int, float and tuple-of-number
field is declared with :func:`gaitnet_mpc.config.bounded` (a :class:`Range` with its unit
and reason); a value outside is refused, by :func:`~gaitnet_mpc.config.apply` with the full
dotted key and by the dataclass itself when built in Python. ``tests/corpus/overrides.txt``
holds ``--set`` items (one per line) that once raised something else than a
:class:`ConfigError`; they are replayed on every controller.
"""

from __future__ import annotations

import typing
from collections.abc import Iterator
from dataclasses import Field, fields, is_dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any, NamedTuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitnet_mpc.cli import main
from gaitnet_mpc.config import (
    Range,
    _all_keys,
    apply,
    check_value,
    field_range,
    parse_overrides,
    preset_names,
    read_toml,
)
from gaitnet_mpc.control.registry import CONTROLLERS, KD_FAMILY, config_type, controller_config
from gaitnet_mpc.dt_policy import CONTROL_TICK_S
from gaitnet_mpc.errors import ConfigError

#: Controllers with settings, one of each config class (kd, gaitnet, oracle share one).
CONFIGURED = sorted(n for n in CONTROLLERS if config_type(n) is not None)
CLASSES = [n for n in CONFIGURED if n not in KD_FAMILY[1:]]
#: str fields that take any text (a path or a shipped name), not one of fixed choices.
FREE_TEXT = {"dt_policy.gaitnet_weights"}
CORPUS = Path(__file__).parent / "corpus" / "overrides.txt"


def _unwrap(tp: Any) -> tuple[Any, bool]:
    """(the type inside ``X | None``, whether None was allowed)."""
    if typing.get_origin(tp) in (typing.Union, typing.get_origin(int | None)):
        (inner,) = (a for a in typing.get_args(tp) if a is not type(None))
        return inner, True
    return tp, False


def _is_number_type(tp: Any) -> bool:
    """int, float, or a tuple of them (``tuple[float, ...]``, ``tuple[float, float]``)."""
    if tp in (int, float):
        return True
    if typing.get_origin(tp) is tuple:
        args = [a for a in typing.get_args(tp) if a is not Ellipsis]
        return bool(args) and all(a in (int, float) for a in args)
    return False


class Leaf(NamedTuple):
    """A non-dataclass field of a config tree."""

    key: str  # dotted, from the tree's root
    owner: Any  # the dataclass instance that holds it
    field: Field[Any]
    type: Any  # the annotation without ``| None``
    optional: bool  # the annotation admits None
    value: Any


def _leaves(obj: Any, prefix: str = "") -> Iterator[Leaf]:
    """Every non-dataclass field of the config tree ``obj``, walking into the nested
    dataclasses (those that are not None)."""
    hints = typing.get_type_hints(type(obj))
    for f in fields(obj):
        if not f.init:
            continue
        value = getattr(obj, f.name)
        inner, optional = _unwrap(hints[f.name])
        if is_dataclass(inner):
            if value is not None:
                yield from _leaves(value, f"{prefix}{f.name}.")
            continue
        yield Leaf(prefix + f.name, obj, f, inner, optional, value)


def _trees(name: str) -> Iterator[tuple[str, Any]]:
    """(label, config) of every shipped preset of controller ``name``, on both robots, and
    for the kd family with ``--preview`` (PreviewConfig is None by default)."""
    preset_of = "kd" if name in KD_FAMILY else name
    for preset in preset_names(preset_of):
        for planar in (False, True):
            yield f"{preset} planar={planar}", controller_config(name, planar, preset=preset)
    if name in KD_FAMILY:
        yield "--preview", controller_config(name, False, preview=True)


@cache
def _default(name: str) -> Any:
    return controller_config(name, False)


# --------------------------------------------------------------------------- (a) coverage
@pytest.mark.parametrize("name", CONFIGURED)
def test_every_number_field_has_a_range(name: str) -> None:
    numbers = {leaf.key: leaf for _, tree in _trees(name) for leaf in _leaves(tree)}
    numbers = {k: leaf for k, leaf in numbers.items() if _is_number_type(leaf.type)}
    missing = sorted(k for k, leaf in numbers.items() if field_range(leaf.field) is None)
    assert not missing, f"fields without a Range (declare them with config.bounded): {missing}"
    assert len(numbers) >= 20  # the walk found the tree


@pytest.mark.parametrize("name", CONFIGURED)
def test_defaults_and_shipped_presets_lie_inside_their_ranges(name: str) -> None:
    cls = config_type(name)
    assert cls is not None
    for label, tree in [("defaults", cls()), *_trees(name)]:
        for leaf in _leaves(tree):
            rng = field_range(leaf.field)
            if rng is not None:
                try:
                    check_value(rng, leaf.key, leaf.value, optional=leaf.optional)
                except ConfigError as exc:
                    pytest.fail(f"{name} {label}: {exc}")


@pytest.mark.parametrize("name", CLASSES)
def test_every_config_class_refuses_an_out_of_range_value_built_in_python(name: str) -> None:
    """``check_ranges`` is called by each class's ``__post_init__``: ``replace`` with a value
    past the range raises :class:`ConfigError` naming the field (or its element)."""
    tree = controller_config(name, False, preview=name in KD_FAMILY)
    for leaf in _leaves(tree):
        rng = field_range(leaf.field)
        if rng is None:
            continue
        field_name = leaf.field.name
        with pytest.raises(ConfigError) as exc:
            replace(leaf.owner, **{field_name: _outside(rng, leaf.value)})
        assert exc.value.field.startswith(field_name), (leaf.key, exc.value)


def _outside(rng: Range, value: Any) -> Any:
    """A value of the field's shape just past ``rng`` (an int where the range is of ints)."""
    step = max(1.0, abs(rng.hi))
    bad = rng.hi + (int(step) if isinstance(rng.hi, int) and isinstance(rng.lo, int) else step)
    if isinstance(value, tuple):
        return (bad, *value[1:])
    if value is None and rng.ordered:
        return (rng.lo, bad)
    return bad


@pytest.mark.parametrize("name", CONFIGURED)
def test_str_fields_with_choices_refuse_junk(name: str) -> None:
    keys = [leaf.key for leaf in _leaves(_default(name)) if leaf.type is str]
    assert keys
    for key in keys:
        if key not in FREE_TEXT:
            with pytest.raises(ConfigError) as exc:
                controller_config(name, False, overrides=(f"{key}=no-such-choice",))
            assert exc.value.field.endswith(key.rsplit(".", 1)[-1]), exc.value


def test_the_control_tick_is_the_simulators_timestep() -> None:
    from gaitnet_mpc.robots import load_robot
    from gaitnet_mpc.sim.simulator import SimConfig

    assert SimConfig().timestep_s == CONTROL_TICK_S
    for robot in ("humanoid3d", "biped2d"):
        assert load_robot(robot).mj_model.opt.timestep == CONTROL_TICK_S


# --------------------------------------------------------------------------- (b) the issue
ISSUE_CASES = [
    (
        "foothold_margin_m=10",
        "foothold_margin_m: got 10, expected a margin in [0, 0.09] m (under half the shortest "
        "built-in stone, 0.18 m)",
    ),
    (
        "replan_period_s=0",
        "replan_period_s: got 0, expected a period in [0.001, 1] s (at least one 1 kHz control "
        "tick",
    ),
    (
        "sequential.dt_bounds_s=[0.07,0.04]",
        "sequential.dt_bounds_s: got [0.07, 0.04], expected (min, max) with min <= max, each a "
        "sampling time in [0.03, 0.2] s (",
    ),
    (
        "dt_policy.bounds_s=[0.07, 0.04]",
        "dt_policy.bounds_s: got [0.07, 0.04], expected None or (min, max) with min <= max",
    ),
    (
        "dt_policy.drawn_step_range_s=[0.4, 0.15]",
        "dt_policy.drawn_step_range_s: got [0.4, 0.15], expected (min, max) with min <= max",
    ),
]


@pytest.mark.parametrize(("item", "message"), ISSUE_CASES)
def test_the_issues_inputs_are_refused_by_apply(item: str, message: str) -> None:
    with pytest.raises(ConfigError) as exc:
        apply(_default("kd"), parse_overrides([item]), "--set ")
    assert str(exc.value) == f"--set {message}" or str(exc.value).startswith(f"--set {message}")


@pytest.mark.parametrize("name", KD_FAMILY)
@pytest.mark.parametrize(("item", "message"), ISSUE_CASES)
def test_the_issues_inputs_are_refused_by_the_registry(name: str, item: str, message: str) -> None:
    with pytest.raises(ConfigError) as exc:
        controller_config(name, False, overrides=(item,))
    assert str(exc.value).startswith(f"--set {message}")


@pytest.mark.parametrize("key", ["mass_kg", "toe_m", "heel_m", "min_foot_separation_m"])
def test_a_setting_the_controller_takes_from_the_robot_is_refused(key: str) -> None:
    with pytest.raises(ConfigError) as exc:
        controller_config("kd", False, overrides=(f"sequential.kd.{key}=0.05",))
    assert exc.value.field == f"--set sequential.kd.{key}"
    assert "takes it from the robot" in exc.value.expected


@pytest.mark.parametrize(
    ("items", "key"),
    [
        (("dt_policy.bounds_s=[0.03, 0.1]",), "dt_policy.bounds_s"),
        (("dt_policy.dt_s=0.03",), "dt_policy.dt_s"),
    ],
)
def test_dt_policy_outside_the_schedules_bounds_is_refused(items: tuple[str], key: str) -> None:
    narrow = "sequential.dt_bounds_s=[0.045, 0.07]"
    with pytest.raises(ConfigError) as exc:
        controller_config("gaitnet", False, overrides=(*items, narrow))
    assert exc.value.field == f"--set {key}"
    assert "within sequential.dt_bounds_s [0.045, 0.07] s" in exc.value.expected
    ok = controller_config("gaitnet", False, overrides=("dt_policy.bounds_s=[0.05, 0.06]", narrow))
    assert ok.dt_policy.bounds_s == (0.05, 0.06)


def test_the_cli_prints_the_range_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x"
    argv = ["run", "--no-video", "--no-progress", "--out", str(out), "--controller", "kd"]
    rc = main([*argv, "--set", "foothold_margin_m=10"])
    assert rc == 2
    assert "foothold_margin_m: got 10, expected a margin in [0, 0.09] m" in capsys.readouterr().err
    assert not out.exists()  # refused before the run


@pytest.mark.parametrize(
    ("name", "item", "key"),
    [
        ("srbm", "replan_period_s=0", "replan_period_s"),
        ("srbm", "mpc.contact.fz_min_n=600", "mpc.contact.fz_min_n"),  # above fz_max_n
        ("srbm", "max_lateral_separation_m=0.05", "min_lateral_separation_m"),
        ("wbmpc", "mpc.weights.q_base=[1, 1, 1, 1, 1, -1]", "mpc.weights.q_base[5]"),
        ("wbmpc", "step_durations.seed=-1", "step_durations.seed"),
        ("kd", "low_level.ik_lookahead_s=0", "low_level.ik_lookahead_s"),  # it divides
        ("kd", "preview.min_width_m=0.5", "preview.min_width_m"),  # above max_width_m
    ],
)
def test_other_controllers_name_the_full_key(name: str, item: str, key: str) -> None:
    with pytest.raises(ConfigError) as exc:
        controller_config(name, False, overrides=(item,))
    assert exc.value.field == f"--set {key}"


# --------------------------------------------------------------------------- (c) fuzzing
def _keys(name: str) -> list[str]:
    cls = config_type(name)
    assert cls is not None
    return _all_keys(cls, "")


_TOML_JUNK = [
    "", "[", "]", "{", "{a = 1}", "[[1]]", '"x"', "'", "1979-05-27", "07:32:00", "none",
    "0x10", "0o7", "1_000", "+inf", "-inf", "nan", "-0.0", "1e400", "[1, 'a']", "[1, [2]]",
    "true", "false", "{}", "[]", "1 # c", "1\nv = 2", "\"\"\"a\"\"\"", "\\", "=", "==",
    "[" * 1200 + "]" * 1200, "{a = " * 600 + "1" + "}" * 600, "1" + "0" * 400,
]  # fmt: skip
_JUNK_KEYS = [
    "", ".", "a.", ".a", "sequential..kd", "sequential.kd.horizon.x", "preview.n_steps",
    "w_pose[0]", " replan_period_s", "replan_period_s ", "dt_policy.gaitnet.x", "mpc",
]  # fmt: skip
_numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**30), 10**30).map(str),
    st.sampled_from(["0", "-1", "1e-300", "1e308", "-1e308", "5e-324", "0.0001"]),
)
_values = st.one_of(
    _numbers,
    st.lists(_numbers, max_size=7).map(lambda xs: "[" + ", ".join(xs) + "]"),
    st.sampled_from(_TOML_JUNK),
    st.booleans().map(lambda b: str(b).lower()),
    st.text(max_size=20),
    st.text(max_size=10).map(repr),  # a quoted TOML string, often
)


def _outcome_is_a_config_or_a_config_error(name: str, items: list[str]) -> None:
    base = _default(name)
    try:
        config = apply(base, parse_overrides(items), "--set ")
    except ConfigError:
        return
    assert type(config) is type(base)
    for leaf in _leaves(config):  # what is accepted lies inside its range
        rng = field_range(leaf.field)
        if rng is not None:
            check_value(rng, leaf.key, leaf.value, optional=leaf.optional)


@settings(max_examples=200, deadline=None)
@given(data=st.data(), name=st.sampled_from(CLASSES))
def test_random_overrides_give_a_config_or_a_config_error(data: st.DataObject, name: str) -> None:
    key = st.one_of(st.sampled_from(_keys(name)), st.sampled_from(_JUNK_KEYS), st.text(max_size=8))
    item = st.one_of(
        st.tuples(key, _values).map(lambda kv: f"{kv[0]}={kv[1]}"),
        st.text(max_size=12),  # often no '=' at all
    )
    _outcome_is_a_config_or_a_config_error(name, data.draw(st.lists(item, min_size=1, max_size=3)))


def _corpus() -> list[str]:
    return [line for line in CORPUS.read_text().splitlines() if line.strip()]


@pytest.mark.parametrize("name", CLASSES)
@pytest.mark.parametrize("item", _corpus(), ids=lambda s: s[:40])
def test_corpus_overrides_give_a_config_or_a_config_error(item: str, name: str) -> None:
    _outcome_is_a_config_or_a_config_error(name, [item])


def test_a_config_file_nested_past_the_recursion_limit_is_a_config_error(tmp_path: Path) -> None:
    path = tmp_path / "deep.toml"
    path.write_text("v = " + "[" * 1200 + "]" * 1200 + "\n")
    with pytest.raises(ConfigError, match=r"--config: got .*deep\.toml"):
        read_toml(path)
