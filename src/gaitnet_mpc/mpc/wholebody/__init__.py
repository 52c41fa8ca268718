"""Whole-body NMPC of Sec. III-A (eqs. 1-4, Table VI): model, problem, transcription.

* :mod:`.dynamics`: symbolic rigid-body dynamics (RNEA with contact forces) and the
  semi-implicit Euler step, on MuJoCo's state convention.
* :mod:`.problem`: :class:`WBConfig` (Table VI), :class:`WBProblem` and the contact
  schedule / per-step sampling times / reference builders.
* :mod:`.nlp`: :class:`WholeBodyMPC`, the multiple-shooting NLP and its warm start.
* :mod:`.solvers`: IPOPT / FATROP settings; :mod:`.solution`: :class:`WBSolution`.
"""

from gaitnet_mpc.mpc.wholebody.dynamics import ContactPoint, WholeBodyDynamics
from gaitnet_mpc.mpc.wholebody.nlp import WholeBodyMPC
from gaitnet_mpc.mpc.wholebody.problem import (
    WBConfig,
    WBProblem,
    WBWeights,
    contact_schedule,
    make_problem,
    stage_dt,
)
from gaitnet_mpc.mpc.wholebody.solution import WBSolution
from gaitnet_mpc.mpc.wholebody.solvers import SOLVERS

__all__ = [
    "SOLVERS",
    "ContactPoint",
    "WBConfig",
    "WBProblem",
    "WBSolution",
    "WBWeights",
    "WholeBodyDynamics",
    "WholeBodyMPC",
    "contact_schedule",
    "make_problem",
    "stage_dt",
]
