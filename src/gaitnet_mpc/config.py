"""Controller settings from outside: TOML files, ``--set KEY=VALUE`` overrides, presets.

A controller's settings are a tree of frozen dataclasses (``KDWalkConfig``,
``SRBMWalkConfig``). A TOML table mirrors that tree: a key is a field, a sub-table a nested
dataclass (``[sequential.kd]``). A file may be partial; what it names replaces the value of
the config it is applied to (:func:`apply`), checked for its type (bool, int, float --
an integer is accepted --, str, tuple length, nested dataclass, Optional) and then by the
dataclasses' own ``__post_init__`` range checks. TOML has no null: ``"none"`` stands for
``None``, and a table for an Optional dataclass that is None starts from that class's
defaults. A ``tuple[tuple[str, Any], ...]`` field (``qp_options``) is a table of options.

Presets are partial files shipped in ``gaitnet_mpc/presets/``: ``<controller>-<name>.toml``
over the config class's defaults, then ``<controller>-<name>.planar.toml`` on top for a
planar robot when it exists. :func:`dumps` writes a whole config back, so a run's
``config.toml`` read with :func:`apply` gives the same config again.

Reading is :mod:`tomllib`, writing ``tomli-w``. The typed conversion is written out here:
converters such as ``dacite`` build from class defaults (not over a preset), accept a bool
where an int is expected, and have no ``"none"``; here each error is a
:class:`ConfigError` naming the full key, the value and what was expected.
"""

from __future__ import annotations

import difflib
import tomllib
import types
import typing
from dataclasses import fields, is_dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, cast

import tomli_w

from gaitnet_mpc.errors import ConfigError

#: How ``None`` is written in a TOML config (TOML has no null).
NONE = "none"

_PRESETS = resources.files("gaitnet_mpc") / "presets"


# --------------------------------------------------------------------------- reading
def read_toml(path: str | Path, field: str = "--config") -> dict[str, Any]:
    """The tables of a TOML file; :class:`ConfigError` if it is missing or not TOML."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise ConfigError(field, str(path), f"a readable TOML file ({exc.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(field, str(path), f"a valid UTF-8 TOML file ({exc})") from None


def parse_overrides(items: typing.Iterable[str]) -> dict[str, Any]:
    """``["a.b=1", "a.c=x"]`` -> ``{"a": {"b": 1, "c": "x"}}``.

    A value is read as a TOML value (``1e-3``, ``true``, ``[1, 2]``, ``"lip"``), else
    kept as the bare string (``lip``, ``none``).
    """
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        parts = key.strip().split(".")
        if not sep or not all(parts) or not text.strip():
            expected = "KEY=VALUE with a dotted KEY, e.g. sequential.kd.w_force=1e-3"
            raise ConfigError("--set", item, expected)
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        node = out
        for i, part in enumerate(parts[:-1]):
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ConfigError("--set", item, f"{'.'.join(parts[: i + 1])} set only once")
        node[parts[-1]] = value
    return out


def preset_names(controller: str) -> list[str]:
    """Names of the presets shipped for ``controller``."""
    prefix = f"{controller}-"
    return sorted(
        p.name[len(prefix) : -len(".toml")]
        for p in _PRESETS.iterdir()
        if p.name.startswith(prefix) and p.name.endswith(".toml") and ".planar." not in p.name
    )


def load_preset(cls: type, controller: str, name: str, planar: bool) -> Any:
    """``cls()`` with the preset file ``<controller>-<name>.toml`` (and for a planar robot
    ``<controller>-<name>.planar.toml`` where it exists) applied."""
    if name not in preset_names(controller):
        expected = f"one of {preset_names(controller)} for the {controller} controller"
        raise ConfigError("--preset", name, expected)
    config = cls()
    stems = [f"{controller}-{name}"] + ([f"{controller}-{name}.planar"] if planar else [])
    for stem in stems:
        path = _PRESETS / f"{stem}.toml"
        if path.is_file():
            config = apply(config, tomllib.loads(path.read_text()), f"preset {stem}.toml: ")
    return config


# --------------------------------------------------------------------------- applying
def apply(config: Any, data: dict[str, Any], label: str = "") -> Any:
    """``config`` with the (partial) table ``data`` applied; errors name ``label`` + key."""
    try:
        return _merge(config, data, "")
    except ConfigError as exc:
        raise ConfigError(label + exc.field, exc.value, exc.expected) from None


def _merge(obj: Any, data: Any, prefix: str) -> Any:
    cls = type(obj)
    if not isinstance(data, dict):
        raise ConfigError(prefix.rstrip(".") or "config", data, f"a table of {cls.__name__}")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in fields(obj) if f.init]
    changes = {}
    for key, raw in data.items():
        if key not in names:
            raise ConfigError(prefix + key, raw, _unknown_key(cls, prefix, key))
        changes[key] = _convert(hints[key], raw, getattr(obj, key), prefix + key)
    try:
        return replace(obj, **changes)
    except ConfigError as exc:  # a __post_init__ check names the bare field
        raise ConfigError(prefix + exc.field, exc.value, exc.expected) from None


def _convert(tp: Any, raw: Any, current: Any, key: str) -> Any:
    """``raw`` (from TOML) as a value of type ``tp``; ``current`` is the value it replaces."""
    args = typing.get_args(tp)
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        (inner,) = (a for a in args if a is not type(None))
        if raw == NONE:
            return None
        if is_dataclass(inner) and current is None:
            current = cast(type, inner)()  # a class: an argument of a type hint
        return _convert(inner, raw, current, key)
    if is_dataclass(tp):
        return _merge(current, raw, key + ".")
    if tp is Any:
        return raw
    if tp is bool:
        if isinstance(raw, bool):
            return raw
        raise ConfigError(key, raw, "true or false")
    if tp is int:
        if isinstance(raw, int) and not isinstance(raw, bool):
            return raw
        raise ConfigError(key, raw, "an integer")
    if tp is float:
        if isinstance(raw, int | float) and not isinstance(raw, bool):
            return float(raw)
        raise ConfigError(key, raw, "a number")
    if tp is str:
        if isinstance(raw, str):
            return raw
        raise ConfigError(key, raw, "a string")
    if typing.get_origin(tp) is tuple:
        if _is_options(tp):
            if not isinstance(raw, dict):
                raise ConfigError(key, raw, "a table of options (NAME = VALUE)")
            return tuple(raw.items())
        variadic = len(args) == 2 and args[1] is Ellipsis
        if not isinstance(raw, list) or not (variadic or len(raw) == len(args)):
            n = "" if variadic else f"{len(args)} "
            raise ConfigError(key, raw, f"a list of {n}{_name(args[0])} values")
        elem = [args[0]] * len(raw) if variadic else list(args)
        pairs = enumerate(zip(elem, raw, strict=True))
        return tuple(_convert(t, v, None, f"{key}[{i}]") for i, (t, v) in pairs)
    raise TypeError(f"{key}: type {tp} is not supported in a TOML config")


def _is_options(tp: Any) -> bool:
    """Whether ``tp`` is ``tuple[tuple[str, Any], ...]`` (named options)."""
    args = typing.get_args(tp)
    return len(args) == 2 and args[1] is Ellipsis and typing.get_args(args[0]) == (str, Any)


def _name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def _unknown_key(cls: type, prefix: str, key: str) -> str:
    """What was expected instead of an unknown key, with the closest keys of the tree."""
    keys = _all_keys(cls, prefix)
    close = difflib.get_close_matches(prefix + key, keys, n=3, cutoff=0.6)
    close += [k for k in keys if k.endswith("." + key) and k not in close]
    where = f"a field of {cls.__name__}"
    if close:
        return f"{where}; close matches: {', '.join(close)}"
    return f"{where}: one of {', '.join(f.name for f in fields(cls) if f.init)}"


def _all_keys(cls: type, prefix: str) -> list[str]:
    """Every dotted key of the dataclass tree of ``cls``."""
    out = []
    hints = typing.get_type_hints(cls)
    for f in fields(cls):
        if not f.init:
            continue
        out.append(prefix + f.name)
        for t in (hints[f.name], *typing.get_args(hints[f.name])):
            if is_dataclass(t):
                out += _all_keys(cast(type, t), f"{prefix}{f.name}.")  # a hint: a class
    return out


# --------------------------------------------------------------------------- writing
def to_table(config: Any) -> dict[str, Any]:
    """The whole config as TOML-ready nested dicts (``None`` as ``"none"``)."""
    hints = typing.get_type_hints(type(config))
    return {
        f.name: _to_toml(hints[f.name], getattr(config, f.name)) for f in fields(config) if f.init
    }


def _to_toml(tp: Any, value: Any) -> Any:
    if value is None:
        return NONE
    if is_dataclass(value):
        return to_table(value)
    if isinstance(value, tuple):
        return dict(value) if _is_options(tp) else list(value)
    return value


def dumps(config: Any, header: str = "") -> str:
    """TOML text of the whole ``config``, after ``header`` lines written as comments."""
    comment = "".join(f"# {line}".rstrip() + "\n" for line in header.splitlines())
    return comment + tomli_w.dumps(to_table(config))
