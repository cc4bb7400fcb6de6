"""Checks across input files before anything is computed or written.

Output locations are checked by :class:`spherecal.correction.files.outputs.OutputSet` (the one mechanism).
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, SpherecalError, tool_point
from spherecal.correction.tool import TOOL_MATCH_TOL, arm_of, nominal_tool_of, tools_apart

#: A model whose tool point lies further than this from the nominal one's on some configuration is
#: not a description of the same arm [m] (as :data:`controller.compensation.MAX_MODEL_DIFFERENCE`).
MAX_MODEL_DIFFERENCE = 0.05
#: Configurations on which the tool points are compared (seeded: the check is reproducible).
_PROBES = 200


class ValidationInputError(SpherecalError):
    """Input files that do not fit together (one line naming the file and the field)."""


def check_models(models: dict[str, RobotModel], files: dict[str, str]) -> None:
    """Every model describes the nominal arm: same joint count, DH convention and joint limits, and a
    tool point within :data:`MAX_MODEL_DIFFERENCE` of the nominal one's (as ``compensate`` checks). A calibration
    of this robot file (its record names the nominal's tool) is compared with the nominal's tool: the arms alone.

    Args:
        models: role (``"nominal"``, ``"calibrated"``, ``"truth"``) -> model; ``"nominal"`` first.
        files: role -> the file it came from (for the message).

    Raises:
        ValidationInputError: on the first mismatch.
    """
    reference = models["nominal"]
    q = reference.random_configurations(_PROBES, np.random.default_rng(0))
    nominal_tool = tool_point(reference, q)
    for role, model in models.items():
        mismatch = reference.mismatch(model, limits=True)
        if mismatch is not None:
            field, what = mismatch
            raise ValidationInputError(f"{files[role]}: field {field}: {what} as in the nominal {files['nominal']}")
        swapped = isinstance(model.extras.get("tool_swap"), dict)
        gap = np.linalg.norm(tool_point(arm_of(model, reference), q) - nominal_tool, axis=1)
        if not np.all(gap <= MAX_MODEL_DIFFERENCE):
            worst = float(np.nanmax(np.where(np.isfinite(gap), gap, np.inf)))
            field, why = (("tool", "its tool was replaced by `spherecal tool`: validate the calibrated file it was "
                           "made from, whose tool point is the one the data was recorded with") if swapped else
                          ("joints", "a model of another arm?"))
            raise ValidationInputError(
                f"{files[role]}: field '{field}': tool point up to {worst * 1e3:.0f} mm from the nominal "
                f"{files['nominal']}'s (more than {MAX_MODEL_DIFFERENCE * 1e3:.0f} mm: {why})"
            )
        apart = tools_apart(model, reference)
        if not swapped and apart > TOOL_MATCH_TOL:  # a calibration with the ball against a nominal at the flange: the
            raise ValidationInputError(  # two figures would be of different points, the nominal's inflated by the gap
                f"{files[role]}: field 'calibration.nominal_tool': its tool point calibrates the tool at "
                f"{np.round(nominal_tool_of(model), 6).tolist()} m in the last frame, {apart * 1e3:.1f} mm from the "
                f"nominal {files['nominal']}'s {np.round(reference.tool, 6).tolist()} m (give --nominal the robot file "
                "and --tip-link it was calibrated with)"
            )
