"""Where a campaign's episodes run: a local process pool, or an existing dask.distributed cluster.

A backend maps a picklable function over episode indices and yields results as they
finish, in any order (the campaign writes each one down as it arrives). At most
``window`` tasks are in flight at once, so an interrupted campaign leaves little undone
and memory stays flat however many episodes there are. Only the function's small
arguments travel; workers build worlds and pymunk spaces themselves.

- ``LocalBackend(workers)``: ``concurrent.futures.ProcessPoolExecutor`` with the ``spawn``
  start method (no state inherited from the parent; the same on every platform).
  ``workers=1`` runs in this process, with no pool at all. Workers ignore Ctrl-C (the
  campaign decides what it means) and exit by themselves within a second of the campaign
  process dying; ``abort()`` terminates them at once.
- ``DaskBackend(address, workers)``: ``dask.distributed.Client`` connected to the scheduler
  at ``address`` (``tcp://HOST:PORT``), or to a new ``LocalCluster`` on 127.0.0.1 with
  ``workers`` single-threaded worker processes when no address is given. Needs the
  ``dask`` extra (``pip install 'albot2d[dask]'``); workers need albot2d installed (and a
  ``module:Class`` mapper importable).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol, TypeVar
from urllib.parse import urlsplit

from albot2d.errors import InputError
from albot2d.limits import MAX_LOCAL_WORKERS

__all__ = [
    "BACKENDS",
    "Backend",
    "DaskBackend",
    "LocalBackend",
    "WorkerDiedError",
    "make_backend",
]

# The first is the default.
BACKENDS = ("local", "dask")
# Tasks kept in flight per worker: enough to keep every worker busy between results.
_IN_FLIGHT_PER_WORKER = 2
# How long to wait for a dask scheduler to answer before giving up.
_CONNECT_TIMEOUT_S = 10.0
# How often a local worker checks that the campaign process is still alive, and the exit
# code it ends with when it is not.
_PARENT_POLL_S = 0.25
_ORPHAN_EXIT_CODE = 75


R = TypeVar("R")


class Backend(Protocol):
    """Runs ``fn(*args, item)`` for each item; yields ``(item, result)`` as they finish, the
    result being the exception instead when the task could not finish (a dead worker)."""

    workers: int

    def map_unordered(
        self, fn: Callable[..., R], items: Iterable[int], *args: object
    ) -> Iterator[tuple[int, R | BaseException]]: ...

    def close(self) -> None: ...


class WorkerDiedError(RuntimeError):
    """The worker process running a task died (a segfault, the OOM killer, os._exit)."""


def _exit_with_parent(parent_pid: int) -> None:
    """Poll the parent's pid; exit at once when the parent is gone (a worker is then
    adopted by init or a subreaper, so ``os.getppid()`` changes)."""
    while True:
        if os.getppid() != parent_pid:
            os._exit(_ORPHAN_EXIT_CODE)
        time.sleep(_PARENT_POLL_S)


def _init_worker(parent_pid: int) -> None:
    """Workers leave Ctrl-C to the campaign, which stops handing out episodes, lets the
    running ones finish and keeps everything written so far; and they never outlive the
    campaign: a watchdog thread ends the worker when its parent dies (``kill -9``), which
    no signal or pipe of the pool would tell it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(
        target=_exit_with_parent, args=(parent_pid,), name="albot2d-watchdog", daemon=True
    ).start()


class LocalBackend:
    """This machine's cores: a spawn-context process pool (or, for one worker, this process).

    When a worker process dies the pool is restarted and the tasks that were in flight are
    run again one at a time, so only the task that kills its worker is reported (as a
    ``WorkerDiedError``) and the others finish normally.
    """

    def __init__(self, workers: int) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise InputError(f"--workers must be a positive integer, got {workers!r}")
        if workers > MAX_LOCAL_WORKERS:
            raise InputError(
                f"--workers must be at most {MAX_LOCAL_WORKERS} on one machine, got {workers!r}"
            )
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_worker,
                initargs=(os.getpid(),),
            )
        return self._pool

    def _restart(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None

    def map_unordered(
        self, fn: Callable[..., R], items: Iterable[int], *args: object
    ) -> Iterator[tuple[int, R | BaseException]]:
        if self.workers == 1:
            for item in items:
                yield item, fn(*args, item)
            return
        queue = iter(items)
        suspects: list[int] = []  # in flight when a worker died: rerun one at a time
        pending: dict[Future[R], int] = {}
        window = self.workers * _IN_FLIGHT_PER_WORKER
        isolating = False
        try:
            while True:
                if suspects and not pending:
                    item = suspects.pop(0)
                    pending[self._executor().submit(fn, *args, item)] = item
                    isolating = True
                elif not suspects:
                    isolating = False
                    while len(pending) < window and (queued := next(queue, None)) is not None:
                        pending[self._executor().submit(fn, *args, queued)] = queued
                if not pending:
                    return
                done, _ = wait(set(pending), return_when=FIRST_COMPLETED)
                broken = False
                for future in done:
                    item = pending.pop(future)
                    exc = future.exception()
                    if isinstance(exc, BrokenProcessPool):
                        broken = True
                        if isolating:
                            yield (
                                item,
                                WorkerDiedError(
                                    f"the worker process died while running task {item}"
                                ),
                            )
                        else:
                            suspects.append(item)
                    else:
                        yield item, exc if exc is not None else future.result()
                if broken:
                    suspects.extend(pending.values())
                    pending.clear()
                    self._restart()
        finally:
            # Tasks still in flight when the caller stops early are not cancelled here:
            # close() cancels the queued ones, abort() ends them all. (A future cancelled
            # here would break the pool's own clean-up if abort() followed: CPython's
            # manager thread then fails to mark it broken, with a traceback.)
            pending.clear()

    def abort(self) -> None:
        """Stop now: terminate the worker processes, drop every task (a second Ctrl-C)."""
        if self._pool is None:
            return
        terminate = getattr(self._pool, "terminate_workers", None)
        if terminate is not None:  # pragma: no cover - Python >= 3.14
            terminate()
        else:
            # No public way to stop running tasks before Python 3.14's terminate_workers:
            # the pool's own table of its processes.
            for process in list((getattr(self._pool, "_processes", None) or {}).values()):
                with contextlib.suppress(Exception):
                    process.terminate()
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = None

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


def _check_address(address: str) -> tuple[str, int]:
    """``(host, port)`` of a ``tcp://HOST:PORT`` scheduler address; InputError naming it if not."""
    try:
        parts = urlsplit(address if "://" in address else f"tcp://{address}")
        port = parts.port  # urllib raises ValueError for a port that is not 0-65535
    except ValueError:
        port = None
        parts = None
    if parts is None or parts.scheme not in ("tcp", "tls") or not parts.hostname or not port:
        raise InputError(f"--address {address!r}: expected tcp://HOST:PORT (port 1-65535)")
    return parts.hostname, port


def _check_reachable(address: str) -> None:
    """Fail fast, with one line, when nothing listens at ``tcp://HOST:PORT``."""
    host, port = _check_address(address)
    try:
        with socket.create_connection((host, port), timeout=_CONNECT_TIMEOUT_S):
            pass
    except OSError as exc:
        raise InputError(
            f"--address {address}: no dask scheduler reachable there ({exc.strerror or exc})"
        ) from None


class DaskBackend:
    """A dask.distributed cluster: the scheduler at ``address``, or a new local cluster."""

    def __init__(self, address: str | None = None, workers: int = 1) -> None:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise InputError(
                "--backend dask needs dask.distributed: pip install 'albot2d[dask]'"
            ) from None
        self._cluster: Any = None  # a dask LocalCluster: dask ships no types
        if address is not None:
            _check_reachable(address)
            try:
                self._client = Client(address, timeout=_CONNECT_TIMEOUT_S)
            except (OSError, TimeoutError) as exc:
                raise InputError(
                    f"--address {address}: cannot connect to a dask scheduler ({exc})"
                ) from None
        else:
            self._cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address=None,
            )
            self._client = Client(self._cluster)
        self.workers = max(1, sum(self._client.nthreads().values()))

    def map_unordered(
        self, fn: Callable[..., R], items: Iterable[int], *args: object
    ) -> Iterator[tuple[int, R | BaseException]]:
        from dask.distributed import wait as dask_wait

        queue = iter(items)
        pending: dict[Any, int] = {}  # dask Futures: dask ships no types
        window = self.workers * _IN_FLIGHT_PER_WORKER
        try:
            while True:
                while len(pending) < window and (item := next(queue, None)) is not None:
                    # pure=False: every call runs, never deduplicated or cached.
                    pending[self._client.submit(fn, *args, item, pure=False)] = item
                if not pending:
                    return
                for future in dask_wait(list(pending), return_when="FIRST_COMPLETED").done:
                    item = pending.pop(future)
                    exc = future.exception()
                    yield item, exc if exc is not None else future.result()
        finally:
            for future in pending:
                future.cancel()

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._client.close()
        if self._cluster is not None:
            with contextlib.suppress(Exception):
                self._cluster.close()


def make_backend(name: str, *, workers: int, address: str | None = None) -> Backend:
    """The backend called ``name`` (``local`` or ``dask``); checks the combination."""
    if name not in BACKENDS:
        raise InputError(f"unknown backend {name!r}; valid: {', '.join(BACKENDS)}")
    if name == "local":
        if address is not None:
            raise InputError("--address is for --backend dask")
        return LocalBackend(workers)
    return DaskBackend(address, workers)
