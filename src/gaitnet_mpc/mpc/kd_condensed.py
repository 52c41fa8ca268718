"""The CMPC QP condensed to its free variables and solved by a dense active set (DAQP).

The sparse QP of :mod:`~gaitnet_mpc.mpc.implicit_kd` keeps every state as a variable:
345 variables, 165 equality rows, a box on each variable. Most of them are determined
by the constraints, and eliminating them leaves a small dense QP that an active-set
method solves in a fraction of an interior point's time
(``benchmarks/results/kd_qp_condensed.md``). Eliminated, with ``z`` the sparse QP's
variables (layout :class:`~gaitnet_mpc.mpc.kd_layout.KDLayout`):

* **the states** ``x_k`` and ``delta p_c,k`` (the dynamics, eqs. 14-15, 19-20). In stage
  order the equality rows are lower triangular with a unit diagonal in these columns
  (``A_S``), so ``z_S = A_S^{-1} (b_eq - A_I z_I)`` with ``I`` the other columns;
* **a swing foot's wrench**: its rows ``C (w^j + delta w) = 0`` have full column rank
  (:mod:`~gaitnet_mpc.mpc.contact`), so ``delta w = -w^j``;
* **the foot ties**: a tie group (the stages of one swing and the stance after it, or
  the measured stance) has one position, so ``delta p_f,k = delta p_f,k0 + p_f,k0^j -
  p_f,k^j`` from the group's first stage ``k0``, and its tie rows hold by construction;
* **fixed axes** (box ``lb = ub``: the measured stance foot, heights taken from the
  reference).

What remains, ``u``, is the wrench of every stance foot and stage and the free axes of
the other tie groups: 62-100 variables for ``h = 10`` (64-66 while walking). With
``z = M u + m``::

    min_u 0.5 u^T (M^T P M) u + (M^T (P m + q))^T u
    s.t.  l - A m <= A M u <= u - A m     (stance wrench rows, separation rows)
          lb_z - m_S <= M_S u <= ub_z - m_S  (finite boxes on states: the CoM trust
                                            region)
          box of each group's first stage    (eq. 24 and the trust region, on u)

The objective and the feasible set are those of the sparse QP restricted to the
eliminated variables' values, so the minimiser is the same (checked against PIQP on
random and recorded problems in ``tests/test_kd_condensed.py``). The states follow from
a forward substitution over the stages, ``s_{k+1} = s_k + dt (...)``, and the products
above run over each stage's prefix of ``u`` (in stage order, a state depends only on the
variables of earlier stages). The compiled kernels that build all of this straight from
the iterate, without forming the sparse QP, are in
:mod:`~gaitnet_mpc.mpc.kd_condensed_kernel`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from gaitnet_mpc.errors import ConfigError, reraise_interrupt
from gaitnet_mpc.mpc import kd_condensed_kernel as kernel
from gaitnet_mpc.mpc.kd_config import KDConfig
from gaitnet_mpc.mpc.kd_inputs import KDInputs
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.mpc.kinematic_rows import qp_reach_rows
from gaitnet_mpc.mpc.qp.solution import QPSolution

try:
    import daqp
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    daqp = None

#: DAQP exit flags: 1 optimal, 2 soft-optimal; the rest are failures.
_SOLVED = {1: "solved", 2: "solved_inaccurate"}


@dataclass(frozen=True)
class CondensedQP:
    """The dense QP of one CMPC sub-problem, in DAQP's form, and the way back.

    Attributes:
        qp: ``daqp.solve``'s ``H, f, A, bupper, blower, sense`` (the first ``n_u``
            bounds are the box on ``u``).
        idx, m_in, m_mat, m_vec: the maps of :func:`kd_condensed_kernel.expand`.
    """

    qp: dict[str, np.ndarray]
    idx: np.ndarray
    m_in: np.ndarray
    m_mat: np.ndarray
    m_vec: np.ndarray

    @property
    def n_u(self) -> int:
        """Number of condensed variables."""
        return int(self.qp["H"].shape[0])

    def expand(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """The sparse QP's variables at ``u``, as :meth:`KDLayout.unpack` splits them."""
        parts = kernel.expand(u, self.idx, self.m_in, self.m_mat, self.m_vec)
        names = ("states", "delta_p_com", "delta_f", "delta_tau", "delta_p_foot")
        return dict(zip(names, parts, strict=True))


class KDCondensed:
    """Builds the condensed QP of a sub-problem (module docstring) and solves it with DAQP.

    Args:
        config: the sub-problem's parameters (weights, separation, CoM trust region).
        daqp_options: ``daqp.solve`` settings.

    Raises:
        ConfigError: DAQP is not installed.
    """

    backend = "daqp-condensed"

    def __init__(self, config: KDConfig, daqp_options: dict[str, Any] | None = None) -> None:
        if daqp is None:
            raise ConfigError("qp_form", "condensed", "the daqp package installed")
        c = self.config = config
        self.options = dict(daqp_options or {})
        self._mass, self._gravity = float(c.mass_kg), float(c.gravity_mps2)
        # the sparse QP's P = 2 W and gradient factors (as implicit_kd._build_cost_diag)
        w_state, w_input = c.stage_weights()
        self._p_state, self._p_input = 2.0 * w_state, 2.0 * w_input
        w_p_foot = np.asarray(c.w_p_foot, dtype=float)
        self._q_input = 2.0 * np.array([[c.w_force] * 3, [c.w_moment] * 3, w_p_foot])
        self._q_p_com = 2.0 * np.asarray(c.w_p_com, dtype=float)
        self._min_sep = kernel.or_nan(c.min_foot_separation_m)
        self._sweep = max(c.toe_m, c.heel_m)
        self._trust_com = kernel.or_nan(c.trust_region_com_m)

    def condense(
        self,
        it: KDIterate,
        a: KDInputs,
        wrench_rows: tuple[np.ndarray, np.ndarray, np.ndarray],
        lo: np.ndarray,
        hi: np.ndarray,
    ) -> CondensedQP:
        """The dense QP of the sub-problem about ``it`` with ``a``.

        Args:
            wrench_rows: the stance rows ``C`` (h, 2, mw, 6) and bounds ``l, u`` at each
                foot yaw (:meth:`StanceWrenchRows.stack`).
            lo, hi: (h, 2, 3) absolute foot bounds (:func:`kd_condensed_kernel.foot_bounds`).
        """
        c_w, l_w, u_w = wrench_rows
        reach = qp_reach_rows(self.config, it, a, lo, hi)
        out = kernel.condense(
            a.dts_s, a.contact, self._mass, self._affine(a), it.f, it.tau, it.p_foot,
            it.p_com, a.x0, a.H_ref, a.h_ref, a.p_com_ref, a.p_foot_ref, self._p_state,
            self._p_input, self._q_input, self._q_p_com, c_w, l_w, u_w, lo, hi,
            a.foot_yaw_rad, self._min_sep, self._sweep, self._trust_com, *reach,
        )  # fmt: skip
        names = ("H", "f", "A", "bupper", "blower", "sense")
        return CondensedQP(dict(zip(names, out[:6], strict=True)), *out[6:])

    def _affine(self, a: KDInputs) -> np.ndarray:
        """``[m g + f_ext; tau_ext]`` (6,): what acts on the momentum beside the feet."""
        out = a.wrench_ext.copy()
        out[2] -= self._mass * self._gravity
        return out

    def solve(self, dense: CondensedQP) -> tuple[QPSolution, dict[str, np.ndarray] | None]:
        """Solve ``dense`` with DAQP: the solution (``found`` if DAQP calls it optimal; its
        ``x`` and ``problem`` are left to the caller) and the expanded parts, or None
        where DAQP failed."""
        start = time.perf_counter()
        u, _fval, exitflag, info = daqp.solve(**dense.qp, **self.options)
        status = _SOLVED.get(int(exitflag), "numerical_error" if exitflag != -1 else "infeasible")
        parts = None
        if status in _SOLVED.values():
            if np.all(np.isfinite(u)):
                parts = dense.expand(u)
            else:
                status = "nan"
        sol = QPSolution(
            x=None,
            status=status,
            found=status == "solved",
            iterations=int(info.get("iterations", 0)),
            solve_time_s=time.perf_counter() - start,
            backend=self.backend,
            native_status=f"daqp exit {exitflag}",
        )
        return sol, parts


__all__ = ["CondensedQP", "KDCondensed"]
