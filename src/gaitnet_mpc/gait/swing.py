"""Swing-foot trajectories from lift-off to the planned foothold, with obstacle clearance.

The swing lasts one footstep, Δt = h'·dt (paper Sec. IV-B1), and is tracked by the low-level
joint-PD swing-leg control (Sec. III).  The trajectory is made of quintic Hermite pieces
(position, velocity and acceleration prescribed at both ends of each piece):

* horizontal (x, y): one minimum-jerk quintic from ``p0`` to ``p1`` with zero velocity and
  acceleration at lift-off and touchdown, ``p(s) = p0 + (p1 - p0) σ(s)``,
  ``σ(s) = 10 s³ - 15 s⁴ + 6 s⁵``, ``s = t / T``; when an obstacle is close to lift-off or
  touchdown, the quintic runs on ``[λT, (1-λ)T]`` and the foot moves only vertically before
  and after it (λ is the smallest of six values 0, ..., ``max_lift_fraction`` giving a clearing
  apex at most ``apex_height_m`` above the highest obstacle requirement);
* vertical (z): a rise from ``p0_z`` to the apex ``z_apex`` at mid-swing (zero vertical
  velocity and acceleration at both ends) and a descent from the apex to ``p1_z`` ending with
  vertical velocity ``-touchdown_speed_mps`` and zero acceleration (C² at the apex).

The apex is ``max(p0_z, p1_z) + apex_height_m``, raised where needed so that the foot point
stays ``clearance_m`` above every obstacle top while the foot (a segment of half-length
``foot_half_length_m`` along world x) overlaps the obstacle's x-interval.  Because the
vertical position is linear in ``z_apex`` with non-negative weights, the smallest such apex
is found exactly on a dense time grid (the obstacle intervals are widened by the grid's
horizontal spacing, so the check holds between grid points too).  The apex is capped at
``max_apex_rise_m`` above ``max(p0_z, p1_z)``; :attr:`SwingTrajectory.clearance_ok` reports
whether the final trajectory clears every obstacle.

:meth:`SwingTrajectory.retarget` moves the touchdown point mid-swing while keeping position,
velocity and acceleration continuous at the retarget time.

:func:`swing_profile` is the obstacle-free trajectory in closed form (``σ`` from
:func:`min_jerk`), vectorised over many swings at once for the reference trajectory; it
equals :meth:`SwingTrajectory.position` to rounding (1e-12 m, tested) without building the
piecewise polynomials (~0.5 ms per trajectory).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from gaitnet_mpc.config import bounded, check_ranges
from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.gait.quintic import PiecewiseQuintic, quintic_coeffs

__all__ = ["SwingConfig", "SwingTrajectory", "min_jerk", "obstacle_array", "swing_profile"]

#: Samples of the clearance check over one swing.
_N_CHECK = 401
#: Tolerance [m] of the clearance check.
_CLEAR_TOL_M = 1e-9
#: Range of a swing height above the higher end [m]: the humanoid's hip is 0.42 m high.
_HEIGHT, _HEIGHT_REASON = "[0, 0.4] m", "the humanoid's hip is 0.42 m high"


# ----------------------------------------------------------------------------------------------
# Input checks
# ----------------------------------------------------------------------------------------------


def _point(value: ArrayLike, field: str) -> np.ndarray:
    try:
        p = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(field, value, "a finite (3,) point [m]") from None
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ConfigError(field, value, "a finite (3,) point [m]")
    return p.copy()


def _scalar(value: object, field: str, lo: float, expected: str, strict: bool = False) -> float:
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    if ok:
        v = float(value)  # type: ignore[arg-type]
        ok = math.isfinite(v) and (v > lo if strict else v >= lo)
    if not ok:
        raise ConfigError(field, value, expected)
    return v


def obstacle_array(obstacles: Iterable[Any]) -> np.ndarray:
    """(n, 3) array of ``(x_min, x_max, top_z)`` [m] from tuples or terrain ``Obstacle``s.

    An element may be a 3-sequence ``(x_min, x_max, top_z)`` or any object with ``x_min``,
    ``x_max`` and ``z_top_m`` attributes (:class:`gaitnet_mpc.terrain.Obstacle`).
    """
    rows: list[tuple[float, float, float]] = []
    for i, ob in enumerate(obstacles):
        if all(hasattr(ob, a) for a in ("x_min", "x_max", "z_top_m")):
            row = (ob.x_min, ob.x_max, ob.z_top_m)
        else:
            row = ob
        try:
            r = np.asarray(row, dtype=float)
        except (TypeError, ValueError):
            r = np.empty(0)
        if r.shape != (3,) or not np.all(np.isfinite(r)) or not r[0] < r[1]:
            raise ConfigError(f"obstacles[{i}]", ob, "(x_min, x_max, top_z) [m] with x_min < x_max")
        rows.append((float(r[0]), float(r[1]), float(r[2])))
    return np.array(rows, dtype=float).reshape(-1, 3)


# ----------------------------------------------------------------------------------------------
# Swing trajectory
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SwingConfig:
    """Shape parameters of swing trajectories (one per controller).

    Attributes:
        apex_height_m: apex above ``max(p0_z, p1_z)`` without obstacles [m].
        clearance_m: margin of the foot point above obstacle tops [m] (add the sole offset
            of the foot point here if it is not on the sole).
        foot_half_length_m: half-length of the foot along world x [m] (toe/heel extent).
        touchdown_speed_mps: downward vertical speed at touchdown [m/s] (0 = soft landing).
        max_apex_rise_m: cap of the apex above ``max(p0_z, p1_z)`` [m].
        max_lift_fraction: largest fraction of the swing time, at each end, during which the
            foot may move only vertically (used when an obstacle is close to lift-off or
            touchdown) [-].
    """

    apex_height_m: float = bounded(0.06, _HEIGHT, "a height", _HEIGHT_REASON)
    clearance_m: float = bounded(
        0.02, "[0, 0.3] m", "a margin", "0.3 m is above the humanoid's knee"
    )
    foot_half_length_m: float = bounded(0.0, "[0, 0.3] m", "a length", "humanoid3d: 0.075 m")
    touchdown_speed_mps: float = bounded(0.0, "[0, 2] m/s", "a speed", "2 m/s: a 0.2 m drop")
    max_apex_rise_m: float = bounded(0.30, _HEIGHT, "a height", _HEIGHT_REASON)
    max_lift_fraction: float = bounded(
        0.25, "[0, 0.4]", "a fraction", "at each end; 0.4 leaves 20 %"
    )

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.max_apex_rise_m < self.apex_height_m:
            raise ConfigError("max_apex_rise_m", self.max_apex_rise_m, ">= apex_height_m")

    def trajectory(
        self,
        p0_world_m: ArrayLike,
        p1_world_m: ArrayLike,
        duration_s: float,
        obstacles: Iterable[Any] = (),
    ) -> SwingTrajectory:
        """A :class:`SwingTrajectory` with these parameters."""
        return SwingTrajectory(
            p0_world_m,
            p1_world_m,
            duration_s,
            self.apex_height_m,
            obstacles=obstacles,
            clearance_m=self.clearance_m,
            foot_half_length_m=self.foot_half_length_m,
            touchdown_speed_mps=self.touchdown_speed_mps,
            max_apex_rise_m=self.max_apex_rise_m,
            max_lift_fraction=self.max_lift_fraction,
        )


@dataclass(frozen=True)
class _Plan:
    """A candidate remainder of the swing from the re-plan time on."""

    xy: PiecewiseQuintic
    z: PiecewiseQuintic
    apex_z_m: float
    clearance_ok: bool
    target_apex_z_m: float
    direct_descent: bool = False


class SwingTrajectory:
    """Swing-foot position over ``t`` in [0, T] (T = h'·dt, Sec. IV-B1), world frame.

    Args:
        p0_world_m: (3,) lift-off point [m].
        p1_world_m: (3,) planned foothold (touchdown point) [m].
        duration_s: swing duration T [s] (> 0).
        apex_height_m: apex above ``max(p0_z, p1_z)`` [m] without obstacles.
        obstacles: ``(x_min, x_max, top_z)`` [m] world-x intervals with known top height, or
            terrain ``Obstacle`` objects; obstacles are assumed to span the foot's lane in y.
        clearance_m: margin of the foot point above obstacle tops [m].
        foot_half_length_m: foot half-length along world x [m].
        touchdown_speed_mps: downward vertical speed at touchdown [m/s].
        max_apex_rise_m: cap of the apex above ``max(p0_z, p1_z)`` [m].
        max_lift_fraction: largest fraction of T, at each end, during which the foot may move
            only vertically when an obstacle is near lift-off or touchdown [-].

    :meth:`position`, :meth:`velocity` and :meth:`acceleration` take a scalar time (-> (3,))
    or an array of N times (-> (N, 3)); times are clamped to [0, T].
    """

    def __init__(
        self,
        p0_world_m: ArrayLike,
        p1_world_m: ArrayLike,
        duration_s: float,
        apex_height_m: float = 0.06,
        *,
        obstacles: Iterable[Any] = (),
        clearance_m: float = 0.02,
        foot_half_length_m: float = 0.0,
        touchdown_speed_mps: float = 0.0,
        max_apex_rise_m: float = 0.30,
        max_lift_fraction: float = 0.25,
    ) -> None:
        self._p0 = _point(p0_world_m, "p0_world_m")  # (3,)
        self._p1 = _point(p1_world_m, "p1_world_m")  # (3,)
        self._T = _scalar(duration_s, "duration_s", 0.0, "a finite duration > 0 s", strict=True)
        self.config = SwingConfig(
            apex_height_m=apex_height_m,
            clearance_m=clearance_m,
            foot_half_length_m=foot_half_length_m,
            touchdown_speed_mps=touchdown_speed_mps,
            max_apex_rise_m=max_apex_rise_m,
            max_lift_fraction=max_lift_fraction,
        )
        self._obstacles = obstacle_array(obstacles)  # (n, 3)
        empty = PiecewiseQuintic(np.zeros(1), np.zeros((0, 6, 1)))
        self._xy = PiecewiseQuintic(np.zeros(1), np.zeros((0, 6, 2)))
        self._z = empty
        self._apex_z_m = float("nan")
        self._clearance_ok = True
        self._apply(0.0, self._p0, np.zeros(3), np.zeros(3))

    # ------------------------------------------------------------------ properties

    @property
    def duration_s(self) -> float:
        """Swing duration T [s]."""
        return self._T

    @property
    def p0_world_m(self) -> np.ndarray:
        """(3,) lift-off point [m]."""
        return self._p0.copy()

    @property
    def p1_world_m(self) -> np.ndarray:
        """(3,) current touchdown target [m]."""
        return self._p1.copy()

    @property
    def obstacles(self) -> np.ndarray:
        """(n, 3) obstacle intervals ``(x_min, x_max, top_z)`` [m]."""
        return self._obstacles.copy()

    @property
    def apex_z_m(self) -> float:
        """Height of the last planned apex [m] (world z)."""
        return self._apex_z_m

    @property
    def clearance_ok(self) -> bool:
        """True iff the (remaining) trajectory clears every obstacle by ``clearance_m``."""
        return self._clearance_ok

    # ------------------------------------------------------------------ evaluation

    def _eval(self, t: ArrayLike, deriv: int) -> np.ndarray:
        t_arr = np.asarray(t, dtype=float)
        tc = np.clip(t_arr.reshape(-1), 0.0, self._T)  # (N,)
        out = np.concatenate([self._xy.eval(tc, deriv), self._z.eval(tc, deriv)], axis=1)
        return out[0] if t_arr.ndim == 0 else out.reshape((*t_arr.shape, 3))

    def sample(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, velocity, acceleration) (3,) each at one time [m, m/s, m/s²], as
        :meth:`position`, :meth:`velocity` and :meth:`acceleration` give them."""
        tc = min(max(float(t_s), 0.0), self._T)
        pva = np.hstack(
            [self._xy.value_velocity_acceleration(tc), self._z.value_velocity_acceleration(tc)]
        )  # (3, 3): rows p, v, a
        return pva[0], pva[1], pva[2]

    def position(self, t_s: ArrayLike) -> np.ndarray:
        """Foot position [m]: (3,) for scalar ``t_s``, (N, 3) for (N,) times."""
        return self._eval(t_s, 0)

    def velocity(self, t_s: ArrayLike) -> np.ndarray:
        """Foot velocity [m/s] at the clamped times, same shapes as :meth:`position`."""
        return self._eval(t_s, 1)

    def acceleration(self, t_s: ArrayLike) -> np.ndarray:
        """Foot acceleration [m/s²] at the clamped times, same shapes as :meth:`position`."""
        return self._eval(t_s, 2)

    # ------------------------------------------------------------------ planning

    def _required_z(self, x: np.ndarray, widen_m: float) -> np.ndarray:
        """(N,) lowest allowed foot-point height at foot x-positions (N,); -inf if free."""
        req = np.full(x.shape, -np.inf)
        half = self.config.foot_half_length_m + widen_m
        for x_min, x_max, top in self._obstacles:
            overlap = (x + half >= x_min) & (x - half <= x_max)
            req = np.where(overlap, np.maximum(req, top + self.config.clearance_m), req)
        return req

    def _horizontal(
        self, t_a: float, p: np.ndarray, v: np.ndarray, a: np.ndarray, lift_s: float
    ) -> PiecewiseQuintic | None:
        """xy on [t_a, T]: still until ``lift_s`` (if at rest), quintic, still for ``lift_s``.

        None if the moving window would be shorter than half the remaining time.
        """
        T = self._T
        at_rest = not (np.any(np.abs(v) > 1e-12) or np.any(np.abs(a) > 1e-12))
        t_s = max(t_a, lift_s) if at_rest else t_a
        t_e = T - lift_s
        if t_e - t_s < 0.5 * (T - t_a) and lift_s > 0.0:
            return None
        zero = np.zeros(2)
        out = PiecewiseQuintic(np.array([t_a]), np.zeros((0, 6, 2)))
        if t_s > t_a:
            out = PiecewiseQuintic.single(
                t_a, t_s, quintic_coeffs(p, zero, zero, p, zero, zero, 1.0)
            )
        p1 = self._p1[:2]
        out = out.then(
            PiecewiseQuintic.single(t_s, t_e, quintic_coeffs(p, v, a, p1, zero, zero, t_e - t_s))
        )
        if t_e < T:
            rest = quintic_coeffs(p1, zero, zero, p1, zero, zero, 1.0)
            out = out.then(PiecewiseQuintic.single(t_e, T, rest))
        return out

    def _vertical(self, xy: PiecewiseQuintic, t_a: float, z_state: np.ndarray) -> _Plan:
        """z on [t_a, T] from the state (z, vz, az) at t_a, for the horizontal path ``xy``."""
        cfg = self.config
        T = self._T
        z1 = self._p1[2]
        end = (np.array([z1]), np.array([-cfg.touchdown_speed_mps]), np.zeros(1))
        start = (np.array([z_state[0]]), np.array([z_state[1]]), np.array([z_state[2]]))
        base_z = max(self._p0[2], z1)
        cap = base_z + cfg.max_apex_rise_m
        rising = t_a < 0.5 * T - 1e-12
        floor = base_z + cfg.apex_height_m if rising else float(z_state[0])
        t_mid = 0.5 * T if rising else t_a + 0.5 * (T - t_a)

        def pieces(apex: float) -> PiecewiseQuintic:
            top = (np.array([apex]), np.zeros(1), np.zeros(1))
            up = PiecewiseQuintic.single(t_a, t_mid, quintic_coeffs(*start, *top, t_mid - t_a))
            down = PiecewiseQuintic.single(t_mid, T, quintic_coeffs(*top, *end, T - t_mid))
            return up.then(down)

        if len(self._obstacles) == 0 and rising:  # nothing to clear: no grid needed
            return _Plan(xy, pieces(floor), floor, True, floor)
        single = PiecewiseQuintic.single(t_a, T, quintic_coeffs(*start, *end, T - t_a))
        if len(self._obstacles) == 0:
            return _Plan(xy, single, self._apex_z_m, True, floor, direct_descent=True)

        grid = np.linspace(t_a, T, _N_CHECK)  # (N,)
        x = xy.eval(grid)[:, 0]  # (N,)
        widen = float(np.max(np.abs(np.diff(x)), initial=0.0))
        req_solve = self._required_z(x, widen) + _CLEAR_TOL_M  # (N,)
        req_check = self._required_z(x, 0.0)  # (N,)
        highest = float(np.max(req_check, initial=-np.inf))
        target = max(floor, highest + cfg.apex_height_m)
        # Already past mid-swing: descend directly unless an obstacle needs a new apex.
        if not rising and np.all(single.eval(grid)[:, 0] >= req_check - _CLEAR_TOL_M):
            return _Plan(xy, single, self._apex_z_m, True, target, direct_descent=True)

        # z(t) = a(t) + b(t) · apex with b >= 0: smallest apex meeting every requirement.
        a = pieces(0.0).eval(grid)[:, 0]  # (N,)
        b = pieces(1.0).eval(grid)[:, 0] - a  # (N,)
        active = np.isfinite(req_solve) & (b > 1e-9)
        need = float(np.max((req_solve[active] - a[active]) / b[active], initial=-np.inf))
        apex = min(max(floor, need), max(cap, floor))
        z = pieces(apex)
        ok = bool(np.all(z.eval(grid)[:, 0] >= req_check - _CLEAR_TOL_M))
        return _Plan(xy, z, apex, ok, target)

    def _apply(self, t_a: float, p: np.ndarray, v: np.ndarray, a: np.ndarray) -> None:
        """Re-plan [t_a, T] from the state (p, v, a) (each (3,)) at t_a and splice it in.

        Tries horizontal lift/land pauses of 0, ..., ``max_lift_fraction`` · T and keeps the
        first plan that clears every obstacle with an apex at most ``apex_height_m`` above
        the highest requirement (else the clearing plan with the lowest apex).
        """
        fractions = np.linspace(0.0, self.config.max_lift_fraction, 6)
        if len(self._obstacles) == 0:
            fractions = fractions[:1]
        best: _Plan | None = None
        for frac in fractions:
            xy = self._horizontal(t_a, p[:2], v[:2], a[:2], float(frac) * self._T)
            if xy is None:
                continue
            plan = self._vertical(xy, t_a, np.array([p[2], v[2], a[2]]))
            low = plan.direct_descent or plan.apex_z_m <= plan.target_apex_z_m + 1e-9
            if plan.clearance_ok and low:
                best = plan
                break
            if best is None or (plan.clearance_ok, -plan.apex_z_m) > (
                best.clearance_ok,
                -best.apex_z_m,
            ):
                best = plan
        assert best is not None  # fraction 0 always gives a plan
        self._xy = self._xy.truncated(t_a).then(best.xy)
        self._z = self._z.truncated(t_a).then(best.z)
        self._apex_z_m = best.apex_z_m
        self._clearance_ok = best.clearance_ok

    def retarget(
        self,
        p1_world_m: ArrayLike,
        t_now_s: float,
        *,
        obstacles: Iterable[Any] | None = None,
        min_remaining_s: float = 1e-3,
    ) -> bool:
        """Move the touchdown target to ``p1_world_m`` (3,) from time ``t_now_s`` [s] on.

        The trajectory before ``t_now_s`` is kept; after it, the horizontal part is a quintic
        from the current (position, velocity, acceleration) to the new target at rest, and
        the vertical part is re-planned (rise to a new apex at mid-swing if ``t_now_s < T/2``;
        otherwise a direct descent, or a new apex when an obstacle requires it).  Position,
        velocity and acceleration are continuous at ``t_now_s``.  ``obstacles`` replaces
        the obstacle list (None keeps it).

        Returns False (and changes nothing) if less than ``min_remaining_s`` of the swing is
        left, True otherwise.
        """
        p1 = _point(p1_world_m, "p1_world_m")
        t = min(max(_scalar(t_now_s, "t_now_s", -math.inf, "a finite time [s]"), 0.0), self._T)
        if self._T - t < min_remaining_s:
            return False
        if obstacles is not None:
            self._obstacles = obstacle_array(obstacles)
        p, v, a = (self._eval(t, d) for d in range(3))  # each (3,)
        self._p1 = p1
        self._apply(t, p, v, a)
        return True

    def retime(self, duration_s: float, t_now_s: float) -> None:
        """Make the swing last ``duration_s`` [s] from lift-off, re-planning it from time
        ``t_now_s`` [s] on to the same target (position, velocity and acceleration stay
        continuous at ``t_now_s``, as in :meth:`retarget`). ``duration_s`` must exceed
        ``t_now_s``."""
        t = _scalar(t_now_s, "t_now_s", 0.0, "a time >= 0 s")
        T = _scalar(duration_s, "duration_s", t, f"a duration > t_now_s = {t!r} s", strict=True)
        p, v, a = (self._eval(min(t, self._T), d) for d in range(3))  # each (3,)
        self._T = T
        self._apply(t, p, v, a)

    def __repr__(self) -> str:
        return (
            f"SwingTrajectory(p0={self._p0.tolist()}, p1={self._p1.tolist()}, "
            f"T={self._T:.4f} s, apex_z={self._apex_z_m:.4f} m, clearance_ok={self._clearance_ok})"
        )


# ----------------------------------------------------------------------------------------------
# Obstacle-free swing path in closed form
# ----------------------------------------------------------------------------------------------


def min_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk blend ``σ(s) = 10 s³ - 15 s⁴ + 6 s⁵`` (zero rate and acceleration at 0, 1)."""
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def swing_profile(
    p0_m: np.ndarray, p1_m: np.ndarray, phase: np.ndarray, apex_height_m: float
) -> np.ndarray:
    """Obstacle-free path of :class:`SwingTrajectory` (zero touchdown speed), vectorised.

    x-y: ``p0 + (p1 - p0) σ(s)``; z: rise from ``z0`` to the apex ``max(z0, z1) +
    apex_height_m`` over ``s`` in [0, 1/2] and descent to ``z1`` over [1/2, 1], each
    ``σ``-shaped. ``s = 0`` gives ``p0`` exactly and ``s = 1`` gives ``p1`` up to rounding.

    Args:
        p0_m: (N, 3) lift-off points [m].
        p1_m: (N, 3) touchdown points [m].
        phase: (N,) normalised swing time ``s = t / T`` in [0, 1].
        apex_height_m: apex above ``max(z0, z1)`` [m].

    Returns:
        (N, 3) foot positions [m].
    """
    s = np.clip(phase, 0.0, 1.0)
    out = p0_m + (p1_m - p0_m) * min_jerk(s)[:, None]
    z0, z1 = p0_m[:, 2], p1_m[:, 2]
    apex = np.maximum(z0, z1) + apex_height_m
    rise = s < 0.5
    out[:, 2] = np.where(
        rise,
        z0 + (apex - z0) * min_jerk(np.minimum(2.0 * s, 1.0)),
        apex + (z1 - apex) * min_jerk(np.maximum(2.0 * s - 1.0, 0.0)),
    )
    return out
