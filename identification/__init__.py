"""Identification: spherical-joint samples in, calibrated robot parameters out.

The public names are loaded lazily (importing the package loads no numpy)::

    from spherecal.identification import build_problem, CalibrationResult
    from spherecal.correction import read_samples, read_fixtures   # the data files are the base layer's
    from spherecal.identification.calibrate import calibrate   # (the submodule shares the function's name)
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS: dict[str, str] = {
    "CalibrationProblem": "problem",
    "UnidentifiableError": "problem",
    "build_problem": "build",
    "prune": "pruning",
    "CalibrationResult": "calibrate",
    "solve_lm": "solvers",
    "solve_pso": "solvers",
    "solve_scipy": "solvers",
    "Identifiability": "identifiability",
    "make_dataset": "synthetic",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'identification' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
