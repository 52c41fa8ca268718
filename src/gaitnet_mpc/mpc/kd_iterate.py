"""Iterate, step and tolerances of the sequential CMPC (paper Sec. IV-B, Algorithm 1).

The *iterate* ``j`` is the total solution the CMPC sub-problem is linearised about (eqs.
13-15): contact forces ``f``, contact moments ``tau`` and foot positions ``p_f`` per stage
and foot, and the CoM path ``p_c``. A sub-problem solve returns the search directions
(:class:`KDStep`); iteration ``j + 1 = j + alpha delta`` (eq. 13) until every direction is
within the tolerances of Table X (:class:`KDTolerances`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import GRAVITY_MPS2
from gaitnet_mpc.mpc.centroidal_model import N_FEET
from gaitnet_mpc.mpc.checks import bool_array, float_array
from gaitnet_mpc.mpc.qp import QPSolution


@dataclass(frozen=True)
class KDTolerances:
    """Convergence tolerances of the sequential CMPC (paper Table X): a search direction at
    or below each counts as converged (0: only an exact zero, so up to ``j_max`` QPs)."""

    position_m: float = bounded(
        1e-5, "[0, 0.01] m", "a tolerance", "1 cm: twice the 5 mm landing margin"
    )
    force_n: float = bounded(1e-2, "[0, 10] N", "a tolerance", "6 % of the humanoid's weight")
    moment_nm: float = bounded(1e-3, "[0, 1] N m", "a tolerance", "moves m g's CoP by 6 mm")

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class KDIterate:
    """Total solution of iteration ``j`` (the linearisation point of eqs. 13-15).

    Attributes:
        f: (h, 2, 3) contact forces [N], feet ordered as :data:`~gaitnet_mpc.robots.FEET`.
        tau: (h, 2, 3) contact moments about the foot centre [N m].
        p_foot: (h, 2, 3) foot positions [m].
        p_com: (h + 1, 3) CoM positions [m]; ``p_com[0]`` is the measured CoM.
    """

    f: np.ndarray
    tau: np.ndarray
    p_foot: np.ndarray
    p_com: np.ndarray

    def __post_init__(self) -> None:
        f = np.asarray(self.f, dtype=float)
        if f.ndim != 3 or f.shape[1:] != (N_FEET, 3) or f.shape[0] < 1:
            raise ConfigError("iterate.f", f.shape, "shape (h, 2, 3) with h >= 1")
        h = f.shape[0]
        object.__setattr__(self, "f", float_array("iterate.f", f, (h, N_FEET, 3)))
        object.__setattr__(self, "tau", float_array("iterate.tau", self.tau, (h, N_FEET, 3)))
        p_foot = float_array("iterate.p_foot", self.p_foot, (h, N_FEET, 3))
        object.__setattr__(self, "p_foot", p_foot)
        object.__setattr__(self, "p_com", float_array("iterate.p_com", self.p_com, (h + 1, 3)))

    @property
    def horizon(self) -> int:
        """Number of stages ``h``."""
        return int(self.f.shape[0])

    def apply(self, step: KDStep, alpha: float = 1.0) -> KDIterate:
        """Iterate ``j + 1 = j + alpha * delta`` (eq. 13); a new object."""
        return KDIterate(
            f=self.f + alpha * step.delta_f,
            tau=self.tau + alpha * step.delta_tau,
            p_foot=self.p_foot + alpha * step.delta_p_foot,
            p_com=self.p_com + alpha * step.delta_p_com,
        )

    @classmethod
    def initial(
        cls,
        p_com0: np.ndarray,
        p_com_ref: np.ndarray,
        p_foot_ref: np.ndarray,
        contact: np.ndarray,
        mass_kg: float,
        gravity_mps2: float = GRAVITY_MPS2,
    ) -> KDIterate:
        """Warm start ``j = 0``: references for positions, weight shared by stance feet.

        Args:
            p_com0: (3,) measured CoM; p_com_ref: (h + 1, 3); p_foot_ref: (h, 2, 3);
            contact: (h, 2) stance mask.
        """
        p_foot_ref = np.asarray(p_foot_ref, dtype=float)
        h = p_foot_ref.shape[0]
        c = bool_array("contact", contact, (h, N_FEET))
        n_stance = np.maximum(c.sum(axis=1, keepdims=True), 1)
        f = np.zeros((h, N_FEET, 3))
        f[:, :, 2] = c * mass_kg * gravity_mps2 / n_stance
        p_com = np.array(float_array("p_com_ref", p_com_ref, (h + 1, 3)))
        p_com[0] = float_array("p_com0", p_com0, (3,))
        return cls(f=f, tau=np.zeros((h, N_FEET, 3)), p_foot=p_foot_ref.copy(), p_com=p_com)


def shift_iterate(
    previous: KDIterate,
    previous_dts_s: np.ndarray,
    previous_contact: np.ndarray,
    elapsed_s: float,
    dts_s: np.ndarray,
    contact: np.ndarray,
    fallback: KDIterate,
) -> KDIterate:
    """The previous plan moved onto a new horizon that starts ``elapsed_s`` later: the
    warm start of a replan (the shifted solution of a real-time iteration).

    A stage takes the previous plan's wrench and foot position at its mid-time where the
    previous horizon covers it and the foot's contact there agrees; else the foot keeps
    ``fallback``'s (:meth:`KDIterate.initial`). The CoM path is the previous one
    interpolated at the new stage boundaries, ``fallback``'s past the previous horizon,
    and ``fallback.p_com[0]`` (the measurement) at the start.

    Args:
        previous: the last plan's iterate; previous_dts_s (h,), previous_contact (h, 2):
            its stage durations [s] and stance mask.
        elapsed_s: time from the start of the previous horizon to the new one [s].
        dts_s (h,), contact (h, 2): the new horizon's.
        fallback: the iterate used where the previous plan says nothing.
    """
    t_prev = np.concatenate([[0.0], np.cumsum(previous_dts_s)])  # (h'+1,) boundaries
    t_new = elapsed_s + np.concatenate([[0.0], np.cumsum(dts_s)])  # (h+1,)
    mid = 0.5 * (t_new[:-1] + t_new[1:])
    j = np.searchsorted(t_prev, mid, side="right") - 1  # previous stage of each new one
    inside = (j >= 0) & (j < previous_dts_s.size)
    j = np.clip(j, 0, previous_dts_s.size - 1)
    same = inside[:, None] & (previous_contact[j] == contact)  # (h, 2)
    keep = same[:, :, None]
    p_com = fallback.p_com.copy()
    covered = t_new[1:] <= t_prev[-1]
    for a in range(3):
        p_com[1:, a] = np.where(
            covered, np.interp(t_new[1:], t_prev, previous.p_com[:, a]), p_com[1:, a]
        )
    return KDIterate(
        f=np.where(keep, previous.f[j], fallback.f),
        tau=np.where(keep, previous.tau[j], fallback.tau),
        p_foot=np.where(keep, previous.p_foot[j], fallback.p_foot),
        p_com=p_com,
    )


@dataclass(frozen=True)
class KDStep:
    """Solution of one CMPC sub-problem.

    Attributes:
        delta_f: (h, 2, 3) force search direction [N].
        delta_tau: (h, 2, 3) moment search direction [N m].
        delta_p_foot: (h, 2, 3) foot-position search direction [m].
        delta_p_com: (h + 1, 3) CoM search direction [m]; row 0 is zero.
        states: (h + 1, 12) predicted ``[H; l_G; k_G]``, ``states[0] = x0``.
        solution: the backend's :class:`QPSolution`.
        max_delta_pos_m: ``max |delta p_f|, |delta p_c|``.
        max_delta_force_n: ``max |delta f|``.
        max_delta_moment_nm: ``max |delta tau|``.
    """

    delta_f: np.ndarray
    delta_tau: np.ndarray
    delta_p_foot: np.ndarray
    delta_p_com: np.ndarray
    states: np.ndarray
    solution: QPSolution
    max_delta_pos_m: float
    max_delta_force_n: float
    max_delta_moment_nm: float

    def converged(self, tol: KDTolerances | None = None) -> bool:
        """Whether every search direction is within the tolerances (Table X)."""
        tol = tol or KDTolerances()
        return (
            self.max_delta_pos_m <= tol.position_m
            and self.max_delta_force_n <= tol.force_n
            and self.max_delta_moment_nm <= tol.moment_nm
        )


__all__ = ["KDIterate", "KDStep", "KDTolerances", "shift_iterate"]
