"""The linear inverted pendulum (LIP) in closed form: the CoM over a point (or line) foot
at constant height ``z0``, ``p'' = omega^2 (p - p_foot)`` with ``omega = sqrt(g / z0)``.

Used for footholds (Raibert gains, ``srbm``), the lateral sway reference of ``kd`` and the
multi-step footstep preview. Lengths in m, times in s.
"""

from __future__ import annotations

import math

import numpy as np

from gaitnet_mpc.geometry import GRAVITY_MPS2


def lip_frequency(com_height_m: float) -> float:
    """``omega = sqrt(g / z0)`` [1/s] of a LIP of height ``com_height_m`` above its foot."""
    return math.sqrt(GRAVITY_MPS2 / com_height_m)


def lip_propagate(
    p_m: np.ndarray, v_mps: np.ndarray, foot_m: np.ndarray, omega: float, t_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """CoM (position, velocity) after ``t_s`` on the LIP about ``foot_m`` (exact):
    ``p(t) = f + (p - f) cosh(w t) + v sinh(w t) / w``, ``v(t) = (p - f) w sinh(w t) +
    v cosh(w t)``."""
    ch, sh = math.cosh(omega * t_s), math.sinh(omega * t_s)
    d = p_m - foot_m
    return foot_m + d * ch + v_mps * (sh / omega), d * (omega * sh) + v_mps * ch


def lip_gains(z0_m: float, step_s: float, half_width_m: float) -> tuple[float, float, float, float]:
    """LIP foothold gains for CoM height ``z0_m`` and step (stance) time ``step_s``.

    Returns ``(omega, k_v, lateral_offset, cmd_scale)``: the LIP frequency [1/s], the
    Raibert velocity gain ``k_v = coth(omega T)/omega - T/2`` [s] (deadbeat: after one
    stance of ``T`` on the new foot, a velocity error is cancelled), the heuristic's lateral
    offset [m] whose fixed point is the symmetric sway orbit with the feet ``half_width_m``
    beside the CoM (orbit touchdown speed ``V = omega d tanh(omega T / 2)``) and the factor
    applied to the velocity command inside the heuristic [-] (see below).
    """
    omega = lip_frequency(z0_m)
    x = omega * step_s
    k_v = 1.0 / (omega * math.tanh(x)) - 0.5 * step_s
    t = math.tanh(0.5 * x)
    # Walking at mean speed v on the LIP, the CoM is fastest at touchdown:
    # v_td = v (x/2) coth(x/2) (8 % above v here). The heuristic's fixed point is that
    # orbit (foothold v T / 2 ahead of the CoM) when its velocity command is scaled by
    # kappa + (kappa - 1) T / (2 k_v); with the plain command its fixed point is an orbit
    # about 10 % slower than commanded, which the MPC then has to make up with the CoP.
    kappa = 0.5 * x / math.tanh(0.5 * x)
    cmd_scale = kappa + (kappa - 1.0) * step_s / (2.0 * k_v)
    return omega, k_v, half_width_m * (1.0 - t * t) / 2.0, cmd_scale


def lip_sway_orbit(
    side: np.ndarray, half_width_m: float, omega: float, tau_s: np.ndarray, step_s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Lateral offset and velocity of the periodic LIP sway of a gait with the feet at
    ``+-half_width_m`` beside a centre line (a line foot has no roll moment):
    ``y = s b (1 - cosh(w (tau - T/2)) / cosh(w T / 2))``,
    ``y' = -s b w sinh(w (tau - T/2)) / cosh(w T / 2)``, with ``s = side`` (+1 in left
    stance, -1 in right stance, 0 without a stance foot), ``tau`` the time in a step of
    length ``T`` (arrays of one shape)."""
    b = half_width_m
    den = np.cosh(omega * step_s / 2)
    y_off = side * b * (1.0 - np.cosh(omega * (tau_s - step_s / 2)) / den)
    v_off = -side * b * omega * np.sinh(omega * (tau_s - step_s / 2)) / den
    return y_off, v_off


def sway_phases(
    times_s: np.ndarray,
    dts_s: np.ndarray,
    contact: np.ndarray,
    time_in_step_s: float,
    stages_per_step: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where in its step each of a horizon's ``h + 1`` boundaries lies, for
    :func:`lip_sway_orbit`: ``side`` (+1 left stance, -1 right, 0 none), the time in the
    step ``tau_s`` and the step's length ``step_s`` (``stages_per_step`` of its stages).

    Args:
        times_s: (h + 1,) boundary times from now; dts_s: (h,) stage lengths;
        contact: (h, 2) stance mask (left, right); time_in_step_s: the current step's age.
    """
    h = dts_s.size
    start = np.empty(h)  # step start time and length of each stage's step
    length = np.empty(h)
    s0 = -float(time_in_step_s)
    for k in range(h):
        if k > 0 and not np.array_equal(contact[k], contact[k - 1]):
            s0 = float(times_s[k])
        start[k] = s0
    for k in range(h):
        first = int(np.searchsorted(times_s, start[k] - 1e-9)) if start[k] >= 0 else 0
        length[k] = stages_per_step * float(dts_s[min(first, h - 1)])
    side = np.where(contact[:, 0] & ~contact[:, 1], 1.0, np.where(contact[:, 1], -1.0, 0.0))
    kk = np.minimum(np.arange(h + 1), h - 1)
    return side[kk], times_s - start[kk], length[kk]
