"""Shared by the bench scripts; import it first.

One BLAS thread, as the command-line tools use, and no Rerun analytics.
"""

from __future__ import annotations

import os
import time

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("RERUN_ANALYTICS", "0")


def median_time(function, repeats: int = 9) -> float:
    """Median wall time [s] of ``function()`` over ``repeats`` runs, after one warm-up run."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2]
