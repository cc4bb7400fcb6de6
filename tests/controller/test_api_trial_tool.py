"""A controls engineer's trial of the tool swap in Python (``correction.with_tool``): inputs in the wrong unit or of
the wrong kind are refused in one line naming the field, instead of a tool point metres away (or a payload the
gravity torques choke on later)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import load_robot, perturb, tool_point
from spherecal.correction.tool import ToolError, with_tool


@pytest.fixture
def calibrated():
    """A perturbed Panda standing for a calibration with the ball at the flange (nominal tool ``[0, 0, 0.107]``)."""
    panda = load_robot("panda")
    model = perturb(panda, np.random.default_rng(3))
    return replace(model, extras={**model.extras, "calibration": {"nominal_tool": [float(v) for v in panda.tool]}})


def test_nominal_tool_in_millimetres_is_refused(calibrated) -> None:
    """``nominal_tool=[0, 0, 107]`` (millimetres) carried ``tool - nominal_tool`` over as -107 m: the new tool point
    was 106.7 m behind the flange, and the controller took it."""
    right = with_tool(calibrated, [0.0, 0.0, 0.2104], nominal_tool=[0.0, 0.0, 0.107])
    assert np.linalg.norm(right.model.tool - calibrated.tool) == pytest.approx(0.1034, abs=1e-12)
    with pytest.raises(ToolError, match=r"field 'calibration.nominal_tool'.*millimetres"):
        with_tool(calibrated, [0.0, 0.0, 0.2104], nominal_tool=[0.0, 0.0, 107.0])
    q = calibrated.random_configurations(5, np.random.default_rng(0))  # the right swap: 0.1034 m along z7 further
    assert np.all(np.linalg.norm(tool_point(right.model, q) - tool_point(calibrated, q), axis=1) < 0.11)
