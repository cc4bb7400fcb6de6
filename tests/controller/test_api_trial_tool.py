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


@pytest.mark.parametrize("payload, field", [
    ({"mass": "heavy"}, "payload.mass"),
    ({"mass": -1.0, "com": [0.0, 0.0, 0.1]}, "payload.mass"),
    ({"mass": 1.0, "com": [0.0, 0.0, 140.0]}, "payload.com"),  # millimetres
    ([1.0], "payload"),
])
def test_a_malformed_payload_is_refused_by_the_swap(calibrated, payload, field) -> None:
    """A payload was stored as given: the swap returned, and the first gravity torque (an elastic model's every tool
    point) raised later, far from the call that caused it, or an export wrote it."""
    with pytest.raises(ToolError, match=rf"field '{field}'"):
        with_tool(calibrated, [0.0, 0.0, 0.2104], payload=payload)
    good = with_tool(calibrated, [0.0, 0.0, 0.2104], payload={"mass": 1.2, "com": [0.0, 0.0, 0.15]})
    assert good.model.extras["payload"]["mass"] == 1.2


def test_adapter_and_angle_must_be_what_they_say(calibrated) -> None:
    """``adapter="no"`` read as True (a non-empty string) and carried an offset the user meant not to carry; an
    angle in degrees (0.2 for the prior's 0.2 deg) or a negative one printed a figure 57x too large or below zero."""
    for adapter in ("no", 1):
        with pytest.raises(ToolError, match="field 'adapter'"):
            with_tool(calibrated, [0.0, 0.0, 0.2104], adapter=adapter)
    for angle in (-0.01, float("nan"), 0.2):
        with pytest.raises(ToolError, match="field 'angle'"):
            with_tool(calibrated, [0.0, 0.0, 0.2104], angle=angle)
    swap = with_tool(calibrated, [0.0, 0.0, 0.2104], angle=np.deg2rad(0.5))
    assert swap.unidentified == pytest.approx(np.sin(np.deg2rad(0.5)) * swap.distance)
