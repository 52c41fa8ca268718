"""qpOASES backend through CasADi (``casadi.conic(name, "qpoases", ...)``).

CasADi's conic form is ``min 0.5 x'Hx + g'x  s.t.  lba <= A x <= uba, lbx <= x <= ubx``.
``A`` stacks ``A_eq`` (``lba = uba = b_eq``) over ``A``; the box goes to
``lbx``/``ubx``.  ``H`` is the full symmetric ``P``.  qpOASES runs in its dense
mode (``sparse=False``), with ``printLevel="none"`` and ``error_on_fail=False``.

Warm starting: the ``warm_start`` argument is ignored (CasADi's qpOASES
interface does not use ``x0``).  The CasADi function is built once per sparsity
structure, and CasADi then calls qpOASES' ``hotstart`` (online active-set
homotopy from the previous QP) on every later solve; after a failed solve, or
with ``cold_start=True``, the function is rebuilt so the next solve starts cold
with qpOASES' ``init``.  Building the function prints qpOASES' licence banner on
the C stdout; it is swallowed by redirecting file descriptor 1 during the build.

Quirks: CasADi raises on ``lbx > ubx``/``lba > uba`` (checked beforehand by the
workspace) and reports statuses as strings in ``Function.stats()["return_status"]``.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from gaitnet_mpc.errors import ConfigError, reraise_interrupt
from gaitnet_mpc.mpc.qp.problem import QPProblem
from gaitnet_mpc.mpc.qp.structure import SparsityPattern
from gaitnet_mpc.mpc.qp.workspace import BackendResult, QPWorkspace

try:
    import casadi
except ImportError as _exc:  # pragma: no cover - depends on the environment
    reraise_interrupt(_exc)
    casadi = None  # type: ignore[assignment]  # None marks the missing optional module
    _IMPORT_ERROR: str | None = repr(_exc)
else:
    _IMPORT_ERROR = None
    if not casadi.has_conic("qpoases"):  # pragma: no cover - casadi built without it
        _IMPORT_ERROR = "casadi has no 'qpoases' conic plugin"

_SUCCESS = "Successful return."
_MAX_NWSR = "Maximum number of working set recalculations performed."


def _map_status(text: str) -> str:
    """Map qpOASES' return message (as given by CasADi) to our status set."""
    lowered = text.lower()
    if text == _SUCCESS:
        return "solved"
    if text == _MAX_NWSR or "cpu time" in lowered:
        return "max_iter"
    if "infeasib" in lowered or "unbounded" in lowered:
        return "infeasible"
    return "numerical_error"


@contextlib.contextmanager
def _quiet_c_stdout() -> Iterator[None]:
    """Redirect the process-level stdout (fd 1) to ``/dev/null`` for the block."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError, AttributeError):  # no real fd 1 (embedded use)
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            try:
                yield
            finally:
                os.dup2(saved, 1)
    finally:
        os.close(saved)


def _casadi_sparsity(pattern: SparsityPattern) -> Any:
    rows, cols = pattern.shape
    return casadi.Sparsity(rows, cols, pattern.indptr.tolist(), pattern.indices.tolist())


class QpoasesWorkspace(QPWorkspace):
    """qpOASES (dense active set) via CasADi, hot-started across solves.

    Options: ``cold_start`` (bool, default ``False``: rebuild every solve) plus
    CasADi qpOASES plugin options (``nWSR``, ``CPUtime``, ``printLevel``,
    ``enableRegularisation``, ``sparse``, ...).
    """

    name: ClassVar[str] = "qpoases"
    available: ClassVar[bool] = _IMPORT_ERROR is None
    import_error: ClassVar[str | None] = _IMPORT_ERROR
    supports_update: ClassVar[bool] = True
    default_options: ClassVar[Mapping[str, Any]] = MappingProxyType(
        {"printLevel": "none", "error_on_fail": False, "cold_start": False}
    )

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._conic: Any = None

    def _check_options(self, options: Mapping[str, Any]) -> None:
        # Let CasADi judge the options on a 1-variable problem.
        one = casadi.Sparsity.dense(1, 1)
        try:
            self._build(one, casadi.Sparsity(0, 1), options)
        except RuntimeError as exc:
            raise ConfigError("qpoases options", dict(options), f"valid options ({exc})") from exc

    def _build(self, h: Any, a: Any, options: Mapping[str, Any]) -> Any:
        opts = {k: v for k, v in options.items() if k != "cold_start"}
        with _quiet_c_stdout():
            return casadi.conic("qp", "qpoases", {"h": h, "a": a}, opts)

    def _reset_backend(self) -> None:
        self._conic = None

    def _after_failure(self) -> None:
        self._conic = None
        self._invalidate_structure()

    def _solve(self, problem: QPProblem, warm_start: np.ndarray | None) -> BackendResult:
        A, lba, uba = problem.to_osqp_form(include_box=False)  # boxes go to lbx, ubx
        lbx, ubx = problem.box_bounds()
        P = problem.P

        p_pat, a_pat = SparsityPattern.of(P), SparsityPattern.of(A)
        assert p_pat is not None and a_pat is not None  # of matrices, not None
        if self.options["cold_start"]:
            self._invalidate_structure()
        if self._structure_changed((p_pat, a_pat)) or self._conic is None:
            self._conic = self._build(
                _casadi_sparsity(p_pat), _casadi_sparsity(a_pat), self.options
            )
        res = self._conic(
            h=casadi.DM(self._conic.sparsity_in("h"), P.data),
            g=problem.q,
            a=casadi.DM(self._conic.sparsity_in("a"), A.data),
            lba=lba,
            uba=uba,
            lbx=lbx,
            ubx=ubx,
        )
        stats = self._conic.stats()
        native = str(stats.get("return_status", "unknown"))
        status = _map_status(native)
        x = np.asarray(res["x"], dtype=np.float64).reshape(-1)
        return BackendResult(x, status, native, int(stats.get("iter_count", 0)))
