"""A controls engineer's trial of the Cartesian compensation (``controller.compensation.compensate``): its options
checked before the first controller evaluation."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot, tool_point


def test_compensate_refuses_a_tolerance_that_cannot_be_met() -> None:
    """``tol=-1`` ran 13 controller evaluations to a residual of 3e-15 mm and raised CompensationError "tolerance
    -1e+03 mm"; it is refused before the first, as ``max_iter < 0`` is."""
    from spherecal.controller.compensation import compensate
    from spherecal.correction import SpherecalError, perturb

    panda = load_robot("panda")
    calibrated = perturb(panda, np.random.default_rng(2))
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q0 + 0.05)
    calls = []

    def controller(model, command, q_seed, orientation):
        calls.append(command)
        return q_seed

    for tol, orientation_tol, field in ((-1.0, 1e-8, "tol"), (0.0, 1e-8, "tol"), (1e-9, -1.0, "orientation_tol"),
                                        (float("nan"), 1e-8, "tol")):
        with pytest.raises(SpherecalError, match=f"^{field}: expected"):
            compensate(target, panda, calibrated, q0, tol=tol, orientation_tol=orientation_tol, controller=controller)
    assert not calls
    done = compensate(target, panda, calibrated, q0)
    assert np.linalg.norm(tool_point(calibrated, done.q) - target) < 1e-9
