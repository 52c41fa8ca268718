"""QP layer shared by all MPCs: one problem form, interchangeable backends.

Typical use::

    from gaitnet_mpc.mpc.qp import QPProblem, make_workspace

    ws = make_workspace("osqp", eps_abs=1e-6)        # once
    sol = ws.solve(QPProblem(P, q, A_eq=..., b_eq=..., A=..., l=..., u=...),
                   warm_start=previous_x)            # every tick
    if sol.found:
        apply(sol.x)

Modules: :mod:`.problem` (``QPProblem``), :mod:`.solution` (``QPSolution``),
:mod:`.workspace` (``QPWorkspace`` base), one module per backend, and
:mod:`.registry` (``BACKENDS``, ``make_workspace``).
"""

from gaitnet_mpc.mpc.qp.clarabel_ import ClarabelWorkspace
from gaitnet_mpc.mpc.qp.daqp_ import DAQPWorkspace
from gaitnet_mpc.mpc.qp.osqp_ import OSQPWorkspace
from gaitnet_mpc.mpc.qp.piqp_ import PIQPWorkspace
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.qpoases_ import QpoasesWorkspace
from gaitnet_mpc.mpc.qp.registry import BACKENDS, available_backends, make_workspace
from gaitnet_mpc.mpc.qp.solution import SOLVED_STATUSES, STATUSES, QPSolution
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

__all__ = [
    "BACKENDS",
    "SOLVED_STATUSES",
    "STATUSES",
    "BackendResult",
    "ClarabelWorkspace",
    "DAQPWorkspace",
    "OSQPWorkspace",
    "PIQPWorkspace",
    "QPProblem",
    "QPSolution",
    "QPWorkspace",
    "QpoasesWorkspace",
    "available_backends",
    "make_workspace",
]
