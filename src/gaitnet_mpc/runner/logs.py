"""The run folder's tables: ``log.csv`` (one row per control tick), ``mpc_log.csv`` (one row
per MPC solve), and the recorder that fills the MPC columns from a controller's telemetry."""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gaitnet_mpc.control.base import Controller, Telemetry
from gaitnet_mpc.robots import FEET


@dataclass
class EpisodeLog:
    """Per-tick time series, kept in memory and written as CSV.

    ``self_contact`` is 1 on ticks where two robot geoms touch (see
    :class:`~gaitnet_mpc.sim.simulator.SelfCollisionStats`), else 0. ``fext_*_n`` and
    ``text_*_nm``: the disturbance observer's estimate of the external force and torque
    about the CoM (NaN for a controller without one).
    """

    columns: tuple[str, ...] = (
        "t_s",
        "com_x_m",
        "com_y_m",
        "com_z_m",
        "com_vx_mps",
        "com_vy_mps",
        "com_vz_mps",
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "cmd_vx_mps",
        "contact_left",
        "contact_right",
        "fz_left_n",
        "fz_right_n",
        "lGx",
        "lGy",
        "lGz",
        "kGx",
        "kGy",
        "kGz",
        "tau_abs_max_nm",
        "tau_limit_ratio_max",
        "mpc_dt_s",
        "mpc_n_qps",
        "mpc_solve_ms",
        "stance_foot",
        "self_contact",
        "fext_x_n",
        "fext_y_n",
        "fext_z_n",
        "text_x_nm",
        "text_y_nm",
        "text_z_nm",
    )
    rows: list[np.ndarray] = field(default_factory=list)

    def to_csv(self) -> str:
        return _csv(self.columns, self.rows)


@dataclass
class MPCLog:
    """One row per MPC solve, written as ``mpc_log.csv``.

    ``dt_s`` is the MPC sampling time of the step the solve belongs to (NaN without a gait
    schedule); ``failed``: the solve found no usable solution (the last plan was kept).
    For a controller with a dt policy (``gaitnet``, ``oracle``), a full solve's row also
    holds ``dt_calls`` (dts asked inside its iterations), ``dt_first_s`` (the first one),
    ``dt_fallback`` (:data:`DT_FALLBACK_CODES`) and ``dt_frozen`` (1: the dt was frozen
    after ``max_retimes`` changes); NaN elsewhere. For controllers that expose a
    kino-dynamic ``plan`` (``kd``), the ``*_pred`` columns hold the momentum the plan
    predicts one stage ahead, at ``t_pred_s``, and the ``*_meas`` columns the momentum
    measured at that tick (NaN when the episode ended before it, or for other controllers).
    """

    columns: tuple[str, ...] = (
        "t_s",
        "full_solve",
        "n_qps",
        "converged",
        "solve_ms",
        "dt_s",
        "t_pred_s",
        "lGx_pred",
        "kGy_pred",
        "kGz_pred",
        "lGx_meas",
        "kGy_meas",
        "kGz_meas",
        "failed",
        "dt_calls",
        "dt_first_s",
        "dt_fallback",
        "dt_frozen",
    )
    rows: list[list[float]] = field(default_factory=list)

    def fill_measured(self, log_rows: np.ndarray, h_cols: slice) -> None:
        """Fill the ``*_meas`` columns from the tick log (first tick at or after ``t_pred_s``)."""
        if not self.rows or log_rows.size == 0:
            return
        t = log_rows[:, 0]
        h = log_rows[:, h_cols]  # (n, 6) [l_G; k_G]
        i_pred, i_meas = self.columns.index("t_pred_s"), self.columns.index("lGx_meas")
        for row in self.rows:
            t_pred = row[i_pred]
            if not np.isfinite(t_pred) or t_pred > t[-1] + 1e-9:
                continue
            k = int(np.searchsorted(t, t_pred - 1e-9))
            row[i_meas : i_meas + 3] = [h[k, 0], h[k, 4], h[k, 5]]  # l_G,x, k_G,y, k_G,z

    def to_csv(self) -> str:
        return _csv(self.columns, self.rows)


def _csv(columns: tuple[str, ...], rows: list[Any]) -> str:
    """CSV text with a header line; ``nan`` marks values that do not apply."""
    buf = io.StringIO()
    data = np.asarray(rows, dtype=float).reshape(-1, len(columns))
    np.savetxt(buf, data, delimiter=",", header=",".join(columns), comments="", fmt="%.6g")
    return buf.getvalue()


#: ``mpc_log.csv``'s ``dt_fallback``: why a dt policy kept a dt it did not choose
#: (``gaitnet``: ensemble spread, cycling; ``oracle``: no grid point converged).
DT_FALLBACK_CODES: dict[str | None, int] = {None: 0, "spread": 1, "cycle": 2, "none converged": 3}

#: Columns of ``log.csv`` holding the measured momentum ``[l_G; k_G]``.
H_COLS = slice(EpisodeLog.columns.index("lGx"), EpisodeLog.columns.index("kGz") + 1)


class TelemetryRecorder:
    """Records a controller's solves (``mpc_log.csv``) and telemetry (``log.csv`` columns)
    after each :meth:`~gaitnet_mpc.control.base.Controller.compute`.

    ``telemetry`` is the controller's telemetry of the last tick, asked once per tick by
    :meth:`after_compute` (made after the controller's ``reset``).
    """

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.telemetry: Telemetry | None = controller.telemetry()
        self.n_seen = 0
        self.last_qps = np.nan
        self.last_ms = np.nan
        self.log = MPCLog() if controller.mpc_stats is not None else None

    def step_dt(self) -> float:
        """MPC dt of the current step [s] (NaN without a gait)."""
        tel = self.telemetry
        return np.nan if tel is None else float(tel.step_dt_s)

    def stance_code(self) -> float:
        """Index of the stance foot in ``FEET`` (NaN without a gait)."""
        tel = self.telemetry
        return np.nan if tel is None else float(FEET.index(tel.stance_foot))

    def wrench_ext(self) -> np.ndarray:
        """The disturbance observer's estimate (6,) (NaN without one)."""
        tel = self.telemetry
        w = None if tel is None else tel.wrench_ext
        return np.full(6, np.nan) if w is None else w

    def after_compute(self, t_s: float) -> None:
        """Take this tick's telemetry and record the solves that the last ``compute`` call
        made."""
        self.telemetry = self.controller.telemetry()
        stats = self.controller.mpc_stats
        if stats is None or self.log is None:
            return
        n = len(stats.solve_time_s)
        if n == self.n_seen:
            return
        dt = self.step_dt()
        n_cols = len(self.log.columns)
        for i in range(self.n_seen, n):
            row = [
                t_s,
                float(stats.full_solve[i]),
                float(stats.qps_per_solve[i]),
                float(stats.converged[i]),
                1e3 * stats.solve_time_s[i],
                dt,
            ]
            row += [np.nan] * (n_cols - len(row))
            row[self.log.columns.index("failed")] = float(stats.failed[i])
            if stats.full_solve[i]:
                row[-4:] = self._dt_decision()
            self.log.rows.append(row)
        i_pred = self.log.columns.index("t_pred_s")
        self.log.rows[-1][i_pred : i_pred + 4] = self._prediction(t_s)
        self.last_qps = float(stats.qps_per_solve[n - 1])
        self.last_ms = 1e3 * stats.solve_time_s[n - 1]
        self.n_seen = n

    def _dt_decision(self) -> list[float]:
        """``[dt_calls, dt_first_s, dt_fallback, dt_frozen]`` of the last step start."""
        d = self.controller.last_dt_decision()
        if d is None:
            return [np.nan] * 4
        dts = d.get("dts_s") or [np.nan]
        code = DT_FALLBACK_CODES.get(d.get("fallback"), np.nan)
        return [float(len(dts)), float(dts[0]), float(code), float(bool(d.get("frozen")))]

    def _prediction(self, t_s: float) -> list[float]:
        """``[t_pred, l_G,x, k_G,y, k_G,z]`` one stage ahead of a plan made at ``t_s``."""
        tel = self.telemetry
        pred = None if tel is None else tel.prediction
        if pred is None or abs(pred.t_plan_s - t_s) > 1e-9:
            return [np.nan] * 4  # no plan, or the solve failed and the old plan was kept
        return [pred.t_pred_s, pred.h_pred[0], pred.h_pred[4], pred.h_pred[5]]
