"""Fast paths of the kino-dynamic MPC against straightforward references.

* :meth:`KDSubproblem.build` (vectorised, precomputed scatter positions) against a dense,
  stage-by-stage assembly written directly from the equations of
  :mod:`gaitnet_mpc.mpc.implicit_kd` (eqs. 14, 15, 18-24), on random iterates, contact
  schedules, stage lengths, foot yaws and foothold bounds.
* The PIQP workspace's in-place update path (cached position maps, only changed
  matrices sent) against a fresh one-shot solve of every problem of a sequence.
* The position maps of :class:`EntrySelection` against SciPy's ``triu`` and row slicing.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

from gaitnet_mpc.geometry import skew
from gaitnet_mpc.mpc.centroidal_model import N_FEET, NX
from gaitnet_mpc.mpc.contact import foot_wrench_constraints
from gaitnet_mpc.mpc.foot_ties import next_touchdown_mask, tie_groups
from gaitnet_mpc.mpc.implicit_kd import KDConfig, KDIterate, KDSubproblem
from gaitnet_mpc.mpc.qp import QPProblem, QPSolution, make_workspace
from gaitnet_mpc.mpc.qp.structure import EntrySelection, canonical_csc, triu_csc

H = 6
MASS = 16.0
FREE_TIE_M = 1e3


def random_case(seed: int) -> tuple[dict[str, Any], KDIterate]:
    """Random but plausible sub-problem inputs: a walking-like contact schedule."""
    rng = np.random.default_rng(seed)
    contact = np.ones((H, 2), dtype=bool)
    swing_foot = int(rng.integers(2))
    start, stop = sorted(rng.choice(np.arange(H + 1), size=2, replace=False))
    contact[start:stop, swing_foot] = False
    if rng.random() < 0.5:  # a second swing of the other foot after the first
        contact[stop + 1 :, 1 - swing_foot] = False
    pc = np.array([0.0, 0.0, 0.55]) + np.cumsum(rng.normal(0.02, 0.01, (H + 1, 3)), axis=0)
    bounds = None
    if rng.random() < 0.7:
        bounds = {
            "left": (np.array([0.1, -np.inf, -0.01]), np.array([0.3, np.inf, 0.01]), None),
            "right": (None, np.array([0.4, 0.0, np.inf]), rng.random(H) < 0.5),
        }
    args = {
        "x0": rng.normal(size=NX),
        "h_ref": rng.normal(size=(H + 1, 6)),
        "H_ref": rng.normal(size=(H + 1, 6)),
        "p_foot_ref": rng.normal(scale=0.2, size=(H, 2, 3)),
        "p_com_ref": pc + rng.normal(scale=0.01, size=(H + 1, 3)),
        "dts_s": rng.uniform(0.03, 0.07, size=H),
        "contact": contact,
        "foot_yaw_rad": rng.choice([0.0, 0.2, -0.4], size=(H, 2)),
        "foothold_bounds": bounds,
        "p_foot_measured": rng.normal(scale=0.2, size=(2, 3)),
    }
    it = KDIterate(
        f=rng.normal(scale=40.0, size=(H, 2, 3)),
        tau=rng.normal(scale=2.0, size=(H, 2, 3)),
        p_foot=rng.normal(scale=0.2, size=(H, 2, 3)),
        p_com=pc,
    )
    return args, it


#: Variables per stage block of the CMPC QP (``implicit_kd`` module docstring):
#: ``x_k`` (12), ``dpc_k`` (3), then ``df``, ``dtau``, ``dpf`` (3 per foot each).
NS = NX + 3 + 9 * N_FEET


def ix(k: int) -> int:
    """Column of ``x_k`` (12 entries), ``k = 0 .. h``."""
    return NS * k


def ipc(k: int) -> int:
    """Column of ``delta p_c,k`` (3), ``k = 0 .. h``."""
    return NS * k + NX


def i_f(k: int, i: int) -> int:
    """Column of ``delta f_i,k`` (3)."""
    return NS * k + NX + 3 + 3 * i


def i_tau(k: int, i: int) -> int:
    """Column of ``delta tau_i,k`` (3)."""
    return i_f(k, i) + 3 * N_FEET


def i_pf(k: int, i: int) -> int:
    """Column of ``delta p_f,i,k`` (3)."""
    return i_f(k, i) + 6 * N_FEET


def dense_reference(sub: KDSubproblem, args: dict[str, Any], it: KDIterate) -> dict[str, Any]:
    """The CMPC QP assembled stage by stage into dense arrays (module docstring)."""
    c = sub.config
    n, h = sub.n, sub.horizon
    dts, contact = args["dts_s"], args["contact"]
    a_eq = np.zeros((sub.m_eq, n))
    b_eq = np.zeros(sub.m_eq)
    a_eq[:NX, ix(0) : ix(0) + NX] = np.eye(NX)
    b_eq[:NX] = args["x0"]
    a_eq[NX : NX + 3, ipc(0) : ipc(0) + 3] = np.eye(3)
    for k in range(h):
        dt, row = dts[k], 15 + 15 * k
        x, x1, pc, pc1 = ix(k), ix(k + 1), ipc(k), ipc(k + 1)
        a_eq[row : row + NX, x1 : x1 + NX] += np.eye(NX)
        a_eq[row : row + NX, x : x + NX] -= np.eye(NX)
        a_eq[row : row + 6, x + 6 : x + 12] -= dt * np.eye(6)  # H_{k+1} = H_k + h_k dt
        rl, rk, rc = row + 6, row + 9, row + 12
        torque = np.zeros(3)
        for i in range(N_FEET):
            f_i, arm = it.f[k, i], it.p_foot[k, i] - it.p_com[k]
            fi, ti, pi = i_f(k, i), i_tau(k, i), i_pf(k, i)
            a_eq[rl : rl + 3, fi : fi + 3] -= dt * np.eye(3)  # eqs. 14, 19
            a_eq[rk : rk + 3, ti : ti + 3] -= dt * np.eye(3)  # eq. 15: dtau
            a_eq[rk : rk + 3, pi : pi + 3] += dt * skew(f_i)  # -f x dpf
            a_eq[rk : rk + 3, pc : pc + 3] -= dt * skew(f_i)  # +f x dpc
            a_eq[rk : rk + 3, fi : fi + 3] -= dt * skew(arm)  # r x df
            torque += np.cross(arm, f_i) + it.tau[k, i]
        weight = np.array([0.0, 0.0, -MASS * c.gravity_mps2])
        b_eq[rl : rl + 3] = dt * (it.f[k].sum(axis=0) + weight)
        b_eq[rk : rk + 3] = dt * torque
        a_eq[rc : rc + 3, pc1 : pc1 + 3] += np.eye(3)  # eq. 20
        a_eq[rc : rc + 3, pc : pc + 3] -= np.eye(3)
        a_eq[rc : rc + 3, x + 6 : x + 9] -= dt / MASS * np.eye(3)
        b_eq[rc : rc + 3] = it.p_com[k] - it.p_com[k + 1]

    mw = sub.n_wrench_rows
    a_in = np.zeros((sub.m_ineq, n))
    lo, hi = np.zeros(sub.m_ineq), np.zeros(sub.m_ineq)
    for k in range(h):
        for i in range(N_FEET):
            cm, l_, u_ = foot_wrench_constraints(
                float(args["foot_yaw_rad"][k, i]), c.contact, c.toe_m, c.heel_m, True
            )
            rows = slice((k * N_FEET + i) * mw, (k * N_FEET + i + 1) * mw)
            a_in[rows, i_f(k, i) : i_f(k, i) + 3] = cm[:, :3]
            a_in[rows, i_tau(k, i) : i_tau(k, i) + 3] = cm[:, 3:]
            shift = cm @ np.r_[it.f[k, i], it.tau[k, i]]
            lo[rows], hi[rows] = (l_ - shift, u_ - shift) if contact[k, i] else (-shift, -shift)
    tie0 = N_FEET * h * mw
    for k in range(h - 1):
        for i in range(N_FEET):
            rows = slice(tie0 + (k * N_FEET + i) * 3, tie0 + (k * N_FEET + i + 1) * 3)
            a_in[rows, i_pf(k + 1, i) : i_pf(k + 1, i) + 3] = np.eye(3)
            a_in[rows, i_pf(k, i) : i_pf(k, i) + 3] = -np.eye(3)
            if contact[k, i] and not contact[k + 1, i]:
                lo[rows], hi[rows] = -FREE_TIE_M, FREE_TIE_M
            else:
                lo[rows] = hi[rows] = it.p_foot[k, i] - it.p_foot[k + 1, i]

    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    for i, foot in enumerate(("left", "right")):
        entry = None if args["foothold_bounds"] is None else args["foothold_bounds"][foot]
        mask = None
        if entry is not None:
            mask = next_touchdown_mask(contact[:, i]) if entry[2] is None else entry[2]
        groups = tie_groups(contact[:, i])
        for g in np.unique(groups):
            stages = np.flatnonzero(groups == g)
            if g == 0 and contact[0, i]:
                lo_abs = hi_abs = args["p_foot_measured"][i]
            else:
                lo_abs, hi_abs = np.full(3, -np.inf), np.full(3, np.inf)
                if mask is not None and mask[stages].any():
                    assert entry is not None
                    lo_abs = np.full(3, -np.inf) if entry[0] is None else entry[0].copy()
                    hi_abs = np.full(3, np.inf) if entry[1] is None else entry[1].copy()
                if not (np.isfinite(lo_abs[2]) and np.isfinite(hi_abs[2])):
                    stance = stages[contact[stages, i]]
                    z = args["p_foot_ref"][stance if stance.size else stages, i, 2].mean()
                    lo_abs[2] = hi_abs[2] = z
                centre = it.p_foot[stages, i].mean(axis=0)
                t_lo = np.maximum(lo_abs, centre - c.trust_region_m)
                t_hi = np.minimum(hi_abs, centre + c.trust_region_m)
                ok = t_lo <= t_hi
                lo_abs, hi_abs = np.where(ok, t_lo, lo_abs), np.where(ok, t_hi, hi_abs)
            for k in stages:
                col = i_pf(int(k), i)
                lb[col : col + 3] = lo_abs - it.p_foot[k, i]
                ub[col : col + 3] = hi_abs - it.p_foot[k, i]

    w = np.zeros(n)
    q = np.zeros(n)
    for k in range(1, h + 1):
        x, pc = ix(k), ipc(k)
        w[x : x + 6], w[x + 6 : x + 12] = c.w_pose, c.w_momentum
        w[pc : pc + 3] = np.asarray(c.w_p_com) + c.reg_position
        q[x : x + 6] = -2.0 * np.asarray(c.w_pose) * args["H_ref"][k]
        q[x + 6 : x + 12] = -2.0 * np.asarray(c.w_momentum) * args["h_ref"][k]
        q[pc : pc + 3] = 2.0 * np.asarray(c.w_p_com) * (it.p_com[k] - args["p_com_ref"][k])
    w[ipc(0) : ipc(0) + 3] = c.reg_position
    for k in range(h):
        for i in range(N_FEET):
            fi, ti, pi = i_f(k, i), i_tau(k, i), i_pf(k, i)
            w[fi : fi + 3] = c.w_force + c.reg_force
            w[ti : ti + 3] = c.w_moment + c.reg_moment
            w[pi : pi + 3] = np.asarray(c.w_p_foot) + c.reg_position
            q[fi : fi + 3] = 2.0 * c.w_force * it.f[k, i]
            q[ti : ti + 3] = 2.0 * c.w_moment * it.tau[k, i]
            err = it.p_foot[k, i] - args["p_foot_ref"][k, i]
            q[pi : pi + 3] = 2.0 * np.asarray(c.w_p_foot) * err
    return {
        "P": np.diag(2.0 * w), "q": q, "A_eq": a_eq, "b_eq": b_eq, "A": a_in,
        "l": lo, "u": hi, "lb": lb, "ub": ub,
    }  # fmt: skip


@pytest.fixture(scope="module")
def sub() -> KDSubproblem:
    return KDSubproblem(KDConfig(horizon=H, mass_kg=MASS))


@pytest.mark.parametrize("seed", range(8))
def test_fast_assembly_matches_dense_reference(sub: KDSubproblem, seed: int) -> None:
    args, it = random_case(seed)
    problem = sub.build(it, sub.inputs(it, **args))
    ref = dense_reference(sub, args, it)
    for name in ("P", "A_eq", "A"):
        np.testing.assert_allclose(getattr(problem, name).toarray(), ref[name], atol=1e-12)
    for name in ("q", "b_eq", "l", "u", "lb", "ub"):
        np.testing.assert_allclose(getattr(problem, name), ref[name], rtol=1e-12, atol=1e-12)


def test_pattern_is_the_same_for_every_case(sub: KDSubproblem) -> None:
    first = sub.build(random_case(0)[1], sub.inputs(random_case(0)[1], **random_case(0)[0]))
    for seed in range(1, 4):
        args, it = random_case(seed)
        other = sub.build(it, sub.inputs(it, **args))
        for name in ("P", "A_eq", "A"):
            a, b = getattr(first, name), getattr(other, name)
            assert a.has_canonical_format and b.has_canonical_format
            assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)


def test_updated_piqp_workspace_matches_fresh_solves() -> None:
    """One workspace over a sequence (setup once, then in-place updates, foot yaws and so
    the wrench rows changing in between) against a fresh workspace per problem."""
    sub = KDSubproblem(KDConfig(horizon=H, mass_kg=MASS))
    for seed in range(6):
        args, it = random_case(seed)
        args["p_foot_measured"] = it.p_foot[0]  # feasible: the stance foot stays put
        args["foothold_bounds"] = None
        problem = sub.build(it, sub.inputs(it, **args))
        updated = sub.workspace.solve(problem)
        fresh = make_workspace("piqp", **dict(sub.workspace.options)).solve(problem)
        assert updated.status == fresh.status
        if fresh.found:
            assert updated.x is not None and fresh.x is not None
            np.testing.assert_allclose(updated.x, fresh.x, rtol=1e-7, atol=1e-7)
            assert updated.primal_residual == pytest.approx(
                problem.primal_residual(fresh.x), abs=1e-6
            )
            assert updated.obj == pytest.approx(problem.objective(updated.x))
    assert sub.workspace.n_setups == 1 and sub.workspace.n_updates == 5


def test_piqp_dropped_rows_follow_value_changes() -> None:
    """Rows with two infinite bounds are dropped through a cached row map; the kept rows'
    values still reach PIQP when they change."""
    rng = np.random.default_rng(3)
    n, m = 8, 6
    P = sp.csc_matrix(np.eye(n) * 2.0)
    A = sp.csc_matrix(rng.normal(size=(m, n)) * (rng.random((m, n)) < 0.6))
    l, u = -np.ones(m), np.ones(m)
    l[[1, 4]], u[[1, 4]] = -np.inf, np.inf
    ws = make_workspace("piqp")
    for k in range(3):
        A_k = A.copy()
        A_k.data = A.data * (1.0 + 0.3 * k)
        problem = QPProblem(P, rng.normal(size=n) * 3.0, A=A_k, l=l, u=u)
        got = ws.solve_or_raise(problem)
        ref = make_workspace("piqp").solve_or_raise(problem)
        assert got.x is not None and ref.x is not None
        np.testing.assert_allclose(got.x, ref.x, atol=1e-8)
    assert (ws.n_setups, ws.n_updates) == (1, 2)


@pytest.mark.parametrize("seed", range(3))
def test_entry_selection_matches_scipy(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dense = rng.normal(size=(9, 9)) * (rng.random((9, 9)) < 0.4)
    dense = dense + dense.T
    sym = canonical_csc(dense)
    tri = EntrySelection.upper_triangle(sym)
    expected = triu_csc(sym)
    got = tri.matrix(sym.data[tri.positions])
    assert np.array_equal(got.indptr, expected.indptr)
    assert np.array_equal(got.indices, expected.indices)
    np.testing.assert_array_equal(got.data, expected.data)
    keep = rng.random(9) < 0.5
    rows = EntrySelection.rows(sym, keep)
    expected = canonical_csc(sym[np.flatnonzero(keep)])
    got = rows.matrix(sym.data[rows.positions])
    assert got.shape == expected.shape
    np.testing.assert_array_equal(got.toarray(), expected.toarray())
    assert np.array_equal(got.indices, expected.indices)


def test_solution_objective_and_residual_are_evaluated_on_demand() -> None:
    """Workspaces leave ``obj``/``primal_residual`` to the first read (then cached);
    values given to the constructor are kept as they are."""
    problem = QPProblem(np.eye(2), [1.0, 2.0], A=[[1.0, 1.0]], l=[0.0])
    sol = make_workspace("piqp").solve_or_raise(problem)
    assert sol.x is not None and "_obj" in sol.__dict__ and sol.__dict__["_obj"] is None
    assert sol.obj == problem.objective(sol.x)
    assert sol.primal_residual == problem.primal_residual(sol.x)
    assert sol.__dict__["_obj"] == sol.obj  # cached
    given = QPSolution(sol.x, "solved", True, 1, 0.0, "piqp", 3.0, 0.5, "ok", problem)
    assert (given.obj, given.primal_residual) == (3.0, 0.5)
    bare = QPSolution(None, "infeasible", False, 0, 0.0, "piqp", problem=problem)
    assert bare.obj is None and bare.primal_residual is None
