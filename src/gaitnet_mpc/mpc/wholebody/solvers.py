"""NLP solver backends of the whole-body NMPC: IPOPT and FATROP through CasADi.

Both are interior-point methods (FATROP's algorithm follows IPOPT's); FATROP factorises the
KKT system by a Riccati recursion over the stages, which needs the stage-wise variable
and constraint order of :mod:`.nlp` and the block sizes given here ("manual" structure).
Settings, measurements and the reasons for them: ``benchmarks/results/wbmpc.md``.
"""

from __future__ import annotations

from typing import Any

SOLVERS = ("ipopt", "fatrop")
MAX_ITER = 200
TOL = 1e-6  # convergence tolerance (scaled KKT residual)
ACCEPTABLE_TOL = 1e-4  # stop after ACCEPTABLE_ITER iterations below this
ACCEPTABLE_ITER = 5
# FATROP (through CasADi) returns 1 both at max_iter and when it stops at an "acceptable"
# point; the latter, below max_iter and feasible to this tolerance, is reported as success
# with status "acceptable". On humanoid3d stepping, FATROP's dual infeasibility stalls at
# ~8e-6 (unscaled) on some calls, so without an acceptable level it ran to max_iter.
FEASIBILITY_TOL = 1e-6
# Settings of a warm-started call (primal and shifted duals given): a small initial barrier
# parameter and the initial point kept, so that the interior-point method does not first
# move away from a near-optimal guess (about halves IPOPT's iterations).
WARM_OPTIONS: dict[str, dict[str, Any]] = {
    "ipopt": {
        "ipopt.warm_start_init_point": "yes",
        "ipopt.mu_init": 1e-5,
        "ipopt.warm_start_bound_push": 1e-6,
        "ipopt.warm_start_mult_bound_push": 1e-6,
        "ipopt.warm_start_slack_bound_push": 1e-6,
    },
    # FATROP with mu_init 1e-5 and the shifted duals needed 53 iterations (median) instead
    # of 14 on biped2d stepping and failed 5 of 5 calls: it keeps its cold settings.
    "fatrop": {},
}


def solver_options(
    solver: str, nx: int, nu: int, n_path: list[int], equality: list[bool]
) -> dict[str, Any]:
    """CasADi ``nlpsol`` options of one backend.

    ``n_path`` are the path-constraint rows of stages 0..h (FATROP's ``ng``), ``equality``
    flags the equality rows of ``g`` (FATROP needs them; IPOPT detects them).
    """
    opts: dict[str, Any] = {"expand": True, "print_time": False}
    if solver == "ipopt":
        opts.update(
            {
                "ipopt.print_level": 0,
                "ipopt.sb": "yes",
                "ipopt.tol": TOL,
                "ipopt.acceptable_tol": ACCEPTABLE_TOL,
                "ipopt.acceptable_iter": ACCEPTABLE_ITER,
                "ipopt.max_iter": MAX_ITER,
                "ipopt.linear_solver": "mumps",
            }
        )
    else:
        h = len(n_path) - 1
        opts.update(
            {
                "structure_detection": "manual",
                "N": h,
                "nx": [nx] * (h + 1),
                "nu": [nu] * h + [0],
                "ng": n_path,
                "equality": equality,
                "fatrop.print_level": 0,
                "fatrop.max_iter": MAX_ITER,
                "fatrop.tol": TOL,
                "fatrop.tol_acceptable": ACCEPTABLE_TOL,
                "fatrop.acceptable_iter": ACCEPTABLE_ITER,
            }
        )
    return opts


def solve_status(
    solver: str, stats: dict[str, Any], iterations: int, max_iter: int, violation: float
) -> tuple[bool, str]:
    """(success, status) of a finished solve from CasADi's solver statistics."""
    success = bool(stats.get("success", False))
    status = str(stats.get("return_status", ""))
    if solver == "fatrop" and status == "1" and 0 < iterations < max_iter:
        if violation < FEASIBILITY_TOL:
            success, status = True, "acceptable"
    return success, status
