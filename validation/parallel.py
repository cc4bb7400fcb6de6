"""Independent, seeded tasks over an executor; results in task order, whatever order they finish in.

Where the tasks run (:func:`executor`):

* ``workers=1``, no scheduler: in this process;
* the built-in process pool of ``workers`` processes (the default);
* a dask.distributed cluster (``scheduler``): ``"local"`` starts a LocalCluster of ``workers``
  processes bound to 127.0.0.1 for this run (closed at the end); any other value is the address of a
  running scheduler (``tcp://host:8786``), whose workers must have spherecal installed. Dask is the
  optional extra ``spherecal[dask]``, imported only when a scheduler is asked for.

:func:`run_tasks` takes any :class:`concurrent.futures.Executor`. Each task runs under the thread
cap (:mod:`validation.threads`) and also returns the name and package versions of the worker that
ran it; progress follows completed tasks; a task that raises is reported (a
:class:`TaskFailedWarning` naming it) and the others are kept. Tasks write nothing: the caller
writes the outputs, with the workers' versions in their provenance. A task's result depends on its
own seed only, so it is the same (bit for bit) in this process, in the pool or on a cluster.
"""

from __future__ import annotations

import functools
import logging
import os
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.provenance import this_process

from .threads import cap_process, thread_cap

#: Seconds to wait for a running scheduler to answer.
CONNECT_TIMEOUT = 10


class SchedulerError(SpherecalError):
    """``--scheduler`` cannot be used: Dask is not installed, or the scheduler does not answer."""


class TaskFailedWarning(UserWarning):
    """One task raised: it is reported (its name and the error, one line) and the others are kept."""


@dataclass(frozen=True)
class Failure:
    """A task that raised: its name and ``"ErrorType: message"``."""

    name: str
    error: str


@dataclass(frozen=True)
class Outcome:
    """What :func:`run_tasks` gives back.

    Attributes:
        results: one per task, in task order; ``None`` where the task failed.
        failures: the tasks that raised, in task order.
        workers: worker (``"host pid N"``; the command's own process ``"host main process"``) -> its package versions
            (``correction.files.provenance.this_process``), every worker that finished a task.
    """

    results: list[Any]
    failures: list[Failure] = field(default_factory=list)
    workers: dict[str, dict[str, str]] = field(default_factory=dict)


@functools.lru_cache(maxsize=4)
def _worker(pid: int) -> tuple[str, dict[str, str]]:
    """This process's name and package versions, once per process (by pid: a forked child has its own)."""
    return this_process()


@functools.lru_cache(maxsize=4)
def _capped_process(pid: int) -> None:
    """Cap this worker process's thread pools for good, once (a scan of the loaded libraries takes
    milliseconds); libraries loading later read the environment it sets."""
    cap_process()


def in_worker(function: Callable[[Any], Any], item: Any) -> tuple[Any, str, dict[str, str]]:
    """``function(item)`` in a worker process, capped, with the name and versions of that process."""
    _capped_process(os.getpid())
    return (function(item), *_worker(os.getpid()))


def _here(function: Callable[[Any], Any], item: Any) -> tuple[Any, str, dict[str, str]]:
    return (function(item), *_worker(os.getpid()))


def run_tasks(
    function: Callable[[Any], Any],
    items: Sequence[Any],
    executor: Executor | None = None,
    names: Sequence[str] | None = None,
    on_done: Callable[[], None] | None = None,
) -> Outcome:
    """``function(item)`` for every item, on ``executor`` (None: one after the other in this process).

    Args:
        function: a module-level (picklable) function of one item.
        items: the tasks (picklable), each carrying its own seed.
        executor: any process-based concurrent.futures.Executor (see :func:`executor`): each worker
            process is capped to one BLAS thread for good (a thread pool would cap this process).
        names: a name per task for the failure report (default: its index).
        on_done: called once per finished task (failed ones too), as they finish.

    Returns:
        The results in task order, the failures, the workers and their versions.
    """
    names = [str(i) for i in range(len(items))] if names is None else list(names)
    results: list[Any] = [None] * len(items)
    failures: dict[int, Failure] = {}
    workers: dict[str, dict[str, str]] = {}

    def finish(index: int, run: Callable[[], tuple[Any, str, dict[str, str]]]) -> None:
        try:
            results[index], worker, packages = run()
            workers[worker] = packages
        except Exception as error:  # one task's crash is reported, not the end of the others
            text = " ".join(f"{type(error).__name__}: {error}".split())
            failures[index] = Failure(names[index], text)
            warnings.warn(f"task {names[index]} failed: {text}", TaskFailedWarning, stacklevel=3)
        if on_done is not None:
            on_done()

    if executor is None:
        with thread_cap():  # in this process: capped while the tasks run, restored after
            for index, item in enumerate(items):
                finish(index, functools.partial(_here, function, item))
    else:
        futures = {executor.submit(in_worker, function, item): index for index, item in enumerate(items)}
        try:
            for future in as_completed(futures):
                finish(futures[future], future.result)
        except BaseException:  # interrupted: nothing more is started
            for future in futures:
                future.cancel()
            raise
    return Outcome(results, [failures[i] for i in sorted(failures)], workers)


@contextmanager
def executor(workers: int = 2, scheduler: str | None = None) -> Iterator[Executor | None]:
    """Where tasks run: None (this process: one worker, no scheduler), the built-in process pool, or a
    Dask cluster (``scheduler``: ``"local"`` or a running scheduler's address); closed on exit.

    Raises:
        SchedulerError: Dask is missing, or the scheduler does not answer.
    """
    if scheduler is not None:
        with _dask(scheduler, workers) as dask_executor:
            yield dask_executor
    elif workers <= 1:
        yield None
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            yield pool


@contextmanager
def _dask(scheduler: str, workers: int) -> Iterator[Executor]:
    try:
        from distributed import Client, LocalCluster  # dask: the optional extra spherecal[dask], only when asked for
    except ImportError:
        raise SchedulerError(
            f"field '--scheduler': {scheduler}: dask.distributed is not installed (pip install 'spherecal[dask]')"
        ) from None
    cluster = None
    if scheduler == "local":  # processes (one thread each), on this machine only, no dashboard
        import dask  # installed with distributed

        # Dask's nanny gives its workers MALLOC_TRIM_THRESHOLD_=65536, which turns off glibc's dynamic mmap
        # threshold: every numpy temporary above 128 KiB is then mmap'ed and unmapped again, and a campaign task
        # spent two thirds of its time in the kernel (2-3x slower than in the process pool). Our workers keep
        # glibc's default; the BLAS caps it sets stay.
        environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", default={}))
        environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None, silence_logs=logging.ERROR)
    try:
        try:
            client = Client(cluster if cluster is not None else scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, ValueError) as error:  # OSError: no answer; ValueError: not an address
            raise SchedulerError(f"field '--scheduler': {scheduler}: {' '.join(str(error).split())}") from None
        try:
            yield client.get_executor(pure=False)  # pure=False: every task runs, none is taken from a cache
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()
