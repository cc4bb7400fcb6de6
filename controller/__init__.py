"""Controller: MuJoCo plant built from DH parameters, QP differential IK, self-motion.

Public names are loaded lazily (PEP 562) so that ``spherecal --help``, which imports
``spherecal.commands``, does not import numpy or MuJoCo.

The IK is :func:`controller.ik.ik` (``from spherecal.controller.ik import ik``): the package does not export the
function under the name of its module. Python puts the submodule on the package as ``ik`` whenever anything imports
it, so the name was the module after any import of the compensation (a controls engineer's trial: ``TypeError:
'module' object is not callable``); ``from spherecal.controller import ik`` gives the module.
"""

from __future__ import annotations

import importlib

_EXPORTS: dict[str, str] = {
    "CoverageExploration": "exploration",
    "Ramp": "exploration",
    "RandomExploration": "exploration",
    "joint_coverage": "exploration",
    "make_exploration": "exploration",
    "Export": "export",
    "export_model": "export",
    "IKResult": "ik",
    "UnreachableError": "ik",
    "NullSpaceController": "nullspace",
    "Plant": "plant",
    "build_mjcf": "plant",
    "build_plant": "plant",
    "RigidFit": "rigid_fit",
    "rigid_approximation": "rigid_fit",
    "ControllerFallbackWarning": "qp_ik",
    "PersistentOSQP": "qp_ik",
    "QPSolveError": "qp_ik",
    "build_problem": "qp_ik",
    "damped_pinv_velocity": "qp_ik",
    "solve_qp": "qp_ik",
    "solve_step": "qp_ik",
    "task_share": "qp_ik",
    "velocity_bounds": "qp_ik",
    "FixtureInsideRobotError": "reach",
    "SelfMotionRun": "self_motion",
    "SelfMotionSettings": "self_motion",
    "UnreachableFixtureError": "reach",
    "base_radius": "reach",
    "size_vs_panda": "reach",
    "check_fixture": "reach",
    "check_fixture_distance": "reach",
    "collect_self_motion": "self_motion",
    "reach_fixture": "self_motion",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
