"""The tool point the samples pin down, for a robot file whose tool is not the one recorded.

A ball on a force-torque sensor, an adapter plate or another holder puts the recorded tool point centimetres
from the robot file's; the arm's own errors move it by millimetres. Started from the file's tool, the fit
moves it that far and :func:`.calibrate.check_plausible` refuses the result as noise fitted along directions
the samples barely see, although every fixture pins the tool point (MUKCa's ``panda_1_with_sensor``: the ball
36-41 mm further out than ``panda.urdf`` says; calibrated, 0.29-0.33 mm held out against 20-22 mm nominal).

:func:`pivot_tool` is the classic pivot calibration with the arm at its nominal model: each sample's tool point
is ``p_k + R_k t`` (last joint frame origin and orientation, ``t`` the tool point in that frame), every sample
of a fixture at one centre, so ``t`` solves the linear least squares of the per-fixture deviations from their
means. :func:`recentred_tool` uses it only when the robot file's tool is beyond the plausibility limit from it;
otherwise the calibration is untouched.
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import Dataset, RobotModel

from .calibrate import MAX_CHANGE, tool_point_change
from .ingest.segment import last_frames
from .selfcheck import MAX_SOCKET_NOISE


def pivot_tool(model: RobotModel, dataset: Dataset) -> tuple[np.ndarray, float, float]:
    """(3,) tool point [m] in the last joint frame that best puts each fixture's samples at one point, the
    rest of ``model`` as it is (its compliance and scale included); the samples' rms distance from their
    fixture's mean point per axis with it [m]; and the largest std of the tool's coordinates at that spread
    [m] (inf when the motion recorded does not determine the tool: too few samples, too little rotation)."""
    frame, origin = last_frames(model, dataset.q)
    lhs, rhs = frame.copy(), -origin
    for name in dataset.fixture_names:
        rows = dataset.labels == name
        lhs[rows] -= lhs[rows].mean(axis=0)
        rhs[rows] -= rhs[rows].mean(axis=0)
    lhs, rhs = lhs.reshape(-1, 3), rhs.reshape(-1)
    solution, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    residual = lhs @ solution - rhs
    spread = float(np.sqrt(np.mean(residual**2)))
    dof = rhs.size - 3 - 3 * len(dataset.fixture_names)
    singular = np.linalg.svd(lhs, compute_uv=False)
    if dof <= 0 or singular[-1] <= 1e-9 * max(singular[0], 1e-300):
        return solution, spread, float("inf")
    std = float(np.sqrt(residual @ residual / dof)) / singular[-1]
    return solution, spread, std


def recentred_tool(nominal: RobotModel, dataset: Dataset, max_change: float = MAX_CHANGE,
                   pivot: tuple[np.ndarray, float, float] | None = None) -> tuple[RobotModel, str | None]:
    """``nominal`` with the tool point the samples pin down, and a warning, when its own is implausibly far.

    Far means what :func:`.calibrate.check_plausible` refuses: the change moves the tool points more than
    ``max_change`` times what a real arm's errors do. The recorded motion must pin that tool down (its std at the
    samples' spread within what a real arm's errors move the tool points), and it must explain them: they lie
    within :data:`.selfcheck.MAX_SOCKET_NOISE` per axis of their fixture's point, else the robot file does not
    describe the arm (another arm, its convention, its units) and the self-check says so. Otherwise
    ``(nominal, None)``: the calibration starts from, and its prior pulls toward, the robot file as given.
    ``pivot``: :func:`pivot_tool` of ``nominal`` and ``dataset`` when the caller has it already.
    """
    tool, spread, std = pivot_tool(nominal, dataset) if pivot is None else pivot
    params = nominal.params.copy()
    params[nominal.layout.tool] = tool
    change, typical = tool_point_change(nominal, params, zeros=False)  # a tool against the geometry's errors
    determined = np.all(np.isfinite(tool)) and std <= typical  # the motion recorded pins the tool down
    if not (determined and spread <= MAX_SOCKET_NOISE) or change <= max_change * typical:
        return nominal, None
    shift = (tool - nominal.tool) * 1e3
    note = (f"tool point: the samples put it {np.linalg.norm(shift):.1f} mm from the robot file's "
            f"([{shift[0]:.1f}, {shift[1]:.1f}, {shift[2]:.1f}] mm in the last joint frame; a real arm's errors "
            f"move it about {typical * 1e3:.1f} mm): an adapter or sensor the description lacks? The calibration "
            "starts from, and its prior pulls toward, the tool the samples show; a tool swap (spherecal tool) and the "
            "controller will ask whether it is an adapter every tool sits on")
    return nominal.with_params(params), note
