"""Thread caps that hold: BLAS and OpenMP pools at one thread (or the user's own setting), in a
command's process and in every pool or cluster worker.

Our linear algebra is small (a few thousand rows, ~35 columns): a second BLAS thread only adds
start-up and, on a shared machine, stalls (one thin SVD: ~8 ms on one thread, 144-216 ms on two
contended ones, issue 23); in a pool of N processes each would start its own. Two mechanisms, as a
library reads its setting once, when it loads:

* :func:`cap_environment` sets the variables (unless the user set them) for libraries that load
  later, in this process or in its children; the command line calls it before numpy loads.
* :func:`thread_cap` also limits the libraries already loaded (threadpoolctl), for the duration of
  a command or of a task in a worker that someone else started (a pool, a Dask cluster).

Nothing numerical is imported here (the command line imports this module before numpy).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, MutableMapping
from contextlib import contextmanager
from typing import Any, TypeVar

from threadpoolctl import ThreadpoolController, threadpool_info

#: Environment variable -> the threadpoolctl ``internal_api`` it sets.
VARIABLES: dict[str, str] = {
    "OPENBLAS_NUM_THREADS": "openblas",
    "MKL_NUM_THREADS": "mkl",
    "BLIS_NUM_THREADS": "blis",
    "OMP_NUM_THREADS": "openmp",
}

T = TypeVar("T")


def cap_environment(environ: MutableMapping[str, str] | None = None) -> None:
    """Set each of :data:`VARIABLES` to ``"1"`` unless it is set (the user's setting wins)."""
    environ = os.environ if environ is None else environ
    for variable in VARIABLES:
        environ.setdefault(variable, "1")


def limits(environ: MutableMapping[str, str] | None = None) -> dict[str, int]:
    """internal_api -> thread limit: the user's setting of its variable (a positive integer), else 1."""
    environ = os.environ if environ is None else environ
    out = {}
    for variable, api in VARIABLES.items():
        text = environ.get(variable, "1").split(",")[0].strip()  # OMP's nested "4,2": the outer level
        out[api] = int(text) if text.isdigit() and int(text) > 0 else 1
    return out


@contextmanager
def thread_cap() -> Iterator[None]:
    """Within: every loaded BLAS/OpenMP pool at its :func:`limits`; libraries loading later read
    the variables :func:`cap_environment` set. The previous limits come back on exit."""
    cap_environment()
    controller = ThreadpoolController()  # the libraries loaded now
    with controller.limit(limits=_by_file(controller)):
        yield


def cap_process() -> None:
    """Cap this process's pools for good, as :func:`thread_cap` does (a worker process's: nothing to restore)."""
    cap_environment()
    controller = ThreadpoolController()
    controller.limit(limits=_by_file(controller))  # left in force


def _by_file(controller: ThreadpoolController) -> dict[str, int]:
    """Each loaded library (its file) -> the limit of its kind."""
    wanted = limits()
    return {lib.filepath: wanted[lib.internal_api] for lib in controller.lib_controllers if lib.internal_api in wanted}


def capped(function: Callable[..., T], *args: Any) -> T:
    """``function(*args)`` under :func:`thread_cap` (picklable: what a pool or cluster worker runs)."""
    with thread_cap():
        return function(*args)


def blas_threads() -> dict[str, int]:
    """Loaded BLAS/OpenMP library (its file name) -> its current thread count (a diagnostic)."""
    return {os.path.basename(info["filepath"]): info["num_threads"] for info in threadpool_info()}
