"""The package's import graph: layers import only downward, and nothing imports in a
circle. Every import counts, including those inside functions and under TYPE_CHECKING."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import gaitnet_mpc

ROOT = Path(gaitnet_mpc.__file__).parent

#: The layers, lowest first: a module may import its own layer's and lower layers' modules.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "geometry", "jit", "machine", "state"),
    ("command", "config", "dt_policy", "parallel", "robots", "terrain"),
    ("dataset", "gait", "results", "sim"),
    ("kinematics",),
    ("mpc",),
    ("gaitnet",),
    ("control",),
    ("runner",),
    ("scenario",),
    ("experiments", "table2", "envs"),
    ("cli",),
)
#: Longest source file without a stated reason [lines].
MAX_LINES = 500


def _modules() -> dict[str, Path]:
    out = {}
    for path in ROOT.rglob("*.py"):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _imports(modules: dict[str, Path]) -> dict[str, set[str]]:
    """module -> the package modules it imports (``from pkg import submodule`` counts as
    the submodule, not the package)."""
    out: dict[str, set[str]] = defaultdict(set)
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("gaitnet_mpc"):
                assert node.module is not None
                subs = [f"{node.module}.{a.name}" for a in node.names]
                found = [s for s in subs if s in modules]
                out[name].update(found if len(found) == len(subs) else [node.module, *found])
            elif isinstance(node, ast.Import):
                out[name].update(a.name for a in node.names if a.name.startswith("gaitnet_mpc"))
    return out


def _layer(module: str) -> int:
    top = module.split(".")[1] if "." in module else ""
    for i, names in enumerate(LAYERS):
        if top in names:
            return i
    raise AssertionError(f"{module}: not in any layer of LAYERS (add it)")


def test_every_import_points_down_the_layers() -> None:
    modules = _modules()
    upward = [
        f"{src} -> {dst}"
        for src, dsts in _imports(modules).items()
        if src != "gaitnet_mpc"
        for dst in dsts
        if dst != "gaitnet_mpc" and _layer(dst) > _layer(src)
    ]
    assert not upward, upward


def test_no_module_imports_in_a_circle() -> None:
    modules = _modules()
    graph = _imports(modules)
    state: dict[str, int] = {}  # 1: on the path, 2: done
    cycles = []

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                cycles.append(" -> ".join([*path[path.index(nxt) :], nxt]))
            elif nxt not in state:
                visit(nxt, [*path, nxt])
        state[node] = 2

    for name in sorted(modules):
        if name not in state:
            visit(name, [name])
    assert not cycles, cycles


def test_long_modules_say_why() -> None:
    long = []
    for path in ROOT.rglob("*.py"):
        text = path.read_text()
        n = text.count("\n")
        doc = ast.get_docstring(ast.parse(text)) or ""
        if n > MAX_LINES and f"Over {MAX_LINES} lines" not in doc:
            long.append(f"{path.relative_to(ROOT)}: {n} lines")
    assert not long, long
