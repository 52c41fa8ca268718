"""Controller settings from outside: TOML files, ``--set KEY=VALUE`` overrides, presets.

A controller's settings are a tree of frozen dataclasses (``KDWalkConfig``,
``SRBMWalkConfig``). A TOML table mirrors that tree: a key is a field, a sub-table a nested
dataclass (``[sequential.kd]``). A file may be partial; what it names replaces the value of
the config it is applied to (:func:`apply`), checked for its type (bool, int, float --
an integer is accepted --, str, tuple length, nested dataclass, Optional), then against
the field's physical :class:`Range` and then by the dataclasses' own ``__post_init__``
checks (choices, cross-field constraints). TOML has no null: ``"none"`` stands for
``None``, and a table for an Optional dataclass that is None starts from that class's
defaults. A ``tuple[tuple[str, Any], ...]`` field (``qp_options``) is a table of options.

Presets are partial files shipped in ``gaitnet_mpc/presets/``: ``<controller>-<name>.toml``
over the config class's defaults, then ``<controller>-<name>.planar.toml`` on top for a
planar robot when it exists. :func:`dumps` writes a whole config back, so a run's
``config.toml`` read with :func:`apply` gives the same config again.

Ranges: every int, float and tuple-of-number field of a config reachable by ``--set`` is
declared with :func:`bounded`, which stores a :class:`Range` (bounds, unit, the reason) in
the field's metadata, next to the field (``bounded(0.02, "[0.001, 1] s", "a period",
"at least one control tick")``). :func:`apply` checks each value it sets against
it, naming the full dotted key; :func:`check_ranges`, called by the dataclasses'
``__post_init__``, refuses a config built in Python with a value outside. For a tuple
field the range applies to each element; an interval field (min, max) is ``ordered``.

Reading is :mod:`tomllib`, writing ``tomli-w``. The typed conversion is written out here:
converters such as ``dacite`` build from class defaults (not over a preset), accept a bool
where an int is expected, and have no ``"none"``; here each error is a
:class:`ConfigError` naming the full key, the value and what was expected.
"""

from __future__ import annotations

import collections.abc
import difflib
import math
import numbers
import re
import tomllib
import types
import typing
from dataclasses import Field, dataclass, field, fields, is_dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, cast

import tomli_w

from gaitnet_mpc.errors import ConfigError

#: How ``None`` is written in a TOML config (TOML has no null).
NONE = "none"

_PRESETS = resources.files("gaitnet_mpc") / "presets"


# --------------------------------------------------------------------------- ranges
@dataclass(frozen=True)
class Range:
    """The physical range of a number field, or of each element of a tuple field.

    Attributes:
        lo, hi: the bounds in ``unit`` (finite; included unless ``lo_open`` / ``hi_open``).
        unit: as written after a number (``"s"``, ``"N m/rad"``; ``""``: dimensionless).
        what: what the value is, with its article (``"a period"``, ``"an integer"``).
        reason: why the bounds are where they are, in a few words (shown in the error).
        ordered: the field is an interval (min, max): min <= max too (min = max pins it).
    """

    lo: float
    hi: float
    unit: str
    what: str
    reason: str
    lo_open: bool = False
    hi_open: bool = False
    ordered: bool = False

    def __post_init__(self) -> None:
        if not (-math.inf < self.lo <= self.hi < math.inf):
            raise ValueError(f"a Range needs finite bounds lo <= hi, got {self.lo}, {self.hi}")

    @classmethod
    def parse(cls, interval: str, what: str, reason: str, ordered: bool = False) -> Range:
        """``"[0.001, 1] s"``, ``"(0, 1]"``: bounds, open or closed ends and the unit."""
        m = _INTERVAL.fullmatch(interval.strip())
        if m is None:
            raise ValueError(f"not an interval like '[0, 1] s' or '(0, 1]': {interval!r}")
        left, lo, hi, right, unit = m.groups()
        lo_n, hi_n = (int(x) if re.fullmatch(r"-?\d+", x) else float(x) for x in (lo, hi))
        return cls(lo_n, hi_n, unit, what, reason, left == "(", right == ")", ordered)

    def contains(self, x: float) -> bool:
        """Whether ``x`` lies inside (False for NaN)."""
        above = self.lo < x if self.lo_open else self.lo <= x
        below = x < self.hi if self.hi_open else x <= self.hi
        return above and below

    def describe(self, optional: bool = False) -> str:
        """What is expected: ``a period in [0.001, 1] s (at least one control tick)``."""
        left, right = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
        unit = f" {self.unit}" if self.unit else ""
        text = f"{self.what} in {left}{_num(self.lo)}, {_num(self.hi)}{right}{unit}"
        if self.ordered:
            text = f"(min, max) with min <= max, each {text}"
        return ("None or " if optional else "") + f"{text} ({self.reason})"


#: The declared range of a seed field: numpy's seeds are non-negative integers (a signed
#: 64-bit one at most here).
SEED_INTERVAL = f"[0, {2**63 - 1}]"
SEED_REASON = "numpy's seeds are non-negative"

_INTERVAL = re.compile(r"([\[(])\s*([^,\s]+)\s*,\s*([^\]\)\s]+)\s*([\])])\s*(.*)")


def bounded(default: Any, interval: str, what: str, reason: str, ordered: bool = False) -> Any:
    """A dataclass field with ``default`` and its :class:`Range` (in the field's metadata)::

        replan_period_s: float = bounded(0.02, "[0.001, 1] s", "a period", "one tick at least")

    ``interval`` is written as in a text: ``[`` / ``]`` closed, ``(`` / ``)`` open ends,
    then the unit. A tuple default is immutable and used as is. Typed ``Any``, as
    :func:`dataclasses.field`, so that the annotation stays the field's type.
    """
    rng = Range.parse(interval, what, reason, ordered)
    return field(default=default, metadata={"range": rng})


def weight(default: Any) -> Any:
    """A cost weight's field (or a tuple of weights'): :func:`bounded` in ``[0, 1e9]``."""
    return bounded(default, "[0, 1e9]", "a weight", "a non-negative cost weight")


def check_value(
    rng: Range, key: str, value: Any, shown: Any = None, optional: bool = False
) -> None:
    """:class:`ConfigError` naming ``key`` unless ``value`` (a number, a tuple of numbers
    or, where ``optional``, None) lies in ``rng``; the error shows ``shown`` (the value as
    the user wrote it) where given, and names a tuple's element by its index."""
    shown = value if shown is None else shown
    if value is None and optional:
        return
    if _is_real(value):
        if not rng.contains(value):
            raise ConfigError(key, shown, rng.describe(optional))
        return
    if isinstance(value, str | bytes) or not isinstance(value, collections.abc.Iterable):
        raise ConfigError(key, shown, rng.describe(optional))
    items = list(value)
    raw_items = list(shown) if isinstance(shown, list | tuple) else items
    for i, x in enumerate(items):
        if not (_is_real(x) and rng.contains(x)):
            x_shown = raw_items[i] if len(raw_items) == len(items) else x
            raise ConfigError(f"{key}[{i}]", x_shown, rng.describe())
    if rng.ordered and not (len(items) == 2 and items[0] <= items[1]):
        raise ConfigError(key, shown, rng.describe(optional))


def check_ranges(obj: Any) -> None:
    """:class:`ConfigError` naming the field unless every field of the dataclass ``obj``
    declared with :func:`bounded` lies in its range (call it from ``__post_init__``)."""
    for name, rng, optional in _ranged_fields(type(obj)):
        check_value(rng, name, getattr(obj, name), optional=optional)


def field_range(f: Field[Any]) -> Range | None:
    """The :class:`Range` of a dataclass field (None: declared without one)."""
    rng = f.metadata.get("range")
    return rng if isinstance(rng, Range) else None


def _ranged_fields(cls: type) -> tuple[tuple[str, Range, bool], ...]:
    """(name, range, may be None) of each field of ``cls`` declared with :func:`bounded`
    (worked out once per class)."""
    if cls not in _RANGED:
        ranged = ((f.name, field_range(f), _optional(f)) for f in fields(cls))
        _RANGED[cls] = tuple((n, r, o) for n, r, o in ranged if r is not None)
    return _RANGED[cls]


_RANGED: dict[type, tuple[tuple[str, Range, bool], ...]] = {}


def _is_real(x: object) -> typing.TypeGuard[float]:
    """A real number (int, float, numpy scalar), not a bool."""
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _optional(f: Field[Any]) -> bool:
    """Whether the field's annotation admits None (``float | None``, ``Optional[...]``)."""
    text = str(f.type)
    return "None" in text or "Optional" in text


def _num(x: float) -> str:
    """``x`` as written in a range: ``0.001``, ``1``, ``1e9`` (an int in full)."""
    if isinstance(x, int) or (float(x).is_integer() and abs(x) < 1e6):
        return str(int(x))
    return f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


# --------------------------------------------------------------------------- reading
#: Largest settings / scenario TOML file read [bytes]: a whole ``config.toml`` is ~10 kB.
MAX_TOML_BYTES = 1 << 20


def read_toml(path: str | Path, field: str = "--config") -> dict[str, Any]:
    """The tables of a TOML file (a UTF-8 byte-order mark is skipped); :class:`ConfigError`
    if it is missing, larger than :data:`MAX_TOML_BYTES` (checked before reading) or not
    TOML."""
    try:
        size = Path(path).stat().st_size
        if size > MAX_TOML_BYTES:
            raise ConfigError(field, str(path), f"a TOML file of at most {MAX_TOML_BYTES} bytes")
        return tomllib.loads(Path(path).read_bytes().decode("utf-8-sig"))
    except OSError as exc:
        raise ConfigError(field, str(path), f"a readable TOML file ({exc.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(field, str(path), f"a valid UTF-8 TOML file ({exc})") from None
    except RecursionError:
        raise ConfigError(field, str(path), "a TOML file nested less deep") from None


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
        except (tomllib.TOMLDecodeError, RecursionError):  # nesting past the recursion limit
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
    by_name = {f.name: f for f in fields(obj) if f.init}
    changes = {}
    for key, raw in data.items():
        if key not in by_name:
            raise ConfigError(prefix + key, raw, _unknown_key(cls, prefix, key))
        value = _convert(hints[key], raw, getattr(obj, key), prefix + key)
        rng = field_range(by_name[key])
        if rng is not None:
            check_value(rng, prefix + key, value, raw, _optional(by_name[key]))
        changes[key] = value
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
            try:
                return float(raw)
            except OverflowError:  # an integer past 1.8e308
                raise ConfigError(key, raw, "a number within float range") from None
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
