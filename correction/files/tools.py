"""Another tool on a calibrated arm, from an offset or from the user's URDF (:mod:`correction.tool`)."""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np

from ..gravity import has_inertials
from ..model import RobotModel
from ..tool import NOMINAL_TOOL, SAMPLES_TOOL, ToolError, ToolSwap, point_of, tool_in_frame, with_tool
from .urdf_to_dh import load_urdf


def put_tool(model: RobotModel, offset: np.ndarray | None = None, urdf: str | os.PathLike | None = None,
             tip_link: str | None = None, base_link: str | None = None,
             source: str | os.PathLike | None = None, adapter: bool | None = None) -> tuple[ToolSwap, str]:
    """``model`` with the tool at ``offset`` (in the last DH frame [m]) or at ``tip_link`` of ``urdf``.

    Args:
        model: the calibrated model.
        offset: (3,) the new tool's nominal point in the last DH frame [m] (a calibrated file records its
            old tool's nominal point, ``calibration.nominal_tool``: the calibration's correction of it is
            carried to the new tool, see :func:`correction.tool.with_tool`); or
        urdf, tip_link, base_link: a URDF of the same arm with the new tool, its link at the tool point (the
            chain's last frame must be the model's: :func:`correction.tool.tool_in_frame`). When the URDF has
            masses, what its last link carries (gripper, fingers) becomes the payload.
        source: the calibrated file, named in a refusal of its ``calibration.nominal_tool``.
        adapter: whether the offset at which the samples put the ball (``calibration.samples_tool``, recorded when
            it is beyond a calibration's correction from the robot file's tool) is an adapter every tool sits on
            (True: carried to the new tool) or the ball's own (False); needed only then
            (:func:`correction.tool.with_tool`).

    Returns:
        ``(swap, one line on the payload)``.

    Raises:
        ToolError: neither or both of ``offset`` and ``urdf``, a URDF of another arm, or a tool point
            :func:`.tool.with_tool` refuses.
        RobotFileError: an unreadable URDF or an unknown link (one line).
    """
    if (offset is None) == (urdf is None):
        raise ToolError("field '--offset': give either an offset [m] in the last frame or (--urdf) a URDF with its tip "
                        "link")
    payload = None
    if urdf is not None:
        description = load_urdf(urdf, tip_link=tip_link, base_link=base_link)
        offset = _tool_of(description, model, urdf, base_link)
        if has_inertials(description):
            payload = description.extras["payload"]
    block = model.extras.get("calibration")
    nominal = block.get("nominal_tool") if isinstance(block, dict) else None
    samples = block.get("samples_tool") if isinstance(block, dict) else None
    if nominal is not None:  # a hand-edited file: its name and field, not a traceback ('nominal_tool: abc')
        nominal = point_of(nominal, f"{source or model.name}: field '{NOMINAL_TOOL}'")
        samples = None if samples is None else point_of(samples, f"{source or model.name}: field '{SAMPLES_TOOL}'")
    swap = with_tool(model, offset, payload, nominal_tool=nominal, field="--offset" if urdf is None else "--tip-link",
                     samples_tool=samples, adapter=adapter, source=None if source is None else str(source))
    swap = replace(swap, model=_retipped(swap.model, description.extras.get("urdf") if urdf is not None else None))
    if payload is not None:
        line = f"payload from {urdf}: {payload['mass']:.3f} kg (what its last link carries)"
    elif "payload" in model.extras:
        line = (f"payload kept: {model.extras['payload'].get('mass', 0.0):.3f} kg from the calibrated file (edit "
                f"'payload' if the new tool weighs differently: the gravity sag of an elastic model depends on it)")
    else:
        line = "no payload in the calibrated file"
    return swap, line


def _tool_of(description: RobotModel, model: RobotModel, urdf: str | os.PathLike, base_link: str | None) -> np.ndarray:
    """:func:`.tool.tool_in_frame`, its refusal naming the URDF, the option and the chain it read: a tool link
    before the flange (``--tip-link panda_link3``) was 'tool description: joints: 3 joints, expected 7'."""
    try:
        return tool_in_frame(description, model)
    except ToolError as error:
        links = description.extras.get("urdf", {})
        chain = f"the chain from '{links.get('base_link')}' to '{links.get('tip_link')}'"
        field = "--tip-link" if base_link is None else "--base-link"
        if description.n_joints < model.n_joints:
            raise ToolError(f"{urdf}: field '{field}': {chain} has {description.n_joints} joints, the calibrated arm "
                            f"{model.n_joints}: the tool link must lie beyond the arm's last joint (on its flange) and "
                            "the base link be the arm's base") from None
        if description.n_joints > model.n_joints:
            raise ToolError(f"{urdf}: field '--urdf': {chain} has {description.n_joints} joints, the calibrated arm "
                            f"{model.n_joints}: a URDF of another arm") from None
        raise ToolError(f"{urdf}: field '--urdf': {chain}: {str(error).removeprefix('tool description: ')}") from None


def _retipped(model: RobotModel, links: dict | None) -> RobotModel:
    """``model`` whose ``urdf`` block names the new tool's link: ``links`` (the tool URDF's base and tip), or no
    tip link for an offset (the old one, the ball, is no longer the tool point: ``export --into`` would move it)."""
    block = model.extras.get("urdf")
    if not isinstance(block, dict):
        return model
    block = dict(block)
    if links:
        block.update(base_link=links["base_link"], tip_link=links["tip_link"])
    else:
        block.pop("tip_link", None)
    return replace(model, extras={**model.extras, "urdf": block})
