"""Checked NumPy arrays for the MPC inputs: right shape, finite, else :class:`ConfigError`."""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.errors import ConfigError


def float_array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape``, else :class:`ConfigError`."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(name, value, f"a float array of shape {shape}") from None
    if arr.shape != shape:
        raise ConfigError(name, arr.shape, f"shape {shape}")
    if not np.isfinite(arr).all():
        raise ConfigError(name, "non-finite entries", "finite values")
    return arr


def bool_array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` (booleans or 0/1) as a bool array of ``shape``, else :class:`ConfigError`."""
    arr = np.asarray(value)
    if arr.shape != shape:
        raise ConfigError(name, arr.shape, f"shape {shape}")
    if arr.dtype != np.bool_ and not np.all(np.isin(arr, (0, 1))):
        raise ConfigError(name, "non-boolean entries", "booleans (True = stance)")
    return arr.astype(bool)


__all__ = ["bool_array", "float_array"]
