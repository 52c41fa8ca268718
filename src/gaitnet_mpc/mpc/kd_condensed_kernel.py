"""Compiled kernels of the condensed CMPC QP: the foot boxes, the condensing and the way back.

:mod:`~gaitnet_mpc.mpc.kd_condensed` states the condensed QP and why it has the sparse
QP's minimiser; these kernels build it straight from the iterate and the per-solve inputs
(:class:`~gaitnet_mpc.mpc.kd_inputs.KDInputs`), stage by stage, in scalar loops (numba,
compiled on first use, cached by :mod:`gaitnet_mpc.jit`). The sparse QP of
:mod:`~gaitnet_mpc.mpc.implicit_kd` is not formed: a QP is then about a tenth of a
millisecond of arithmetic instead of a few hundred NumPy calls. Nothing here calls BLAS,
so there are no BLAS threads to limit.

Condensed variables ``u``, in stage order: for each stage ``k``, the force and moment of
each stance foot (``df``, then ``dtau``, left foot first), then the free axes of each tie
group that starts at ``k`` (the group's position ``dpf`` at its first stage). With stage
order the state ``s_k = M_k u + m_k`` depends only on the variables of the stages before
``k``, a prefix of ``u``: the products below stop at that prefix.

Index arrays:
    ``idx`` (h, 2, 3, 3): the ``u`` of input ``[k, foot, kind, axis]`` (kind 0: ``df``,
    1: ``dtau``, 2: ``dpf``), -1 where the input is fixed; ``m_in`` (same shape): the
    input's value at ``u = 0``.
"""

from __future__ import annotations

import math

import numpy as np

from gaitnet_mpc.jit import njit_cached

_NSX = 15  # condensed state per stage: x_k (12) and delta p_c,k (3)
_FREE_M = 1e3  # the sparse QP's "unbounded" row bound (the separation rows' upper bound)
_EQUALITY = 5  # DAQP's flag of an equality row (lower == upper)


def or_nan(value: float | None) -> float:
    """``value``, or NaN (the kernels' "none") for None."""
    return math.nan if value is None else float(value)


@njit_cached()
def foot_bounds(
    contact: np.ndarray,
    p_foot: np.ndarray,
    p_foot_ref_z: np.ndarray,
    p_measured: np.ndarray,
    has_box: np.ndarray,
    box_lo: np.ndarray,
    box_hi: np.ndarray,
    box_mask: np.ndarray,
    height_from_reference: bool,
    trust_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Absolute bounds (h, 2, 3) ``lo, hi`` on each stage's foot position.

    Per tie group of a foot (the stages from a lift-off to the next): the measured
    position for the measured stance group (a foot in stance at stage 0); else the
    eq. 24 box if the group holds a stage of the foot's mask, the reference height (mean
    over the group's stance stages, or all its stages) unless that box bounds the height,
    and the trust region ``trust_m`` (NaN: none) around the group's mean iterate, dropped
    on an axis where it misses the box. Every stage of a group gets its group's bounds.

    Args:
        contact: (h, 2) stance mask; p_foot: (h, 2, 3) iterate; p_foot_ref_z: (h, 2)
            reference heights; p_measured: (2, 3) measured foot positions.
        has_box, box_lo, box_hi, box_mask: per foot, whether it has an eq. 24 box, its
            (2, 3) corners and its (2, h) stage mask.
    """
    h = contact.shape[0]
    lo = np.full((h, 2, 3), -np.inf)
    hi = np.full((h, 2, 3), np.inf)
    g_lo = np.empty(3)
    g_hi = np.empty(3)
    for i in range(2):
        s0 = 0
        while s0 < h:
            s1 = s0 + 1  # the group is [s0, s1): until the next lift-off
            while s1 < h and not (contact[s1 - 1, i] and not contact[s1, i]):
                s1 += 1
            if s0 == 0 and contact[0, i]:
                for a in range(3):
                    g_lo[a] = g_hi[a] = p_measured[i, a]
            else:
                boxed = False
                if has_box[i]:
                    for k in range(s0, s1):
                        boxed = boxed or box_mask[i, k]
                for a in range(3):
                    g_lo[a] = box_lo[i, a] if boxed else -np.inf
                    g_hi[a] = box_hi[i, a] if boxed else np.inf
                if height_from_reference and not (np.isfinite(g_lo[2]) and np.isfinite(g_hi[2])):
                    n_stance = 0
                    for k in range(s0, s1):
                        n_stance += contact[k, i]
                    z0 = s1 - n_stance if n_stance > 0 else s0
                    z = 0.0
                    for k in range(z0, s1):
                        z += p_foot_ref_z[k, i]
                    g_lo[2] = g_hi[2] = z / (s1 - z0)
                if not math.isnan(trust_m):
                    for a in range(3):
                        centre = 0.0
                        for k in range(s0, s1):
                            centre += p_foot[k, i, a]
                        centre /= s1 - s0
                        t_lo = max(g_lo[a], centre - trust_m)
                        t_hi = min(g_hi[a], centre + trust_m)
                        if t_lo <= t_hi:
                            g_lo[a], g_hi[a] = t_lo, t_hi
            for k in range(s0, s1):
                for a in range(3):
                    lo[k, i, a] = g_lo[a]
                    hi[k, i, a] = g_hi[a]
            s0 = s1
    return lo, hi


@njit_cached(inline="always")
def _skew(v: np.ndarray, row: int, col: int) -> float:
    """Entry ``(row, col)`` of the cross-product matrix of the 3-vector ``v``."""
    if row == col:
        return 0.0
    if row == 0:
        return -v[2] if col == 1 else v[1]
    if row == 1:
        return v[2] if col == 0 else -v[0]
    return -v[1] if col == 0 else v[0]


@njit_cached()
def _variables(
    contact: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """The variables ``u`` (module docstring): ``idx``, ``m_in``, the box on ``u``, and
    ``n_before`` (h + 1,), the number of variables of the stages before each stage."""
    h = contact.shape[0]
    idx = np.full((h, 2, 3, 3), -1, dtype=np.int64)
    m_in = np.zeros((h, 2, 3, 3))
    u_lo = np.full(h * 18, -np.inf)
    u_hi = np.full(h * 18, np.inf)
    n_before = np.zeros(h + 1, dtype=np.int64)
    n_u = 0
    base = np.zeros(2, dtype=np.int64)  # first stage of each foot's current tie group
    for k in range(h):
        n_before[k] = n_u
        for i in range(2):
            if contact[k, i]:
                for kind in range(2):
                    for a in range(3):
                        idx[k, i, kind, a] = n_u
                        n_u += 1
            else:
                for a in range(3):
                    m_in[k, i, 0, a] = -f[k, i, a]
                    m_in[k, i, 1, a] = -tau[k, i, a]
        for i in range(2):
            if k > 0 and contact[k - 1, i] and not contact[k, i]:
                base[i] = k
            k0 = base[i]
            for a in range(3):
                fixed = lo[k0, i, a] == hi[k0, i, a]
                m_in[k, i, 2, a] = p_foot[k0, i, a] - p_foot[k, i, a]
                if fixed:
                    m_in[k, i, 2, a] += lo[k0, i, a] - p_foot[k0, i, a]
                elif k0 == k:
                    idx[k, i, 2, a] = n_u
                    u_lo[n_u] = lo[k, i, a] - p_foot[k, i, a]
                    u_hi[n_u] = hi[k, i, a] - p_foot[k, i, a]
                    n_u += 1
                else:
                    idx[k, i, 2, a] = idx[k0, i, 2, a]
    n_before[h] = n_u
    return idx, m_in, u_lo[:n_u], u_hi[:n_u], n_before, n_u


@njit_cached()
def condense(
    dts: np.ndarray,
    contact: np.ndarray,
    mass: float,
    affine: np.ndarray,
    f: np.ndarray,
    tau: np.ndarray,
    p_foot: np.ndarray,
    p_com: np.ndarray,
    x0: np.ndarray,
    pose_ref: np.ndarray,
    momentum_ref: np.ndarray,
    p_com_ref: np.ndarray,
    p_foot_ref: np.ndarray,
    p_state: np.ndarray,
    p_input: np.ndarray,
    q_input_w: np.ndarray,
    w_p_com: np.ndarray,
    c_w: np.ndarray,
    l_w: np.ndarray,
    u_w: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    foot_yaw: np.ndarray,
    min_separation_m: float,
    sweep_m: float,
    trust_com_m: float,
    reach_active: np.ndarray,
    reach_normal: np.ndarray,
    reach_bound: np.ndarray,
) -> tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray, np.ndarray, np.ndarray, np.ndarray,
]:  # fmt: skip
    """The condensed QP of one CMPC sub-problem, in DAQP's form.

    Args:
        dts, contact, f, tau, p_foot, p_com, x0: stage times, stance mask, iterate and
            measured state (as in :class:`~gaitnet_mpc.mpc.kd_inputs.KDInputs`).
        pose_ref, momentum_ref, p_com_ref, p_foot_ref: eq. 18's references.
        mass: the modelled mass [kg]; affine: (6,) the wrench of gravity and the external
            wrench, ``[m g + f_ext; tau_ext]`` [N; N m].
        p_state: (15,) the sparse QP's diagonal ``P`` on ``x_k, delta p_c,k`` (k >= 1).
        p_input: (3, 3) ``P`` on ``df, dtau, dpf`` per axis; q_input_w: (3, 3) the factors
            of their gradient ``q = q_input_w * (value - reference)`` (references 0 for
            the wrench); w_p_com: (3,) ``2 L^{p_c}``, the CoM gradient factor.
        c_w, l_w, u_w: (h, 2, mw, 6), (h, 2, mw) the stance wrench rows at each foot yaw.
        lo, hi: (h, 2, 3) foot bounds (:func:`foot_bounds`).
        foot_yaw: (h, 2); min_separation_m: NaN for no separation rows; sweep_m: the
            longer of toe and heel; trust_com_m: NaN for no CoM trust region.
        reach_active, reach_normal, reach_bound: the reach rows
            (:func:`~gaitnet_mpc.mpc.kinematic_rows.reach_rows`).

    Returns:
        ``H, f, A, upper, lower, sense`` (the first ``n_u`` bounds are the box on ``u``),
        then ``idx, m_in`` and ``M`` (h + 1, 15, n_u), ``m`` (h + 1, 15) for
        :func:`expand`.
    """
    h = dts.shape[0]
    idx, m_in, u_lo, u_hi, n_before, n_u = _variables(contact, f, tau, p_foot, lo, hi)
    # ---- states: s_{k+1} = s_k + dt (eqs. 14-15, 19-20 linearised at the iterate)
    mm = np.zeros((h + 1, _NSX, n_u))
    mv = np.zeros((h + 1, _NSX))
    mv[0, :12] = x0
    force = np.empty(3)
    arm = np.empty(3)
    for k in range(h):
        dt = dts[k]
        n0 = n_before[k]
        old, new = mm[k], mm[k + 1]
        new[:, :n0] = old[:, :n0]
        mv[k + 1] = mv[k]
        for r in range(6):  # H_{k+1} = H_k + dt h_k
            for j in range(n0):
                new[r, j] += dt * old[6 + r, j]
            mv[k + 1, r] += dt * mv[k, 6 + r]
        for a in range(3):
            force[a] = f[k, 0, a] + f[k, 1, a]
        for a in range(3):  # CoM: dpc_{k+1} = dpc_k + dt / m l_k + p_c,k - p_c,k+1
            for j in range(n0):
                new[12 + a, j] += dt / mass * old[6 + a, j]
            mv[k + 1, 12 + a] += dt / mass * mv[k, 6 + a] + p_com[k, a] - p_com[k + 1, a]
            # momentum: + dt (sum df + sum f + m g + f_ext), + dt tau_ext
            mv[k + 1, 6 + a] += dt * (force[a] + affine[a])
            mv[k + 1, 9 + a] += dt * affine[3 + a]
            for b in range(3):  # angular momentum: + dt skew(sum f) dpc_k
                s = dt * _skew(force, a, b)
                if s != 0.0:
                    for j in range(n0):
                        new[9 + a, j] += s * old[12 + b, j]
                    mv[k + 1, 9 + a] += s * mv[k, 12 + b]
        for i in range(2):  # + dt (dtau + skew(r) df - skew(f) dpf + r x f + tau)
            for a in range(3):
                arm[a] = p_foot[k, i, a] - p_com[k, a]
            for a in range(3):
                torque = tau[k, i, a]
                for b in range(3):
                    torque += _skew(arm, a, b) * f[k, i, b]
                mv[k + 1, 9 + a] += dt * torque
            for b in range(3):  # input axis b
                col_f, col_t, col_p = idx[k, i, 0, b], idx[k, i, 1, b], idx[k, i, 2, b]
                val_f, val_t, val_p = m_in[k, i, 0, b], m_in[k, i, 1, b], m_in[k, i, 2, b]
                mv[k + 1, 6 + b] += dt * val_f
                mv[k + 1, 9 + b] += dt * val_t
                if col_f >= 0:
                    new[6 + b, col_f] += dt
                if col_t >= 0:
                    new[9 + b, col_t] += dt
                for a in range(3):
                    s_r = dt * _skew(arm, a, b)
                    s_f = -dt * _skew(f[k, i], a, b)
                    mv[k + 1, 9 + a] += s_r * val_f + s_f * val_p
                    if col_f >= 0:
                        new[9 + a, col_f] += s_r
                    if col_p >= 0:
                        new[9 + a, col_p] += s_f
    # ---- cost: M^T P M and M^T (P m + q), states k >= 1 over their prefix, then inputs
    hess = np.zeros((n_u, n_u))
    grad = np.zeros(n_u)
    q_state = np.empty(_NSX)
    for k in range(1, h + 1):
        n = n_before[k]
        for r in range(6):
            q_state[r] = -p_state[r] * pose_ref[k, r]
            q_state[6 + r] = -p_state[6 + r] * momentum_ref[k, r]
        for a in range(3):
            q_state[12 + a] = w_p_com[a] * (p_com[k, a] - p_com_ref[k, a])
        for r in range(_NSX):
            row = mm[k, r]
            w = p_state[r]
            c = w * mv[k, r] + q_state[r]
            for j in range(n):
                v = row[j]
                if v != 0.0:
                    grad[j] += v * c
                    wv = w * v
                    for col in range(j + 1):
                        hess[j, col] += wv * row[col]
    for j in range(n_u):
        for col in range(j):
            hess[col, j] = hess[j, col]
    for k in range(h):
        for i in range(2):
            for kind in range(3):
                for a in range(3):
                    j = idx[k, i, kind, a]
                    if j >= 0:
                        value = m_in[k, i, kind, a]
                        if kind == 0:
                            q = q_input_w[0, a] * f[k, i, a]
                        elif kind == 1:
                            q = q_input_w[1, a] * tau[k, i, a]
                        else:
                            q = q_input_w[2, a] * (p_foot[k, i, a] - p_foot_ref[k, i, a])
                        hess[j, j] += p_input[kind, a]
                        grad[j] += p_input[kind, a] * value + q
    # ---- rows: stance wrench rows (eqs. 21-23), separation rows, CoM trust region, reach
    mw = c_w.shape[2]
    n_stance = 0
    for k in range(h):
        for i in range(2):
            n_stance += contact[k, i]
    n_sep = 0 if math.isnan(min_separation_m) else h
    n_trust = 0 if math.isnan(trust_com_m) else 3 * h
    n_reach = 0
    for k in range(h):
        for i in range(2):
            n_reach += reach_active[k, i] * reach_normal.shape[2]
    n_rows = n_stance * mw + n_sep + n_trust + n_reach
    rows = np.zeros((n_rows, n_u))
    upper = np.empty(n_u + n_rows)
    lower = np.empty(n_u + n_rows)
    upper[:n_u] = u_hi
    lower[:n_u] = u_lo
    row = 0
    for k in range(h):
        for i in range(2):
            if not contact[k, i]:
                continue
            for r in range(mw):
                shift = 0.0
                for a in range(3):
                    rows[row, idx[k, i, 0, a]] = c_w[k, i, r, a]
                    rows[row, idx[k, i, 1, a]] = c_w[k, i, r, 3 + a]
                    shift += c_w[k, i, r, a] * f[k, i, a] + c_w[k, i, r, 3 + a] * tau[k, i, a]
                lower[n_u + row] = l_w[k, i, r] - shift
                upper[n_u + row] = u_w[k, i, r] - shift
                row += 1
    for k in range(n_sep):  # n_y(psi)^T (p_left - p_right) >= d_min + sweep
        swing = 0 if contact[k, 1] and not contact[k, 0] else 1
        yaw = foot_yaw[k, swing]
        n_y = (-math.sin(yaw), math.cos(yaw))
        value = 0.0
        for a in range(2):
            for i in range(2):
                sign = n_y[a] if i == 0 else -n_y[a]
                value += sign * (p_foot[k, i, a] + m_in[k, i, 2, a])
                j = idx[k, i, 2, a]
                if j >= 0:
                    rows[row, j] += sign
        reach = min_separation_m + sweep_m * abs(math.sin(foot_yaw[k, 0] - foot_yaw[k, 1]))
        lower[n_u + row] = reach - value
        upper[n_u + row] = _FREE_M - value
        row += 1
    if n_trust:
        for k in range(1, h + 1):
            for a in range(3):
                rows[row] = mm[k, 12 + a]
                lower[n_u + row] = -trust_com_m - mv[k, 12 + a]
                upper[n_u + row] = trust_com_m - mv[k, 12 + a]
                row += 1
    for k in range(h):  # n_m^T (dpf_k,i - dpc_k) <= bound (kinematic_rows)
        for i in range(2):
            if not reach_active[k, i]:
                continue
            for face in range(reach_normal.shape[2]):
                value = 0.0
                for a in range(3):
                    n_a = reach_normal[k, i, face, a]
                    value += n_a * (m_in[k, i, 2, a] - mv[k, 12 + a])
                    j = idx[k, i, 2, a]
                    if j >= 0:
                        rows[row, j] += n_a
                    for col in range(n_before[k]):
                        rows[row, col] -= n_a * mm[k, 12 + a, col]
                lower[n_u + row] = -np.inf
                upper[n_u + row] = reach_bound[k, i, face] - value
                row += 1
    sense = np.zeros(n_u + n_rows, dtype=np.int32)
    for r in range(n_u + n_rows):
        if lower[r] == upper[r]:
            sense[r] = _EQUALITY
    return hess, grad, rows, upper, lower, sense, idx, m_in, mm, mv


@njit_cached()
def expand(
    u: np.ndarray, idx: np.ndarray, m_in: np.ndarray, mm: np.ndarray, mv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The sparse QP's variables at a condensed point ``u``: ``states`` (h + 1, 12),
    ``delta_p_com`` (h + 1, 3), ``delta_f``, ``delta_tau``, ``delta_p_foot`` (h, 2, 3)."""
    h = idx.shape[0]
    inputs = m_in.copy()
    for k in range(h):
        for i in range(2):
            for kind in range(3):
                for a in range(3):
                    j = idx[k, i, kind, a]
                    if j >= 0:
                        inputs[k, i, kind, a] += u[j]
    s = mv.copy()
    for k in range(1, h + 1):
        for r in range(_NSX):
            acc = 0.0
            for j in range(u.shape[0]):
                acc += mm[k, r, j] * u[j]
            s[k, r] += acc
    return s[:, :12].copy(), s[:, 12:].copy(), inputs[:, :, 0], inputs[:, :, 1], inputs[:, :, 2]
