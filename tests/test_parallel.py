"""The process-pool runner shared by ``collect`` and the soak, on tiny functions: every item
gets one outcome, an exception or a dead worker is reported on its item only, progress
messages reach the parent, closing the runner stops the workers, and SIGTERM becomes
:class:`KeyboardInterrupt`. (The Ray runner is exercised by ``tests/test_dataset.py``.)"""

from __future__ import annotations

import os
import signal
import time
from typing import Any

import pytest

from gaitnet_mpc.errors import ConfigError
from gaitnet_mpc.parallel import run_processes, stop_signals_as_keyboard_interrupt


def _square(x: int) -> int:
    if x < 0:
        raise ValueError(f"negative: {x}")
    if x == 13:
        os._exit(1)  # a worker that dies (as on a segfault or an OOM kill)
    return x * x


def _square_reporting(x: int, queue: Any) -> int:
    queue.put((x, "started"))
    return x * x


def _sleep(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def test_each_item_gets_its_result_or_its_error() -> None:
    outcomes = {o.item: o for o in run_processes(_square, [1, -2, 3, 4], workers=2)}

    assert sorted(outcomes) == [-2, 1, 3, 4]
    assert [outcomes[i].get() for i in (1, 3, 4)] == [1, 9, 16]
    bad = outcomes[-2]
    assert isinstance(bad.error, ValueError) and not bad.worker_died
    with pytest.raises(ValueError, match="negative"):
        bad.get()


def test_a_dead_worker_is_blamed_on_its_item_only() -> None:
    from concurrent.futures.process import BrokenProcessPool

    # one item in flight at a time: only the dying item is lost, a new pool runs the rest
    outcomes = {o.item: o for o in run_processes(_square, [2, 13, 5], workers=1)}

    assert outcomes[13].worker_died and isinstance(outcomes[13].error, BrokenProcessPool)
    assert outcomes[2].get() == 4 and outcomes[5].get() == 25


def test_progress_messages_reach_the_parent() -> None:
    messages: list[Any] = []

    results = [o.get() for o in run_processes(_square_reporting, [1, 2], 1, messages.append)]

    assert sorted(results) == [1, 4]
    assert sorted(messages) == [(1, "started"), (2, "started")]


def test_closing_the_runner_stops_the_workers() -> None:
    runs = run_processes(_sleep, [0.0, 60.0], workers=2)
    first = next(runs)
    t0 = time.perf_counter()
    runs.close()

    assert first.get() == 0.0
    assert time.perf_counter() - t0 < 10.0, "the sleeping worker was not stopped"


def test_bad_worker_count_is_refused() -> None:
    with pytest.raises(ConfigError, match="workers"):
        next(run_processes(_square, [1], workers=0))


def test_sigterm_becomes_keyboard_interrupt_inside_the_block() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt), stop_signals_as_keyboard_interrupt():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5.0)  # the handler runs at the next bytecode; never reached
    assert signal.getsignal(signal.SIGTERM) == before


def test_an_interrupt_swallowed_by_a_ctypes_callback_is_delivered_again() -> None:
    """A KeyboardInterrupt raised inside a ctypes callback (as when a signal lands while
    numba writes its object cache) is only printed by Python; inside the block it is
    signalled again and stops the caller (a swallowed SIGINT once let a run go on)."""
    import ctypes
    import sys

    def callback() -> None:
        raise KeyboardInterrupt

    hook = sys.unraisablehook
    with pytest.raises(KeyboardInterrupt), stop_signals_as_keyboard_interrupt():
        ctypes.CFUNCTYPE(None)(callback)()
        time.sleep(5.0)  # the re-delivered SIGINT lands here; never reached
    assert sys.unraisablehook is hook
