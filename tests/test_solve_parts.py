"""``benchmarks/solve_parts.py`` times the parts of Algorithm 1 by wrapping them: on a short
episode every part is seen in the replans, the parts fit inside the solve, and the wrapped
methods are restored afterwards. (Tests assert no wall-clock shares.)"""

from __future__ import annotations

import importlib
from pathlib import Path

import pytest

from gaitnet_mpc.mpc import sequential

ROOT = Path(__file__).resolve().parents[1]


def test_solve_parts_times_every_part_and_restores_them(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    solve_parts = importlib.import_module("solve_parts")
    before = sequential.SequentialKDMPC._f_ik
    solves = solve_parts.measure(
        ["run", "--controller", "kd", "--course", "flat", "--vx", "0.5", "--duration", "0.3"]
    )
    assert sequential.SequentialKDMPC._f_ik is before
    assert solves["full"] and len(solves["replan"]) >= 5
    for solve in solves["replan"]:
        assert solve["QPs"] >= 1
        assert (solve["f_IK (line 9)"] > 0.0) == (solve["QPs"] > 1)  # line 9 between QPs
        assert solve["the rest of the solve"] >= 0.0  # the parts run inside the solve
    assert "| f_IK (line 9) |" in solve_parts.report(solves)
