"""One exception hierarchy for the whole package.

Every error raised on bad input names the field, the value received and what was
expected, so a user can fix a command line or a course file without reading code.
"""

from __future__ import annotations

import reprlib

#: How a received value is shown in a message: a huge list or string from a file is cut
#: (``...``), so that the message stays one readable line.
_REPR = reprlib.Repr()  # Python 3.11 takes no keyword arguments
_REPR.maxlevel = 4
_REPR.maxtuple = _REPR.maxlist = _REPR.maxarray = _REPR.maxdict = 12
_REPR.maxset = _REPR.maxfrozenset = _REPR.maxdeque = 12
_REPR.maxstring = _REPR.maxother = 160
_REPR.maxlong = 60


def _short_repr(value: object) -> str:
    try:
        return _REPR.repr(value)
    except (ValueError, RecursionError):  # an int past Python's digit limit, a deep cycle
        return f"<a {type(value).__name__} too large to show>"


class GaitNetMPCError(Exception):
    """Base class of every error this package raises on purpose."""


class ConfigError(GaitNetMPCError, ValueError):
    """A configuration value, CLI argument or file field is invalid.

    The message always reads ``<field>: got <value>, expected <what>``.
    """

    def __init__(self, field: str, value: object, expected: str) -> None:
        self.field = field
        self.value = value
        self.expected = expected
        super().__init__(f"{field}: got {_short_repr(value)}, expected {expected}")

    def __reduce__(self) -> tuple[type, tuple[str, object, str]]:
        # picklable with its own constructor's arguments, so that an error raised in a
        # pool worker reaches the parent as itself (not as a BrokenProcessPool)
        return (type(self), (self.field, self.value, self.expected))


class CourseFormatError(ConfigError):
    """A terrain course (JSON file or dict) is malformed."""


class QPSolveError(GaitNetMPCError, RuntimeError):
    """A QP backend failed (infeasible, max iterations, numerical trouble)."""

    def __init__(self, backend: str, status: str, detail: str = "") -> None:
        self.backend = backend
        self.status = status
        self.detail = detail
        msg = f"QP backend {backend!r} failed with status {status!r}"
        super().__init__(f"{msg}: {detail}" if detail else msg)

    def __reduce__(self) -> tuple[type, tuple[str, str, str]]:
        return (type(self), (self.backend, self.status, self.detail))


class PartialFailure(GaitNetMPCError):
    """Part of a long job failed (e.g. sets of ``collect`` whose workers raised); what did
    not fail is on disk, and ``log`` holds each failure with its traceback."""

    def __init__(self, what: str, failed: list[str], log: str) -> None:
        self.what = what
        self.failed = list(failed)
        self.log = log
        listed = ", ".join(self.failed[:5]) + (", ..." if len(self.failed) > 5 else "")
        super().__init__(f"{what}: {len(self.failed)} failed ({listed}); see {log}")

    def __reduce__(self) -> tuple[type, tuple[str, list[str], str]]:
        return (type(self), (self.what, self.failed, self.log))


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was caused by, a :class:`KeyboardInterrupt`.

    A Ctrl-C or SIGTERM that arrives while a compiled extension initialises (``import
    piqp``) reaches Python as ``ImportError('initialization failed')`` with the interrupt
    as its cause.
    """
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


def reraise_interrupt(exc: BaseException) -> None:
    """Raise :class:`KeyboardInterrupt` if ``exc`` was caused by one
    (:func:`caused_by_interrupt`). Code that treats an ImportError as "not installed"
    calls this first, so that an interrupted start-up stops (exit 130) instead of
    reporting a missing package."""
    if caused_by_interrupt(exc):
        raise KeyboardInterrupt from exc
