"""Piecewise quintic Hermite polynomials: position, velocity and acceleration prescribed at
both ends of each piece (the building block of :class:`gaitnet_mpc.gait.SwingTrajectory`).

A piece on ``[t_i, t_i + D]`` is ``p(t) = sum_k c_k (t - t_i)^k``, ``k = 0..5``, with
``(p, v, a)`` met at both ends (:func:`quintic_coeffs`); :class:`PiecewiseQuintic` strings
pieces together, evaluates them and their first two derivatives, cuts and splices them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PiecewiseQuintic", "quintic_coeffs"]


def quintic_coeffs(
    p0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    p1: np.ndarray,
    v1: np.ndarray,
    a1: np.ndarray,
    duration_s: float,
) -> np.ndarray:
    """(6, d) coefficients c_k of ``p(s) = Σ c_k s^k``, s in [0, D], meeting (p, v, a) at ends.

    All boundary arrays have shape (d,).
    """
    D = duration_s
    dp = p1 - p0
    c3 = (20.0 * dp - (8.0 * v1 + 12.0 * v0) * D - (3.0 * a0 - a1) * D**2) / (2.0 * D**3)
    c4 = (-30.0 * dp + (14.0 * v1 + 16.0 * v0) * D + (3.0 * a0 - 2.0 * a1) * D**2) / (2.0 * D**4)
    c5 = (12.0 * dp - 6.0 * (v1 + v0) * D + (a1 - a0) * D**2) / (2.0 * D**5)
    return np.stack([p0, v0, 0.5 * a0, c3, c4, c5])  # (6, d)


#: Derivative ``d`` of the monomials ``s^k`` (k = 0..5) is ``_FACTOR[d] * s**_POWER[d]``
#: (the factor is 0 where the monomial's derivative vanishes).
_K = np.arange(6)
_FACTOR = (np.ones(6), _K.astype(float), (_K * (_K - 1)).astype(float))
_POWER = (_K, np.maximum(_K - 1, 0), np.maximum(_K - 2, 0))


class PiecewiseQuintic:
    """Piecewise quintic in d dimensions: breaks (n+1,), coefficients (n, 6, d)."""

    def __init__(self, breaks: np.ndarray, coeffs: np.ndarray) -> None:
        self.breaks = breaks  # (n+1,)
        self.coeffs = coeffs  # (n, 6, d)

    @classmethod
    def single(cls, t0: float, t1: float, coeffs: np.ndarray) -> PiecewiseQuintic:
        return cls(np.array([t0, t1]), coeffs[None])

    def eval(self, t: np.ndarray, deriv: int = 0) -> np.ndarray:
        """(N, d) value (deriv 0), velocity (1) or acceleration (2) at times t (N,)."""
        return self.eval_derivs(t, (deriv,))[0]

    def eval_derivs(self, t: np.ndarray, derivs: tuple[int, ...]) -> list[np.ndarray]:
        """:meth:`eval` for each of ``derivs`` at times t (N,), locating the pieces once."""
        n = len(self.breaks) - 1
        idx = np.searchsorted(self.breaks, t, side="right") - 1  # (N,)
        idx = np.minimum(np.maximum(idx, 0), n - 1)
        s = (t - self.breaks[idx])[:, None]  # (N, 1)
        coeffs = self.coeffs[idx]
        return [
            np.einsum("nk,nkd->nd", _FACTOR[d] * s ** _POWER[d], coeffs)  # (N, 6)·(N, 6, d)
            for d in derivs
        ]

    def value_velocity_acceleration(self, t: float) -> np.ndarray:
        """(3, d) value, velocity and acceleration at one time ``t``: :meth:`eval_derivs`
        with ``(0, 1, 2)`` for a single time, as one (3, 6) x (6, d) product (the 1 kHz
        swing path)."""
        n = len(self.breaks) - 1
        i = min(max(int(np.searchsorted(self.breaks, t, side="right")) - 1, 0), n - 1)
        s = t - float(self.breaks[i])
        s2 = s * s
        basis = np.array(
            [
                [1.0, s, s2, s2 * s, s2 * s2, s2 * s2 * s],
                [0.0, 1.0, 2.0 * s, 3.0 * s2, 4.0 * s2 * s, 5.0 * s2 * s2],
                [0.0, 0.0, 2.0, 6.0 * s, 12.0 * s2, 20.0 * s2 * s],
            ]
        )
        return basis @ self.coeffs[i]

    def truncated(self, t_cut: float) -> PiecewiseQuintic:
        """The pieces before ``t_cut`` (the last one ends at ``t_cut``)."""
        n_keep = min(int(np.searchsorted(self.breaks, t_cut, side="left")), len(self.coeffs))
        if n_keep == 0:
            return PiecewiseQuintic(self.breaks[:1].copy(), self.coeffs[:0].copy())
        breaks = np.append(self.breaks[:n_keep], t_cut)
        return PiecewiseQuintic(breaks, self.coeffs[:n_keep].copy())

    def then(self, other: PiecewiseQuintic) -> PiecewiseQuintic:
        """Concatenation; ``other`` must start where ``self`` ends."""
        if len(self.coeffs) == 0:
            return other
        breaks = np.concatenate([self.breaks, other.breaks[1:]])
        keep = breaks[1:] > breaks[:-1]  # drop zero-length pieces
        coeffs = np.concatenate([self.coeffs, other.coeffs])[keep]
        return PiecewiseQuintic(np.append(breaks[:-1][keep], breaks[-1]), coeffs)
