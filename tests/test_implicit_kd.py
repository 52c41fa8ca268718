"""Convex sub-problem of the implicit kino-dynamic MPC (paper Sec. IV-B, eqs. 10, 13-24)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.centroidal_model import NX, nonlinear_rollout, nonlinear_step
from gaitnet_mpc.mpc.contact import foot_wrench_constraints
from gaitnet_mpc.mpc.foot_ties import next_touchdown_mask, tie_groups
from gaitnet_mpc.mpc.implicit_kd import (
    KDConfig,
    KDIterate,
    KDStep,
    KDSubproblem,
    KDTolerances,
)

H = 10
MASS = 16.0
G = 9.81
INF = np.inf


def walking_problem(
    dts: np.ndarray | None = None, v: float = 0.4
) -> tuple[dict[str, Any], np.ndarray]:
    """Single-support walking: left stance 0-4 then swing, right swing 0-4 then stance."""
    dts = np.array([0.05] * 5 + [0.06] * 5) if dts is None else dts
    t = np.concatenate([[0.0], np.cumsum(dts)])
    contact = np.zeros((H, 2), dtype=bool)
    contact[:5, 0] = True
    contact[5:, 1] = True
    pc0 = np.array([0.0, 0.0, 0.55])
    p_com_ref = pc0 + np.outer(t, [v, 0.0, 0.0])
    h_ref = np.zeros((H + 1, 6))
    h_ref[:, 0] = MASS * v
    H_ref = np.zeros((H + 1, 6))
    H_ref[:, :3] = MASS * p_com_ref
    p_foot_ref = np.zeros((H, 2, 3))
    p_foot_ref[:5, 0] = [0.0, 0.08, 0.0]
    p_foot_ref[5:, 0] = [0.25, 0.08, 0.0]  # planned foothold of the next left step
    p_foot_ref[:, 1] = [0.12, -0.08, 0.0]  # planned foothold of the right step
    args = {
        "x0": np.r_[H_ref[0], h_ref[0]],
        "h_ref": h_ref,
        "H_ref": H_ref,
        "p_foot_ref": p_foot_ref,
        "p_com_ref": p_com_ref,
        "dts_s": dts,
        "contact": contact,
        "foot_yaw_rad": np.zeros((H, 2)),
    }
    return args, pc0


def converge(
    sub: KDSubproblem, args: dict[str, Any], pc0: np.ndarray, max_iter: int = 30, **kw: Any
) -> tuple[KDIterate, KDStep, int]:
    """Algorithm 1 without Gait-Net: apply full steps until Table X tolerances hold."""
    it = KDIterate.initial(pc0, args["p_com_ref"], args["p_foot_ref"], args["contact"], MASS)
    for j in range(max_iter):
        step = sub.solve(it, sub.inputs(it, **args, **kw))
        it = it.apply(step)
        if step.converged():
            return it, step, j + 1
    raise AssertionError("sequential CMPC did not converge")


@pytest.fixture(scope="module")
def sub() -> KDSubproblem:
    return KDSubproblem(KDConfig(mass_kg=MASS))


# ------------------------------------------------------------------ model
def test_nonlinear_step_matches_eq10_by_hand() -> None:
    x = np.zeros(NX)
    x[6:9] = [1.0, 0.0, 0.0]
    f = np.array([[0.0, 0.0, MASS * G], [0.0, 0.0, 0.0]])
    tau = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.0]])
    p_foot = np.array([[0.1, 0.0, 0.0], [0.0, 0.0, 0.0]])
    out = nonlinear_step(x, f, tau, p_foot, np.zeros(3), 0.1, MASS, G)
    np.testing.assert_allclose(out[0:6], x[6:12] * 0.1)  # H integrates h
    np.testing.assert_allclose(out[6:9], [1.0, 0.0, 0.0])  # weight cancels gravity
    # (0.1, 0, 0) x (0, 0, m g) = (0, -0.1 m g, 0); plus tau_z.
    np.testing.assert_allclose(out[9:12], [0.0, -0.1 * MASS * G * 0.1, 0.05])


def _random_consistent_iterate(
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, KDIterate]:
    """Random forces/moments/feet and the CoM path of eq. 20 they produce from ``x0``."""
    x0 = rng.normal(size=NX)
    f = rng.normal(scale=50.0, size=(H, 2, 3))
    f[..., 2] += 80.0
    tau = rng.normal(scale=2.0, size=(H, 2, 3))
    p_foot = rng.normal(scale=0.2, size=(H, 2, 3))
    dts = rng.uniform(0.04, 0.07, size=H)
    _, pc = nonlinear_rollout(x0, f, tau, p_foot, rng.normal(size=3), dts, MASS, G)
    return x0, dts, KDIterate(f=f, tau=tau, p_foot=p_foot, p_com=pc)


def pack(
    states: np.ndarray,
    delta_f: np.ndarray,
    delta_tau: np.ndarray,
    delta_p_foot: np.ndarray,
    delta_p_com: np.ndarray,
) -> np.ndarray:
    """The QP vector (n,) of states and search directions (layout of the module docstring
    of :mod:`gaitnet_mpc.mpc.implicit_kd`; inverse of :meth:`KDLayout.unpack`)."""
    body = np.concatenate(
        [
            states[:H],
            delta_p_com[:H],
            delta_f.reshape(H, -1),
            delta_tau.reshape(H, -1),
            delta_p_foot.reshape(H, -1),
        ],
        axis=1,
    )
    return np.concatenate([body.ravel(), states[H], delta_p_com[H]])


def test_pack_inverts_unpack(sub: KDSubproblem) -> None:
    z = np.random.default_rng(0).normal(size=sub.n)
    parts = sub.layout.unpack(z)
    packed = pack(
        parts["states"], parts["delta_f"], parts["delta_tau"], parts["delta_p_foot"],
        parts["delta_p_com"],
    )  # fmt: skip
    np.testing.assert_array_equal(packed, z)


def test_linearised_dynamics_match_eq10_to_first_order(sub: KDSubproblem) -> None:
    """Equality rows evaluated on the exact eq. 10 rollout leave only (dpf - dpc) x df dt."""
    rng = np.random.default_rng(1)
    x0, dts, it = _random_consistent_iterate(rng)
    args, _ = walking_problem(dts)
    args["x0"] = x0
    problem = sub.build(it, sub.inputs(it, **args))
    d_f = rng.normal(scale=100.0, size=(H, 2, 3))
    d_tau = rng.normal(scale=10.0, size=(H, 2, 3))
    d_pf = rng.normal(scale=1.0, size=(H, 2, 3))
    errors = []
    for eps in (1e-2, 5e-3, 2.5e-3):
        xs, pc = nonlinear_rollout(
            x0, it.f + eps * d_f, it.tau + eps * d_tau, it.p_foot + eps * d_pf,
            it.p_com[0], dts, MASS, G,
        )  # fmt: skip
        d_pc = pc - it.p_com
        z = pack(xs, eps * d_f, eps * d_tau, eps * d_pf, d_pc)
        resid = problem.A_eq @ z - problem.b_eq
        # Exactly the dropped bilinear term of eq. 15 (Assumption 2), row block by stage.
        expected = np.zeros_like(resid)
        for k in range(H):
            row = 15 + 15 * k + 9
            lever = eps * d_pf[k] - d_pc[k]
            expected[row : row + 3] = dts[k] * np.cross(lever, eps * d_f[k]).sum(axis=0)
        np.testing.assert_allclose(resid, expected, atol=1e-9)
        errors.append(np.abs(resid).max())
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)  # O(eps^2)
    assert errors[0] < 1e-2


# ------------------------------------------------------------------ iterations
def test_converged_iterate_gives_zero_step(sub: KDSubproblem) -> None:
    args, pc0 = walking_problem()
    it, _, n_iter = converge(sub, args, pc0)
    assert n_iter <= 15
    step = sub.solve(it, sub.inputs(it, **args))
    tol = KDTolerances()
    assert step.max_delta_pos_m < tol.position_m
    assert step.max_delta_force_n < tol.force_n
    assert step.max_delta_moment_nm < tol.moment_nm
    # At the fixed point the linear prediction is the exact eq. 10 / eq. 20 rollout.
    xs, pc = nonlinear_rollout(
        args["x0"], it.f, it.tau, it.p_foot, it.p_com[0], args["dts_s"], MASS
    )
    np.testing.assert_allclose(step.states, xs, atol=1e-3)
    np.testing.assert_allclose(it.p_com, pc, atol=1e-5)


def test_constraints_hold_at_solution(sub: KDSubproblem) -> None:
    args, pc0 = walking_problem()
    bounds = {
        "right": (np.array([0.2, -INF, 0.0]), np.array([0.3, INF, 0.0]), None),
        "left": (np.array([0.3, -INF, -INF]), np.array([0.35, INF, INF]), None),
    }
    it, _, _ = converge(sub, args, pc0, foothold_bounds=bounds)
    cfg = sub.config
    contact = args["contact"]
    tol = 1e-4
    for k in range(H):
        for i in range(2):
            w = np.r_[it.f[k, i], it.tau[k, i]]
            if contact[k, i]:
                fz = w[2]
                assert cfg.contact.fz_min_n - tol <= fz <= cfg.contact.fz_max_n + tol
                assert np.all(np.abs(w[:2]) <= cfg.contact.mu_box * fz + tol)  # eq. 22
                cm, lo, hi = foot_wrench_constraints(0.0, cfg.contact, cfg.toe_m, cfg.heel_m)
                assert np.all(cm @ w >= lo - tol) and np.all(cm @ w <= hi + tol)
            else:
                np.testing.assert_allclose(w, 0.0, atol=tol)  # eq. 23, sigma = 0
    # Stance feet stationary; the measured stance foot stays where it is.
    np.testing.assert_allclose(it.p_foot[:5, 0], np.tile([0.0, 0.08, 0.0], (5, 1)), atol=1e-7)
    np.testing.assert_allclose(it.p_foot[5:, 1], np.tile(it.p_foot[5, 1], (5, 1)), atol=1e-7)
    # Swing stages carry the next touchdown location.
    np.testing.assert_allclose(it.p_foot[:5, 1], np.tile(it.p_foot[5, 1], (5, 1)), atol=1e-7)
    # Foothold bounds (eq. 24) on the next touchdowns; the refs lie outside, so they bind.
    assert np.all(it.p_foot[:, 1, 0] >= 0.2 - 1e-6) and np.all(it.p_foot[:, 1, 0] <= 0.3 + 1e-6)
    assert it.p_foot[9, 1, 0] == pytest.approx(0.2, abs=1e-6)
    assert it.p_foot[5:, 0, 0] == pytest.approx(0.3, abs=1e-6)
    np.testing.assert_allclose(it.p_foot[:, :, 2], 0.0, atol=1e-7)  # foot height


def test_sparsity_pattern_fixed_across_schedules_and_yaw() -> None:
    sub = KDSubproblem(KDConfig(mass_kg=MASS))
    args, pc0 = walking_problem()
    it = KDIterate.initial(pc0, args["p_com_ref"], args["p_foot_ref"], args["contact"], MASS)
    first = sub.build(it, sub.inputs(it, **args))
    other = dict(args)
    other["contact"] = np.roll(args["contact"], 2, axis=0)
    other["contact"][:2] = True
    other["foot_yaw_rad"] = np.full((H, 2), 0.3)
    second = sub.build(it, sub.inputs(it, **other))
    for name in ("P", "A_eq", "A"):
        a, b = getattr(first, name), getattr(second, name)
        assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
    sub.workspace.solve(first)
    updated = sub.workspace.solve(second)
    assert sub.workspace.n_setups == 1 and sub.workspace.n_updates == 1
    fresh = KDSubproblem(KDConfig(mass_kg=MASS)).workspace.solve(second)
    assert updated.found and fresh.found
    np.testing.assert_allclose(updated.x, fresh.x, atol=1e-6)


def test_per_stage_dt_changes_prediction_by_eq20(sub: KDSubproblem) -> None:
    advances = []
    for dt_late in (0.05, 0.07):
        dts = np.array([0.05] * 5 + [dt_late] * 5)
        args, pc0 = walking_problem(dts)
        it, step, _ = converge(sub, args, pc0)
        l_g = step.states[:H, 6:9]
        # eq. 20: the CoM advances by sum_k l_k / m dt_k; the pose integrates h.
        np.testing.assert_allclose(
            it.p_com[H] - it.p_com[0], (l_g / MASS * dts[:, None]).sum(axis=0), atol=1e-5
        )
        np.testing.assert_allclose(
            np.diff(step.states[:, :6], axis=0), step.states[:H, 6:] * dts[:, None], atol=1e-6
        )
        advances.append(it.p_com[H, 0] - it.p_com[0, 0])
    # Five stages 20 ms longer at ~0.4 m/s: ~4 cm more forward travel.
    assert advances[1] - advances[0] == pytest.approx(0.4 * 5 * 0.02, rel=0.25)


@pytest.mark.parametrize("toe_m", [0.075, 0.0])
def test_push_moves_next_foothold_and_stays_feasible(toe_m: float) -> None:
    """After a push the converged iterate is reused (new x0, new CoM): still feasible,
    and the free foothold moves with the push (line feet and point feet)."""
    sub = KDSubproblem(KDConfig(mass_kg=MASS, toe_m=toe_m, heel_m=toe_m))
    args, pc0 = walking_problem()
    it, _, _ = converge(sub, args, pc0)
    nominal = it.p_foot[9, 1].copy()
    args["x0"] = args["x0"] + np.r_[np.zeros(6), 8.0, 5.0, 0.0, np.zeros(3)]  # +0.5, +0.3 m/s
    p_com = it.p_com.copy()
    p_com[0] = pc0 + np.array([0.01, 0.01, 0.0])  # new CoM measurement
    it = replace(it, p_com=p_com)
    for _ in range(30):
        step = sub.solve(it, sub.inputs(it, **args))
        it = it.apply(step)
        if step.converged():
            break
    assert step.converged()
    assert it.p_foot[9, 1, 0] > nominal[0] + 0.1 and it.p_foot[9, 1, 1] > nominal[1] + 0.01
    np.testing.assert_allclose(it.p_foot[:5, 0], np.tile([0.0, 0.08, 0.0], (5, 1)), atol=1e-7)


@pytest.mark.parametrize("qp_form", ["sparse", "condensed"])
def test_an_external_wrench_is_carried_by_the_planned_contact_wrenches(qp_form: str) -> None:
    """Eqs. 14-15 with the affine term: the feet take up a 30 N downward load (a payload's
    weight), a 10 N forward push and a 2 N m roll torque, and the CoM keeps its path."""
    sub = KDSubproblem(KDConfig(mass_kg=MASS, qp_form=qp_form))
    args, pc0 = walking_problem()
    free, _, _ = converge(sub, args, pc0)
    load = np.array([10.0, 0.0, -30.0, 2.0, 0.0, 0.0])
    loaded, _, _ = converge(sub, args, pc0, wrench_ext=load)

    def moment(it: KDIterate) -> np.ndarray:  # sum_i (p_i - c) x f_i + tau_i per stage
        arms = it.p_foot - it.p_com[:-1, None, :]
        return (np.cross(arms, it.f) + it.tau).sum(axis=1)

    extra_force = (loaded.f.sum(axis=1) - free.f.sum(axis=1)).mean(axis=0)
    np.testing.assert_allclose(extra_force, -load[:3], atol=1.0)  # N
    assert abs((moment(loaded) - moment(free)).mean(axis=0)[0] + load[3]) < 1.0  # N m
    assert np.abs(loaded.p_com - free.p_com).max() < 0.01  # m


def test_backends_agree_on_one_subproblem() -> None:
    args, pc0 = walking_problem()
    it = KDIterate.initial(pc0, args["p_com_ref"], args["p_foot_ref"], args["contact"], MASS)
    steps = {
        be: (sub := KDSubproblem(KDConfig(mass_kg=MASS, qp_backend=be, qp_form="sparse"))).solve(
            it, sub.inputs(it, **args)
        )
        for be in ("piqp", "osqp", "clarabel", "daqp")
    }
    steps["condensed"] = KDSubproblem(KDConfig(mass_kg=MASS)).solve(it, sub.inputs(it, **args))
    ref = steps.pop("piqp")
    for step in steps.values():
        np.testing.assert_allclose(step.delta_f, ref.delta_f, atol=2e-2)
        np.testing.assert_allclose(step.delta_p_foot, ref.delta_p_foot, atol=1e-4)
        np.testing.assert_allclose(step.states, ref.states, atol=1e-3)


# ------------------------------------------------------------------ helpers
def test_tie_groups_and_next_touchdown_mask() -> None:
    c = np.array([1, 1, 0, 0, 1, 1, 0, 1], dtype=bool)
    np.testing.assert_array_equal(tie_groups(c), [0, 0, 1, 1, 1, 1, 2, 2])
    np.testing.assert_array_equal(next_touchdown_mask(c), [0, 0, 1, 1, 1, 1, 0, 0])
    np.testing.assert_array_equal(next_touchdown_mask(~c), [1, 1, 1, 1, 0, 0, 0, 0])
    assert not next_touchdown_mask(np.ones(4, dtype=bool)).any()


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("x0", np.zeros(11)),
        ("h_ref", np.zeros((H, 6))),
        ("H_ref", np.zeros((H + 1, 5))),
        ("p_foot_ref", np.zeros((H, 3))),
        ("p_com_ref", np.zeros((H, 3))),
        ("dts_s", np.full(H - 1, 0.05)),
        ("dts_s", np.r_[np.full(H - 1, 0.05), -0.05]),
        ("contact", np.ones((H, 3), dtype=bool)),
        ("foot_yaw_rad", np.zeros(H)),
        ("p_foot_measured", np.zeros(3)),
        ("wrench_ext", np.zeros(3)),
        ("wrench_ext", np.r_[np.nan, np.zeros(5)]),
    ],
)
def test_bad_shapes_raise_config_error(sub: KDSubproblem, name: str, value: np.ndarray) -> None:
    args, pc0 = walking_problem()
    it = KDIterate.initial(pc0, args["p_com_ref"], args["p_foot_ref"], args["contact"], MASS)
    args[name] = value
    with pytest.raises(ConfigError) as err:
        sub.build(it, sub.inputs(it, **args))
    assert err.value.field == name


def test_bad_iterate_and_bounds_raise_config_error(sub: KDSubproblem) -> None:
    args, pc0 = walking_problem()
    it = KDIterate.initial(pc0, args["p_com_ref"], args["p_foot_ref"], args["contact"], MASS)
    with pytest.raises(ConfigError) as err:
        KDIterate(f=it.f, tau=it.tau, p_foot=it.p_foot, p_com=it.p_com[:H])
    assert err.value.field == "iterate.p_com"
    short = KDIterate(f=it.f[:5], tau=it.tau[:5], p_foot=it.p_foot[:5], p_com=it.p_com[:6])
    with pytest.raises(ConfigError, match="iterate"):
        sub.build(short, sub.inputs(short, **args))
    with pytest.raises(ConfigError, match="foothold_bounds"):
        sub.build(it, sub.inputs(it, foothold_bounds={"middle": (None, None)}, **args))
    with pytest.raises(ConfigError, match="p_min <= p_max"):
        sub.build(it, sub.inputs(it, foothold_bounds={"left": (np.ones(3), np.zeros(3))}, **args))
    with pytest.raises(ConfigError, match="horizon"):
        KDConfig(horizon=0)
    with pytest.raises(ConfigError, match="w_p_com"):
        KDConfig(w_p_com=(1.0, 2.0))


def test_motion_weight_units_read_pose_and_momentum_per_unit_mass_and_inertia() -> None:
    """``weight_units = "motion"`` weighs ``[H; h]`` as the quantity weights divided by
    ``m^2`` (linear rows) and ``I^2`` (angular rows): the converged plan equals that of
    the same weights written out; and the option and the inertia are checked."""
    inertia = (0.64, 0.58, 0.094)
    w = (200.0, 150.0, 100.0, 200.0, 300.0, 400.0)
    scale = np.array([MASS] * 3 + list(inertia)) ** 2
    motion = KDConfig(mass_kg=MASS, inertia_kgm2=inertia, weight_units="motion", w_pose=w)
    written = KDConfig(mass_kg=MASS, w_pose=tuple(np.array(w) / scale),
                       w_momentum=tuple(np.array(motion.w_momentum) / scale))  # fmt: skip
    np.testing.assert_allclose(motion.pose_weights, written.pose_weights, rtol=1e-12)
    np.testing.assert_allclose(motion.stage_weights()[0], written.stage_weights()[0], rtol=1e-12)
    args, pc0 = walking_problem()
    a, _, _ = converge(KDSubproblem(motion), args, pc0)
    b, _, _ = converge(KDSubproblem(written), args, pc0)
    np.testing.assert_allclose(a.p_foot, b.p_foot, atol=1e-6)
    np.testing.assert_allclose(a.f, b.f, atol=1e-3)
    quantity = converge(KDSubproblem(KDConfig(mass_kg=MASS, w_pose=w)), args, pc0)[0]
    assert np.abs(quantity.p_com - a.p_com).max() > 1e-4  # the reading changes the plan
    with pytest.raises(ConfigError, match="weight_units"):
        KDConfig(weight_units="si")
    with pytest.raises(ConfigError, match="inertia_kgm2"):
        KDConfig(inertia_kgm2=(0.6, 0.0, 0.1))


def test_foot_separation_row_keeps_the_touchdown_beside_the_stance_foot() -> None:
    """With ``min_foot_separation_m``, a right foot whose (heavily weighted) reference lies
    left of the left stance foot lands ``d_min`` to its right in the heading frame, at a 0.3
    rad heading too; without the row the plan puts the feet closer."""
    args, pc0 = walking_problem()
    d_min = 0.06
    for yaw in (0.0, 0.3):
        rot = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
        a = dict(args)
        p_ref = args["p_foot_ref"].copy()
        p_ref[:, 1] = [0.12, 0.12, 0.0]  # right foot planned 4 cm left of the left foot
        a["p_foot_ref"] = p_ref @ rot.T
        a["foot_yaw_rad"] = np.full((H, 2), yaw)
        plans = {}
        for sep in (None, d_min):
            cfg = KDConfig(mass_kg=MASS, w_p_foot=(1e4, 1e4, 1e4), min_foot_separation_m=sep)
            plans[sep], _, _ = converge(KDSubproblem(cfg), a, pc0)
        n_y = np.array([-np.sin(yaw), np.cos(yaw)])
        lateral = {s: (p.p_foot[:, 0, :2] - p.p_foot[:, 1, :2]) @ n_y for s, p in plans.items()}
        assert lateral[None].min() < d_min - 0.005  # closer than d_min without the row
        assert lateral[d_min].min() >= d_min - 1e-6
