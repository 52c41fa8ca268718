"""Registry of QP backends and the factory used by every MPC."""

from __future__ import annotations

from typing import Any

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.mpc.qp.clarabel_ import ClarabelWorkspace
from gaitnet_mpc.mpc.qp.daqp_ import DAQPWorkspace
from gaitnet_mpc.mpc.qp.osqp_ import OSQPWorkspace
from gaitnet_mpc.mpc.qp.piqp_ import PIQPWorkspace
from gaitnet_mpc.mpc.qp.qpoases_ import QpoasesWorkspace
from gaitnet_mpc.mpc.qp.workspace import QPWorkspace

#: Every backend known to the project, by name, installed or not.
BACKENDS: dict[str, type[QPWorkspace]] = {
    cls.name: cls
    for cls in (
        OSQPWorkspace,
        PIQPWorkspace,
        DAQPWorkspace,
        ClarabelWorkspace,
        QpoasesWorkspace,
    )
}


def available_backends() -> list[str]:
    """Names of the registered backends whose package imports."""
    return [name for name, cls in BACKENDS.items() if cls.available]


def make_workspace(name: str, **options: Any) -> QPWorkspace:
    """Create a workspace for backend ``name``.

    Args:
        name: A key of :data:`BACKENDS` (``"osqp"``, ``"piqp"``, ``"daqp"``,
            ``"clarabel"``, ``"qpoases"``).
        **options: ``inaccurate_tol``, ``check_problem`` and backend settings,
            see :class:`QPWorkspace` and the backend classes.

    Raises:
        ConfigError: unknown ``name``, backend package not installed, or an
            unknown backend option.
    """
    try:
        cls = BACKENDS[name]
    except (KeyError, TypeError):
        raise ConfigError("qp_backend", name, f"one of {sorted(BACKENDS)}") from None
    return cls(**options)
