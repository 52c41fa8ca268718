"""Foot events of an episode (``events.csv``): touchdowns, lift-offs, slips, pivots, scuffs.

Built from what a runner has at every control tick, the measured :class:`RobotState`
(``foot_contact``, ``foot_pos_world_m``, ``foot_yaw_rad``), and optionally the controller's
planned touchdown time of each swinging foot. Per foot, a *contact* runs from the first
tick the foot touches terrain until it has been off the terrain for ``min_air_s`` (shorter
gaps are contact chatter, as ``SimConfig.touchdown_min_air_s``). Rows, one per event:

======================  =========================================  ====================
event                   row time and position                      quantity: value
======================  =========================================  ====================
touchdown               first tick of a contact that lasts         ``impact_speed_mps``
                        ``min_stance_s`` (a stance)
liftoff                 last contact tick of that stance           ``stance_s``
slip                    first tick the stance foot centre is more  ``travel_m``: the
                        than ``slip_m`` (horizontally) from where  largest over the
                        it stood ``min_stance_s`` after touchdown  stance
                        (the landing transient excluded);
                        position where it is at the stance's last
                        tick
pivot                   as slip, for the foot yaw and              ``yaw_change_rad``
                        ``pivot_rad``
scuff                   first tick of a contact shorter than       ``contact_s``
                        ``min_stance_s`` (touched and left again)
scuff                   first tick of a contact of a foot the      ``early_s``: planned
                        controller still swings, more than         touchdown - t
                        ``scuff_lead_s`` before its planned
                        touchdown (needs ``swing_until_s``)
======================  =========================================  ====================

``impact_speed_mps`` is the foot centre's speed (3D) over the tick that ended in contact;
the touchdown position is the foot centre at that tick (as ``Simulator.footholds``). A stance
that is still open when the episode ends has its touchdown (once confirmed) and its slip
and pivot rows, but no lift-off. Feet in contact at the first tick start standing (no
touchdown row).

Typical use, once per control tick after the controller's ``compute``::

    events = EventRecorder()
    ...
    sched = controller.schedule  # kd / srbm: the swing foot lands at the step's end
    events.update(state, {sched.swing_foot: sched.step_start_time_s
                          + sched.current_step_duration_s})
    ...
    write_atomic(run_dir / "events.csv", events.to_csv())
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.geometry import wrap_angle
from gaitnet_mpc.robots import FEET
from gaitnet_mpc.state import RobotState

#: Columns of ``events.csv``.
COLUMNS = ("t_s", "event", "foot", "x_m", "y_m", "z_m", "quantity", "value")


@dataclass(frozen=True)
class EventConfig:
    """Thresholds of :class:`EventRecorder` (module docstring)."""

    min_air_s: float = 0.03  # off the terrain this long ends a contact
    min_stance_s: float = 0.05  # a shorter contact is a scuff, not a stance
    slip_m: float = 0.01  # horizontal travel of a stance foot reported as a slip
    pivot_rad: float = 0.1  # yaw change of a stance foot reported as a pivot
    scuff_lead_s: float = 0.05  # a contact this long before the planned touchdown is a scuff

    def __post_init__(self) -> None:
        for name in ("min_air_s", "min_stance_s", "slip_m", "pivot_rad", "scuff_lead_s"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ConfigError(name, value, "a finite number > 0")


@dataclass(frozen=True)
class FootEvent:
    """One row of ``events.csv``."""

    t_s: float
    event: str  # touchdown, liftoff, slip, pivot, scuff
    foot: str
    pos_world_m: tuple[float, float, float]
    quantity: str  # what ``value`` is (module docstring)
    value: float


class _Row:
    """A row that may still change (slip and pivot grow until the stance ends)."""

    def __init__(
        self, t_s: float, event: str, foot: str, pos: np.ndarray, quantity: str, value: float
    ) -> None:
        self.t_s, self.event, self.foot, self.quantity = t_s, event, foot, quantity
        self.pos = pos.copy()
        self.value = value

    def freeze(self) -> FootEvent:
        p = (float(self.pos[0]), float(self.pos[1]), float(self.pos[2]))
        return FootEvent(self.t_s, self.event, self.foot, p, self.quantity, float(self.value))


class _Contact:
    """One contact of a foot, from its first tick until it ends."""

    def __init__(self, t_s: float, pos: np.ndarray, yaw_rad: float, speed_mps: float) -> None:
        self.t0_s = t_s
        self.pos0 = pos.copy()
        self.ref_pos = pos.copy()  # where slip and pivot are measured from
        self.ref_yaw_rad = yaw_rad
        self.speed_mps = speed_mps
        self.stance = False  # lasted min_stance_s: a touchdown
        self.early = False  # reported as a scuff before the planned touchdown
        self.last_t_s = t_s  # last tick in contact
        self.last_pos = pos.copy()
        self.off_since_s: float | None = None  # first tick off the terrain, if off now
        self.slip: _Row | None = None
        self.pivot: _Row | None = None


class EventRecorder:
    """Per-tick foot event detection of one episode; :meth:`to_csv` gives ``events.csv``."""

    def __init__(self, config: EventConfig | None = None) -> None:
        self.config = config or EventConfig()
        self._rows: list[_Row] = []
        self._contact: dict[str, _Contact | None] = dict.fromkeys(FEET)
        self._prev: dict[str, tuple[float, np.ndarray]] = {}
        self._started = False

    def update(self, state: RobotState, swing_until_s: Mapping[str, float] | None = None) -> None:
        """Record the tick ``state``.

        Args:
            state: measured state of this control tick.
            swing_until_s: for each foot the controller swings now, its planned touchdown
                time [s]; a contact starting more than ``scuff_lead_s`` before it is a
                scuff. None: scuffs are found from contact durations only.
        """
        t = float(state.t_s)
        for foot in FEET:
            pos = np.asarray(state.foot_pos_world_m[foot], dtype=float)
            yaw = float(state.foot_yaw_rad[foot])
            touching = bool(state.foot_contact[foot])
            contact = self._contact[foot]
            if not self._started:
                if touching:  # standing at the start: a stance without a touchdown row
                    contact = _Contact(t, pos, yaw, math.nan)
                    contact.stance = True
            elif contact is None:
                if touching:
                    contact = self._start(foot, t, pos, yaw, swing_until_s)
            elif touching:
                self._in_contact(foot, contact, t, pos, yaw)
            else:
                if contact.off_since_s is None:
                    contact.off_since_s = t
                if t - contact.off_since_s >= self.config.min_air_s - 1e-9:
                    self._end(foot, contact)
                    contact = None
            self._contact[foot] = contact
            self._prev[foot] = (t, pos.copy())
        self._started = True

    def _start(
        self,
        foot: str,
        t: float,
        pos: np.ndarray,
        yaw: float,
        swing_until_s: Mapping[str, float] | None,
    ) -> _Contact:
        prev = self._prev.get(foot)
        speed = math.nan
        if prev is not None and t > prev[0]:
            speed = float(np.linalg.norm(pos - prev[1]) / (t - prev[0]))
        contact = _Contact(t, pos, yaw, speed)
        planned = None if swing_until_s is None else swing_until_s.get(foot)
        if planned is not None and planned - t > self.config.scuff_lead_s:
            self._rows.append(_Row(t, "scuff", foot, pos, "early_s", planned - t))
            contact.early = True
        return contact

    def _in_contact(self, foot: str, c: _Contact, t: float, pos: np.ndarray, yaw: float) -> None:
        cfg = self.config
        c.off_since_s = None
        c.last_t_s, c.last_pos = t, pos.copy()
        if not c.stance and t - c.t0_s >= cfg.min_stance_s - 1e-9:
            c.stance = True
            c.ref_pos, c.ref_yaw_rad = pos.copy(), yaw  # slip and pivot from the settled foot
            self._rows.append(
                _Row(c.t0_s, "touchdown", foot, c.pos0, "impact_speed_mps", c.speed_mps)
            )
        if not c.stance:
            return
        travel = float(np.linalg.norm(pos[:2] - c.ref_pos[:2]))
        if c.slip is None and travel > cfg.slip_m:
            c.slip = _Row(t, "slip", foot, pos, "travel_m", travel)
            self._rows.append(c.slip)
        elif c.slip is not None:
            c.slip.pos, c.slip.value = pos.copy(), max(c.slip.value, travel)
        turn = abs(float(wrap_angle(yaw - c.ref_yaw_rad)))
        if c.pivot is None and turn > cfg.pivot_rad:
            c.pivot = _Row(t, "pivot", foot, pos, "yaw_change_rad", turn)
            self._rows.append(c.pivot)
        elif c.pivot is not None:
            c.pivot.pos, c.pivot.value = pos.copy(), max(c.pivot.value, turn)

    def _end(self, foot: str, c: _Contact) -> None:
        if c.stance:
            self._rows.append(
                _Row(c.last_t_s, "liftoff", foot, c.last_pos, "stance_s", c.last_t_s - c.t0_s)
            )
        elif not c.early:
            duration = c.last_t_s - c.t0_s
            self._rows.append(_Row(c.t0_s, "scuff", foot, c.pos0, "contact_s", duration))

    @property
    def events(self) -> list[FootEvent]:
        """The events so far, in time order (stable for equal times)."""
        return [r.freeze() for r in sorted(self._rows, key=lambda r: r.t_s)]

    def to_csv(self) -> str:
        """``events.csv``: a header line (:data:`COLUMNS`), then one line per event."""
        lines = [",".join(COLUMNS)]
        for e in self.events:
            x, y, z = e.pos_world_m
            lines.append(
                f"{e.t_s:.4f},{e.event},{e.foot},{x:.4f},{y:.4f},{z:.4f},{e.quantity},{e.value:.6g}"
            )
        return "\n".join(lines) + "\n"
