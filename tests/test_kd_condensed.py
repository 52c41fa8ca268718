"""The condensed CMPC QP (:mod:`gaitnet_mpc.mpc.kd_condensed`) against the sparse one.

The condensed form eliminates the states, the swing feet's wrenches, the foot ties and
the fixed axes; its DAQP minimiser, expanded, must be the sparse QP's (PIQP) to the
solvers' tolerance and satisfy every row of the sparse QP. Checked on random
sub-problems (random iterates, schedules, bounds; every optional row kind) and on the
problems a walking controller builds.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.implicit_kd import KDConfig, KDIterate, KDSubproblem
from gaitnet_mpc.mpc.kd_condensed import KDCondensed
from gaitnet_mpc.runner.episode import run_episode
from gaitnet_mpc.scenario import build_episode, make_scenario
from test_perf_kd_fast_paths import MASS, random_case


def _agree(sub: KDSubproblem, ours: Any, ref: Any) -> None:
    """The condensed solution is the sparse QP's minimiser: feasible, the same objective
    (an exact active set is at least as low as the interior point), the same point to
    PIQP's accuracy (weakly determined wrench entries move most)."""
    assert ours.found and ref.found
    assert ours.primal_residual < 1e-8
    scale = max(1.0, abs(ref.obj))
    assert ref.obj - 1e-9 * scale <= ours.obj <= ref.obj + 1e-7 * scale
    a, b = sub.layout.unpack(ours.x), sub.layout.unpack(ref.x)
    for name in ("delta_p_foot", "delta_p_com"):
        np.testing.assert_allclose(a[name], b[name], atol=1e-4, err_msg=name)  # m
    for name in ("delta_f", "delta_tau"):
        np.testing.assert_allclose(a[name], b[name], atol=2e-2, err_msg=name)  # N, N m


@pytest.mark.parametrize(
    "extra",
    [
        {},
        {"min_foot_separation_m": 0.06},
        {"trust_region_com_m": 0.05, "trust_region_m": None},
        {"leg_reach_m": 0.45},
    ],
    ids=["default", "separation", "com-trust", "reach"],
)
def test_condensed_matches_sparse_on_random_subproblems(extra: dict[str, Any]) -> None:
    sparse = KDSubproblem(KDConfig(mass_kg=MASS, horizon=6, **extra))
    condensed = KDSubproblem(KDConfig(mass_kg=MASS, horizon=6, qp_form="condensed", **extra))
    assert condensed.condensed is not None
    schedules: set[bytes] = set()
    for seed in range(40):
        args, it = random_case(seed)
        inputs = sparse.inputs(it, **args)
        problem = sparse.build(it, inputs)
        ref = sparse.workspace.solve(problem)
        ours = _condensed_solution(condensed, it, inputs)
        if ref.status == "infeasible":  # random bounds can exclude each other
            assert ours.status == "infeasible"
            continue
        _agree(sparse, ours, ref)
        schedules.add(inputs.contact.tobytes())
    assert len(schedules) >= 10  # many contact schedules solved


def test_condensed_matches_sparse_with_an_external_wrench() -> None:
    """The affine term of eqs. 14-15 (the disturbance observer's wrench) enters both forms
    alike."""
    sparse = KDSubproblem(KDConfig(mass_kg=MASS, horizon=6))
    condensed = KDSubproblem(KDConfig(mass_kg=MASS, horizon=6, qp_form="condensed"))
    rng = np.random.default_rng(7)
    solved = 0
    for seed in range(12):
        args, it = random_case(seed)
        wrench = np.r_[rng.normal(scale=30.0, size=3), rng.normal(scale=5.0, size=3)]
        inputs = sparse.inputs(it, **args, wrench_ext=wrench)
        ref = sparse.workspace.solve(sparse.build(it, inputs))
        if ref.status == "infeasible":
            continue
        _agree(sparse, _condensed_solution(condensed, it, inputs), ref)
        solved += 1
    assert solved >= 6


def _condensed_solution(sub: KDSubproblem, it: KDIterate, inputs: Any) -> Any:
    """The condensed form's DAQP solution, on the sparse QP (for its objective and
    residual there)."""
    sol, _ = sub._solve_condensed(it, inputs)
    sol.problem = sub.build(it, inputs)
    return sol


def test_condensed_form_is_small() -> None:
    """h = 10 single support: the wrench of the stance foot per stage (6 x 10) and the
    swing foot's touchdown (x, y; its height comes from the reference)."""
    sub = KDSubproblem(KDConfig(mass_kg=MASS, qp_form="condensed"))
    contact = np.zeros((10, 2), dtype=bool)
    contact[:, 0] = True
    pc = np.tile([0.0, 0.0, 0.55], (11, 1))
    it = KDIterate.initial(pc[0], pc, np.zeros((10, 2, 3)), contact, MASS)
    inputs = sub.inputs(
        it, np.zeros(12), np.zeros((11, 6)), np.zeros((11, 6)), np.zeros((10, 2, 3)),
        np.zeros((11, 3)), np.full(10, 0.05), contact, np.zeros((10, 2)),
    )  # fmt: skip
    dense = sub.condensed_qp(it, inputs)
    assert dense.n_u == 62 and dense.qp["H"].shape == (62, 62)
    parts = dense.expand(np.zeros(62))
    assert sub.layout.pack(parts).shape == (sub.layout.n,)
    # u = 0 keeps the fixed stance foot at its measured place and the swing foot's wrench
    # at zero: the point the condensing fixes
    np.testing.assert_array_equal(parts["delta_f"][:, 1], -it.f[:, 1])
    np.testing.assert_array_equal(parts["delta_p_foot"][:, 0], 0.0)


def test_failed_condensed_solve_falls_back_to_the_sparse_qp() -> None:
    sub = KDSubproblem(KDConfig(mass_kg=MASS, horizon=6, qp_form="condensed"))
    assert sub.condensed is not None
    sub.condensed.options["iter_limit"] = 1  # DAQP stops before the optimum
    args, it = random_case(3)
    step = sub.solve(it, sub.inputs(it, **args))
    assert sub.n_fallbacks == 1
    assert step.solution.backend == "piqp" and step.solution.found


def test_unknown_qp_form_is_refused() -> None:
    with pytest.raises(ConfigError, match="qp_form"):
        KDConfig(qp_form="dense")


def test_condensed_matches_sparse_in_the_walking_loop() -> None:
    """Every QP that ``kd`` builds while walking 0.8 s on flat with the condensed form:
    the same minimiser as PIQP's, and the robot walks."""
    scenario = make_scenario(
        controller="kd", course="flat", vx_mps=0.75, duration_s=0.8,
        overrides=["sequential.kd.qp_form=condensed"],
    )  # fmt: skip
    episode = build_episode(scenario)
    sub: KDSubproblem = episode.controller.mpc.subproblem
    assert sub.condensed is not None
    solve = sub.solve
    n_checked = 0

    def checked(iterate: KDIterate, inputs: Any) -> Any:
        nonlocal n_checked
        step = solve(iterate, inputs)
        problem = sub.build(iterate, inputs)
        step.solution.problem = problem
        _agree(sub, step.solution, sub.workspace.solve(problem))
        n_checked += 1
        return step

    sub.solve = checked  # type: ignore[method-assign]
    summary = run_episode(episode.sim, episode.controller, scenario.command, 0.8, progress=False)
    assert n_checked > 20 and sub.n_fallbacks == 0
    assert not summary["fell"], summary["fall_reason"]
    assert summary["distance_m"] > 0.15  # from rest: 0.24 m in 0.8 s at 0.75 m/s


def test_daqp_missing_is_a_config_error(monkeypatch: pytest.MonkeyPatch) -> None:
    import gaitnet_mpc.mpc.kd_condensed as mod

    monkeypatch.setattr(mod, "daqp", None)
    with pytest.raises(ConfigError, match="daqp"):
        KDCondensed(KDConfig(mass_kg=MASS))
