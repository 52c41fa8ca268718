"""A light install (issue 51, item 7): every data file the package loads is package data
(a non-editable ``pip install .`` has it), the CLI starts without the optional extras,
the extras are the ones the README names, and ``make demo`` installs no dev extras."""

from __future__ import annotations

import fnmatch
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "gaitnet_mpc"
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
#: What only the extras bring (and the test tools): never needed to run the controller.
OPTIONAL = ("torch", "ray", "gymnasium", "pytest", "mypy", "hypothesis", "ruff")


def _data_files() -> list[str]:
    """Every file under the package that is not Python source or a cache, relative to it."""
    return sorted(
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    )


def _matches(path: str, pattern: str) -> bool:
    """setuptools' glob: ``*`` stays inside one folder."""
    parts, pats = path.split("/"), pattern.split("/")
    return len(parts) == len(pats) and all(map(fnmatch.fnmatchcase, parts, pats))


def test_every_data_file_is_package_data() -> None:
    patterns = PYPROJECT["tool"]["setuptools"]["package-data"]["gaitnet_mpc"]
    files = _data_files()
    missed = [f for f in files if not any(_matches(f, p) for p in patterns)]
    assert not missed, f"not in [tool.setuptools.package-data]: {missed}"
    stale = [p for p in patterns if not any(_matches(f, p) for f in files)]
    assert not stale, f"package-data patterns matching nothing: {stale}"
    # what the code loads at run time: the robots, the presets, the shipped Gait-Net weights
    for kind in (".xml", ".toml", ".npz"):
        assert any(f.endswith(kind) for f in files), kind


def test_dependencies_and_extras() -> None:
    project = PYPROJECT["project"]
    base = " ".join(project["dependencies"])
    for name in (*OPTIONAL, "threadpoolctl"):
        assert name not in base, name
    extras = project["optional-dependencies"]
    assert set(extras) == {"train", "ray", "gym", "dev"}
    assert set(extras["train"] + extras["ray"] + extras["gym"]) <= set(extras["dev"])
    # a pinned package that nothing imports is not a dependency (threadpoolctl was one)
    sources = "\n".join(p.read_text() for p in PACKAGE.rglob("*.py"))
    assert "threadpoolctl" not in sources


def test_cli_starts_without_the_extras() -> None:
    """``gaitnet-mpc --help`` and every sub-command's ``--help`` import none of them."""
    code = (
        "import sys\n"
        "from gaitnet_mpc.cli.main import COMMANDS, main\n"
        "for argv in [['--help']] + [[c, '--help'] for c in COMMANDS]:\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        f"loaded = sorted({{m.split('.')[0] for m in sys.modules}} & set({OPTIONAL!r}))\n"
        "print('LOADED', loaded)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.splitlines()[-1] == "LOADED []"


def _make_dry_run(target: str, venv: Path) -> str:
    cmd = ["make", "-n", "-C", str(ROOT), target, f"VENV={venv}"]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_make_demo_installs_no_dev_extras_and_make_test_adds_them(tmp_path: Path) -> None:
    if subprocess.run(["make", "--version"], capture_output=True).returncode != 0:
        pytest.skip("no make")
    demo = _make_dry_run("demo", tmp_path / "venv")
    assert "pip install -q -e .\n" in demo and "[dev]" not in demo
    # after `make demo` (its stamp newer than pyproject.toml), `make test` adds the dev extra
    venv = tmp_path / "venv"
    venv.mkdir()
    (venv / ".installed-base").touch()
    test = _make_dry_run("test", venv)
    assert 'pip install -q -e ".[dev]"' in test and "pytest" in test
    again = _make_dry_run("demo", venv)
    assert "pip install" not in again  # the demo's install is up to date


def test_kernels_compile_where_no_cache_folder_can_be_written(tmp_path: Path) -> None:
    """A read-only install run by a user without a writable home: numba's
    ``cache=True`` refuses at import ("no locator available"); ``njit_cached`` compiles
    without a cache and warns instead."""
    (tmp_path / "__pycache__").write_text("")  # no cache folder beside the source
    (tmp_path / "kernel.py").write_text(
        "from gaitnet_mpc.jit import njit_cached\n\n\n"
        "@njit_cached()\n"
        "def twice(x):\n"
        "    return 2 * x\n"
    )
    blocked = tmp_path / "not-a-folder"
    blocked.write_text("")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(
        HOME=str(blocked),
        XDG_CACHE_HOME=str(blocked),
        PYTHONDONTWRITEBYTECODE="1",
        PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT / "src"), env.get("PYTHONPATH", "")]),
    )
    code = "import kernel; print(kernel.twice(21))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "42"
    assert "NUMBA_CACHE_DIR" in out.stderr
