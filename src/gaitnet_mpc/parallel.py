"""Run one function over many items in parallel: a spawn process pool or Ray tasks.

Used by ``gaitnet-mpc collect`` (one data-set set per item) and ``benchmarks/soak.py``
(one episode per item). Both runners are generators of :class:`Outcome` in the order the
items *finish*, with at most a fixed number of items in flight, so that:

* the caller stores each result as soon as it is done (a later interruption keeps it);
* a worker that dies (segfault, OOM kill) is blamed on the items in flight only: the
  process pool is started again for the rest;
* closing the generator (``break``, an exception in the caller, :class:`KeyboardInterrupt`
  inside it, or :meth:`~collections.abc.Generator.close`) stops the workers at once; the
  items in progress are lost.

:func:`stop_signals_as_keyboard_interrupt` makes SIGTERM and SIGINT (even one inherited
as ignored) stop a run as Ctrl-C does (the CLI turns the :class:`KeyboardInterrupt` into
exit status 130).
"""

from __future__ import annotations

import functools
import os
import signal
import socket
import sys
import threading
from collections.abc import Callable, Generator, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from gaitnet_mpc.errors import ConfigError, reraise_interrupt

T = TypeVar("T")
R = TypeVar("R")

#: How often the runners look at the workers and the progress queue [s].
POLL_PERIOD_S = 0.5
#: How long :func:`check_ray_address` waits for a cluster's port to answer [s]; Ray's own
#: connection retries last minutes.
RAY_CONNECT_TIMEOUT_S = 15.0
#: Addresses that name no host:port (Ray finds the local cluster itself).
_RAY_LOCAL_ADDRESSES = ("auto", "local")


def check_ray_address(
    address: str, option: str = "--address", timeout_s: float = RAY_CONNECT_TIMEOUT_S
) -> None:
    """Raise a :class:`ConfigError` naming ``option`` unless ``address`` is ``auto``,
    ``local`` or a ``[ray://]host:port`` whose port accepts a TCP connection within
    ``timeout_s`` (an unknown host or a closed port fails at once), before Ray is asked."""
    if address in _RAY_LOCAL_ADDRESSES:
        return
    expected = "a Ray cluster's host:port (or auto) that accepts a connection"
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(option, address, "a Ray cluster's host:port (or auto)")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s).close()
    except socket.gaierror as exc:
        raise ConfigError(option, address, f"{expected} (unknown host: {exc.strerror})") from None
    except TimeoutError:
        why = f"no answer within {timeout_s:g} s"
        raise ConfigError(option, address, f"{expected} ({why})") from None
    except OSError as exc:
        raise ConfigError(option, address, f"{expected} ({exc.strerror or exc})") from None


@dataclass(frozen=True)
class Outcome(Generic[T, R]):
    """What became of one item.

    Attributes:
        item: the item, as given.
        result: the function's return value (None when ``error`` is set).
        error: the exception the function raised, or that reports its worker's death.
        worker_died: ``error`` reports a dead worker (``BrokenProcessPool``, a Ray worker
            or node failure), not an exception raised by the function.
    """

    item: T
    result: R | None = None
    error: BaseException | None = None
    worker_died: bool = False

    def get(self) -> R:
        """The result; raises :attr:`error` if there is one."""
        if self.error is not None:
            raise self.error
        return self.result  # type: ignore[return-value]  # R itself may include None


def _check_workers(workers: int) -> None:
    if not (isinstance(workers, int) and workers >= 1):
        raise ConfigError("workers", workers, "an integer >= 1")


def _ignore_sigint() -> None:
    # The parent handles Ctrl-C / SIGTERM and stops the pool; workers just exit with it.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_processes(
    fn: Callable[..., R],
    items: Sequence[T],
    workers: int,
    on_progress: Callable[[Any], None] | None = None,
) -> Generator[Outcome[T, R], None, None]:
    """Outcomes of ``fn(item)`` for each item, from a spawn process pool.

    At most ``workers`` items are in flight, submitted in the order of ``items``. If a
    worker dies, the items in flight get an outcome with ``worker_died`` and a fresh pool
    runs the rest.

    Args:
        fn: a picklable (module-level) function. With ``on_progress`` it is called as
            ``fn(item, queue)`` and may ``queue.put(message)`` while it works.
        items: the items (picklable).
        workers: worker processes.
        on_progress: called in this process with each message the workers put, while
            waiting (None: ``fn(item)`` gets no queue).

    Raises:
        ConfigError: ``workers`` is not an integer >= 1.
    """
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    _check_workers(workers)
    ctx = mp.get_context("spawn")  # no MuJoCo/CasADi state shared through fork
    todo = list(reversed(items))
    manager = ctx.Manager() if on_progress is not None else None
    queue = None if manager is None else manager.Queue()

    def drain() -> None:
        if queue is None or on_progress is None:
            return
        while not queue.empty():
            on_progress(queue.get())

    try:
        while todo:
            pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_ignore_sigint)
            broken = False
            pending: dict[Future[R], T] = {}
            try:
                while (todo or pending) and not broken:
                    while todo and len(pending) < workers:
                        item = todo.pop()
                        args = (item,) if queue is None else (item, queue)
                        pending[pool.submit(fn, *args)] = item
                    finished, _ = wait(pending, timeout=POLL_PERIOD_S, return_when=FIRST_COMPLETED)
                    drain()
                    for future in finished:
                        item = pending.pop(future)
                        try:
                            result = future.result()
                        except BrokenProcessPool as exc:
                            broken = True
                            yield Outcome(item, error=exc, worker_died=True)
                        except Exception as exc:  # raised by fn: the caller decides
                            yield Outcome(item, error=exc)
                        else:
                            yield Outcome(item, result)
                for item in pending.values():  # still in flight when the pool broke
                    lost = BrokenProcessPool("the pool was broken by another item's worker")
                    yield Outcome(item, error=lost, worker_died=True)
            finally:
                for process in list((getattr(pool, "_processes", None) or {}).values()):
                    process.terminate()  # an item in progress is lost
                pool.shutdown(wait=True, cancel_futures=True)
    finally:
        if manager is not None:
            manager.shutdown()


def run_ray(
    fn: Callable[[T], R],
    items: Sequence[T],
    workers: int,
    address: str | None = None,
    max_retries: int | None = None,
) -> Generator[Outcome[T, R], None, None]:
    """Outcomes of ``fn(item)`` for each item, as Ray tasks of one CPU each.

    If Ray is not initialized yet, a local instance of ``workers`` CPUs (``address`` None)
    or the cluster at ``address`` is started, and shut down at the end; an instance the
    caller started is used as it is. On a local instance at most ``workers`` items are in
    flight; on a cluster all are submitted and Ray's scheduler fills the cluster.

    Args:
        fn: a picklable function.
        items: the items.
        workers: CPUs of a local instance, and the items in flight on it.
        address: a Ray cluster address (None: a local instance).
        max_retries: Ray's ``max_retries`` of each task after its worker died (None:
            Ray's default).

    Raises:
        ConfigError: Ray is not installed, ``workers`` is not an integer >= 1, or
            ``address`` does not answer (:func:`check_ray_address`); raised by this call,
            before the first outcome is asked for.
    """
    _check_workers(workers)
    if address is not None:
        check_ray_address(address)
    try:
        import ray  # noqa: F401
    except ImportError as exc:
        reraise_interrupt(exc)
        raise ConfigError(
            "--backend", "ray", "Ray installed (pip install 'gaitnet-mpc[ray]')"
        ) from None
    return _ray_outcomes(fn, items, workers, address, max_retries)


def _ray_outcomes(
    fn: Callable[[T], R],
    items: Sequence[T],
    workers: int,
    address: str | None,
    max_retries: int | None,
) -> Generator[Outcome[T, R], None, None]:
    import ray
    from ray.exceptions import RayError, RayTaskError

    started = not ray.is_initialized()
    if started:
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
        if address is None:
            kwargs["num_cpus"] = workers
        main_thread = threading.current_thread() is threading.main_thread()
        on_term = signal.getsignal(signal.SIGTERM) if main_thread else None
        ray.init(address=address, **kwargs)
        if on_term is not None:  # ray.init installs a SIGTERM handler that exits at once
            signal.signal(signal.SIGTERM, on_term)  # ours: SIGTERM stops as Ctrl-C does
    try:
        options: dict[str, Any] = {"num_cpus": 1}
        if max_retries is not None:
            options["max_retries"] = max_retries
        task = ray.remote(**options)(fn)
        in_flight = workers if address is None else max(len(items), 1)
        todo = list(reversed(items))
        pending: dict[Any, T] = {}
        try:
            while todo or pending:
                while todo and len(pending) < in_flight:
                    item = todo.pop()
                    pending[task.remote(item)] = item
                ready, _ = ray.wait(list(pending), num_returns=1, timeout=POLL_PERIOD_S)
                for ref in ready:
                    item = pending.pop(ref)
                    try:
                        result = ray.get(ref)
                    except RayTaskError as exc:  # raised by fn
                        yield Outcome(item, error=exc)
                    except RayError as exc:  # the worker or its node died
                        yield Outcome(item, error=exc, worker_died=True)
                    else:
                        yield Outcome(item, result)
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
    finally:
        if started:
            ray.shutdown()


@contextmanager
def stop_signals_as_keyboard_interrupt() -> Iterator[None]:
    """Inside the block, SIGTERM and SIGINT raise :class:`KeyboardInterrupt`; the previous
    handlers are restored on exit. Main thread only.

    SIGINT is set as well because a process started in the background of a
    non-interactive shell (``cmd &``, ``nohup``) inherits it ignored, and Python then
    never raises KeyboardInterrupt: such a run could not be stopped with ``kill -INT``.

    A KeyboardInterrupt raised where Python cannot pass it on (inside a ctypes callback,
    e.g. numba's object cache while a kernel compiles) is only printed, and the run would go
    on; :func:`_redeliver_interrupt` signals again, so it lands in the next Python code.
    """
    previous_term = signal.signal(signal.SIGTERM, _raise_keyboard_interrupt)
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    previous_hook = sys.unraisablehook
    sys.unraisablehook = functools.partial(_redeliver_interrupt, previous_hook)
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        signal.signal(signal.SIGTERM, previous_term)
        signal.signal(signal.SIGINT, previous_int)


def _raise_keyboard_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def _redeliver_interrupt(previous: Callable[[Any], object], unraisable: Any) -> None:
    """``sys.unraisablehook``: an interrupt that could not be raised is signalled again,
    from another thread a moment later, so that it is raised in the main thread's next
    Python code and not in this hook (where it would be swallowed as well)."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        timer = threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT))
        timer.daemon = True
        timer.start()
    else:
        previous(unraisable)
