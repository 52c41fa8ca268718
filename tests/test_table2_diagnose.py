"""Table II's profile (``table2/diagnose.py``): NLP sizes and the per-solve time split."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gaitnet_mpc.table2.diagnose import METHODS, SolveProfile, Structure, main
from gaitnet_mpc.table2.problems import (
    RecordingSpec,
    load_problems,
    record_run,
    save_problems,
)


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rec = record_run(RecordingSpec(course="flat", duration_s=0.5, skip_s=0.2))
    path = tmp_path_factory.mktemp("table2_diagnose") / "problems.npz"
    return save_problems(path, rec.problems[:1], ["flat"], cop_fraction=rec.cop_fraction)


@pytest.fixture(scope="module")
def report(saved: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("table2_profile") / "profile.md"
    assert main([str(saved), "--problems", "1", "--out", str(out)]) == 0
    return out


def test_profile_counts_the_built_nlps_and_splits_the_time(saved: Path, report: Path) -> None:
    rows = [json.loads(line) for line in report.with_suffix(".jsonl").read_text().splitlines()]
    structures = [Structure(**r) for r in rows if "problem" not in r]
    solves = [SolveProfile(**r) for r in rows if "problem" in r]
    # the point-test variant solves WBD-SQP's own NLPs
    assert [s.method for s in structures] == [m for m in METHODS if "point" not in m]
    assert [s.method for s in solves] == list(METHODS)
    h = int(load_problems(saved, 1)[0].problem.timing.dts_s.size)
    by = {s.method: s for s in structures}
    n_dt = by["explicit KD-SQP"].n_x - 64 * h
    assert 1 <= n_dt <= 3
    assert by["WBD-SQP"].n_x == 103 * h + n_dt
    assert by["CD-SQP"].n_x == by["CD-SQP (PIQP)"].n_x == 30 * h
    for s in structures:
        assert 0 < s.n_g and 0 < s.nnz_jac_g < s.n_x * s.n_g
        assert 0 < s.nnz_hess_l <= s.n_x * (s.n_x + 1) // 2
        assert s.build_s > 0.0
    for p in solves:
        assert p.n_qps >= 1 and p.time_s > 0.0
        # the split's parts are parts of the solve's wall time
        assert 0.0 < p.t_qp_s + p.t_hess_s + p.t_jac_s + p.t_callback_s <= 1.05 * p.time_s


def test_report_has_a_row_per_method(report: Path) -> None:
    text = report.read_text()
    assert text.startswith("Machine: ")
    assert "ms per QP iteration" in text
    for m in METHODS:
        assert f"| {m} | 1 |" in text
