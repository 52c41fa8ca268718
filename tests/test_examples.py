"""The scripts of ``examples/`` run as a user would run them (short episodes)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(script: str, *args: str) -> str:
    cmd = [sys.executable, str(EXAMPLES / script), *args]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_step_loop() -> None:
    out = _run("step_loop.py", "--duration", "0.6")
    lines = out.splitlines()
    assert len(lines) == 2 + 12  # header, 12 lines of 50 ms, the outcome
    assert lines[-1].startswith("outcome: ok")


def test_gym_dt_policy() -> None:
    pytest.importorskip("gymnasium")
    out = _run("gym_dt_policy.py", "--duration", "0.8")
    assert "upright at t = 0.80 s" in out.splitlines()[-1]
