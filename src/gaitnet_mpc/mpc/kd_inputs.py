"""Per-solve data of the CMPC sub-problem (paper eqs. 16-24), checked.

What changes from one sequential iteration or control tick to the next: the measured
state, the references of eq. 18, the stage lengths, the contact schedule, the foot yaws
of the line-foot wrench rows and the foothold bounds of eq. 24. :meth:`KDInputs.check`
validates the arguments of :meth:`~gaitnet_mpc.mpc.implicit_kd.KDSubproblem.build` into
arrays of the right shapes (:class:`~gaitnet_mpc.errors.ConfigError` otherwise).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc import kd_condensed_kernel as condensed_kernel
from gaitnet_mpc.mpc.centroidal_model import N_FEET, NX
from gaitnet_mpc.mpc.checks import bool_array, float_array
from gaitnet_mpc.mpc.foot_ties import next_touchdown_mask
from gaitnet_mpc.mpc.kd_iterate import KDIterate
from gaitnet_mpc.robots.spec import FEET

#: Checked foothold bounds of one foot (eq. 24): ``p_min``, ``p_max`` (3,) [m], stage mask (h,).
StageBox = tuple[np.ndarray, np.ndarray, np.ndarray]


def _foot_index(foot: object) -> int:
    if foot in FEET:
        return FEET.index(foot)  # type: ignore[arg-type]
    raise ConfigError("foothold_bounds", foot, f"keys among {FEET}")


@dataclass(frozen=True)
class KDInputs:
    """Checked per-solve data of one CMPC QP (shapes for a horizon of ``h`` stages).

    Attributes:
        x0: (12,) measured ``[H; l_G; k_G]``.
        h_ref, H_ref: (h + 1, 6) momentum and centroidal-pose references; row 0 unused.
        p_foot_ref: (h, 2, 3) foot reference [m]; p_com_ref: (h + 1, 3) CoM reference [m].
        dts_s: (h,) per-stage sampling times [s], all > 0.
        contact: (h, 2) stance mask (True = stance).
        foot_yaw_rad: (h, 2) foot headings.
        p_foot_measured: (2, 3) measured foot positions [m].
        foothold_bounds: per foot (ordered as :data:`FEET`), its eq. 24 box or ``None``.
        wrench_ext: (6,) external wrench ``[f_ext (N); tau_ext about the CoM (N m)]``
            acting through the horizon beside gravity (the disturbance observer's
            estimate, :mod:`~gaitnet_mpc.control.disturbance_observer`); zeros: none.
    """

    x0: np.ndarray
    h_ref: np.ndarray
    H_ref: np.ndarray
    p_foot_ref: np.ndarray
    p_com_ref: np.ndarray
    dts_s: np.ndarray
    contact: np.ndarray
    foot_yaw_rad: np.ndarray
    p_foot_measured: np.ndarray
    foothold_bounds: tuple[StageBox | None, ...]
    wrench_ext: np.ndarray = field(default_factory=lambda: np.zeros(6))

    @classmethod
    def check(
        cls,
        horizon: int,
        x0: object,
        iterate: object,
        h_ref: object,
        H_ref: object,
        p_foot_ref: object,
        p_com_ref: object,
        dts_s: object,
        contact: object,
        foot_yaw_rad: object,
        foothold_bounds: object,
        p_foot_measured: object,
        wrench_ext: object = None,
    ) -> KDInputs:
        """The arguments of :meth:`~gaitnet_mpc.mpc.implicit_kd.KDSubproblem.build`,
        checked against a horizon of ``horizon`` stages.

        Raises:
            ConfigError: an argument has the wrong shape or invalid values.
        """
        h = horizon
        if not isinstance(iterate, KDIterate):
            raise ConfigError("iterate", type(iterate).__name__, "a KDIterate")
        if iterate.horizon != h:
            raise ConfigError("iterate", f"horizon {iterate.horizon}", f"horizon {h}")
        fields = {
            "x0": float_array("x0", x0, (NX,)),
            "h_ref": float_array("h_ref", h_ref, (h + 1, 6)),
            "H_ref": float_array("H_ref", H_ref, (h + 1, 6)),
            "p_foot_ref": float_array("p_foot_ref", p_foot_ref, (h, N_FEET, 3)),
            "p_com_ref": float_array("p_com_ref", p_com_ref, (h + 1, 3)),
            "dts_s": float_array("dts_s", dts_s, (h,)),
            "contact": bool_array("contact", contact, (h, N_FEET)),
            "foot_yaw_rad": float_array("foot_yaw_rad", foot_yaw_rad, (h, N_FEET)),
        }
        if np.any(fields["dts_s"] <= 0.0):
            raise ConfigError("dts_s", fields["dts_s"].tolist(), "sampling times > 0 [s]")
        measured = (
            iterate.p_foot[0].copy()
            if p_foot_measured is None
            else float_array("p_foot_measured", p_foot_measured, (N_FEET, 3))
        )
        bounds = _check_foothold_bounds(foothold_bounds, fields["contact"])
        ext = np.zeros(6) if wrench_ext is None else float_array("wrench_ext", wrench_ext, (6,))
        return cls(**fields, p_foot_measured=measured, foothold_bounds=bounds, wrench_ext=ext)

    def foot_bounds(
        self, it: KDIterate, height_from_reference: bool, trust_region_m: float | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Absolute bounds ``lo, hi`` (h, 2, 3) on each stage's foot position about the
        iterate ``it``: per tie group (:func:`~gaitnet_mpc.mpc.foot_ties.tie_groups`), the
        measured position, the eq. 24 box, the reference height and the trust region
        (:func:`~gaitnet_mpc.mpc.kd_condensed_kernel.foot_bounds`)."""
        has_box = np.zeros(N_FEET, dtype=bool)
        box = np.zeros((2, N_FEET, 3))
        mask = np.zeros((N_FEET, self.dts_s.shape[0]), dtype=bool)
        for i, bounds in enumerate(self.foothold_bounds):
            if bounds is not None:
                has_box[i] = True
                box[0, i], box[1, i], mask[i] = bounds
        return condensed_kernel.foot_bounds(
            self.contact, it.p_foot, np.ascontiguousarray(self.p_foot_ref[:, :, 2]),
            self.p_foot_measured, has_box, box[0], box[1], mask, height_from_reference,
            condensed_kernel.or_nan(trust_region_m),
        )  # fmt: skip

    def with_references(
        self, h_ref: object, H_ref: object, p_foot_ref: object, p_com_ref: object, dts_s: object
    ) -> KDInputs:
        """These inputs with new references and stage times (the next iteration of a
        sequential solve: the measured state, contacts, headings and foothold boxes are
        the same), checked as in :meth:`check`."""
        h = self.dts_s.shape[0]
        dts = float_array("dts_s", dts_s, (h,))
        if np.any(dts <= 0.0):
            raise ConfigError("dts_s", dts.tolist(), "sampling times > 0 [s]")
        return replace(
            self,
            h_ref=float_array("h_ref", h_ref, (h + 1, 6)),
            H_ref=float_array("H_ref", H_ref, (h + 1, 6)),
            p_foot_ref=float_array("p_foot_ref", p_foot_ref, (h, N_FEET, 3)),
            p_com_ref=float_array("p_com_ref", p_com_ref, (h + 1, 3)),
            dts_s=dts,
        )


def _check_foothold_bounds(
    foothold_bounds: object, contact: np.ndarray
) -> tuple[StageBox | None, ...]:
    """Foot name -> ``(p_min | None, p_max | None[, stage_mask | None])`` as one box per
    foot (``None``: unbounded); a missing or ``None`` mask is the next touchdown."""
    h = contact.shape[0]
    bounds: list[StageBox | None] = [None] * N_FEET
    if foothold_bounds is None:
        return tuple(bounds)
    if not isinstance(foothold_bounds, Mapping):
        raise ConfigError(
            "foothold_bounds", type(foothold_bounds).__name__, "a dict foot -> bounds"
        )
    for foot, entry in foothold_bounds.items():
        i = _foot_index(foot)
        name = f"foothold_bounds[{foot!r}]"
        if not isinstance(entry, tuple | list) or len(entry) not in (2, 3):
            raise ConfigError(name, entry, "a tuple (p_min, p_max[, stage_mask])")
        p_min = np.full(3, -np.inf) if entry[0] is None else np.asarray(entry[0], float)
        p_max = np.full(3, np.inf) if entry[1] is None else np.asarray(entry[1], float)
        for side, value in (("p_min", p_min), ("p_max", p_max)):
            if value.shape != (3,) or np.any(np.isnan(value)):
                raise ConfigError(f"{name}.{side}", value, "shape (3,), no NaN, or None")
        if np.any(p_min > p_max):
            raise ConfigError(name, (p_min.tolist(), p_max.tolist()), "p_min <= p_max")
        mask_value = entry[2] if len(entry) == 3 else None
        mask = (
            next_touchdown_mask(contact[:, i])
            if mask_value is None
            else bool_array(f"{name}.stage_mask", mask_value, (h,))
        )
        bounds[i] = (p_min, p_max, mask)
    return tuple(bounds)


__all__ = ["KDInputs", "StageBox"]
