"""numba's ``njit`` with an on-disk cache of the compiled kernels where one can be kept.

``njit(cache=True)`` keeps compiled kernels beside the source file (``__pycache__``) or,
where the package folder cannot be written (an install owned by another user), in the
user's cache folder (``~/.cache/numba``, or ``$NUMBA_CACHE_DIR``). Where neither can be
written (a read-only install run by a user without a writable home), numba refuses at
import time ("cannot cache function ...: no locator available"), which would make the
package unimportable. :func:`njit_cached` then compiles the kernel without a cache (each
process compiles the kernels again on first use, a few seconds) and warns, naming
``NUMBA_CACHE_DIR``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from numba import njit

#: The start of numba's message when no cache folder can be written.
_NO_LOCATOR = "cannot cache function"


def njit_cached(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, **options)`` as a decorator, falling back to
    ``cache=False`` (with a warning) where numba finds no folder to cache in."""

    def decorate(func: Callable[..., Any]) -> Any:
        try:
            return njit(cache=True, **options)(func)
        except RuntimeError as exc:
            if not str(exc).startswith(_NO_LOCATOR):
                raise
            warnings.warn(
                "numba finds no writable folder for its cache (beside the installed package "
                "or in the user's cache folder): compiled kernels are not kept between runs; "
                "set NUMBA_CACHE_DIR to a writable folder to keep them",
                RuntimeWarning,
                stacklevel=1,  # one location: shown once, not once per kernel
            )
            return njit(cache=False, **options)(func)

    return decorate
