"""Conversion between standard and modified DH descriptions of the same arm.

A modified chain ``B prod_i [Rx(alpha_i) Lx(a_i) Rz(theta_i+q_i) Lz(d_i)] t`` regroups as
``B Rx(alpha_1) Lx(a_1) prod_i [Rz(theta_i+q_i) Lz(d_i) Lx(a_{i+1}) Rx(alpha_{i+1})] t``
with ``a_{n+1} = alpha_{n+1} = 0``: the first joint's ``a, alpha`` move into the base.
The other way, the last standard joint's trailing ``Lx(a_n) Rx(alpha_n)`` moves into the
tool point. A Hayati ``Ry(beta)`` travels with its ``Lx(a) Rx(alpha)``: modified joint ``i+1``'s
``beta`` is standard joint ``i``'s. Both keep every tool point, for every configuration, exactly, and move
the link inertials into the new link frames (gravity torques unchanged).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .gravity import has_inertials
from .inertials import transfer_inertials
from .model import RobotModel, matrix_rpy


def _link_x(a: float, alpha: float, beta: float = 0.0) -> np.ndarray:
    """(4, 4) ``Lx(a) Rx(alpha) Ry(beta)`` (``Lx(a) Rx(alpha) = Rx(alpha) Lx(a)``: both act along x)."""
    c, s = np.cos(alpha), np.sin(alpha)
    pose = np.array([[1.0, 0, 0, a], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])
    if beta != 0.0:
        cb, sb = np.cos(beta), np.sin(beta)
        pose = pose @ np.array([[cb, 0, sb, 0], [0, 1.0, 0, 0], [-sb, 0, cb, 0], [0, 0, 0, 1.0]])
    return pose


def to_standard(model: RobotModel) -> RobotModel:
    """The same arm in standard DH; the first joint's ``a, alpha`` (and ``beta``) go into the base.

    Args:
        model: the arm, either convention (a standard one is returned as it is).

    Returns:
        A model with the same tool point and tool orientation at every configuration (to rounding), the same
        joint limits, compliance, scale and other ``extras``; link inertials moved into the new link frames.
    """
    if model.convention == "standard":
        return model
    return _inertials_moved(_to_standard(model), model)


def _to_standard(model: RobotModel) -> RobotModel:
    base = model.base_transform @ _link_x(model.a[0], model.alpha[0], model.beta[0])
    return replace(
        model,
        convention="standard",
        a=np.append(model.a[1:], 0.0),
        alpha=np.append(model.alpha[1:], 0.0),
        beta=np.append(model.beta[1:], 0.0),
        hayati=tuple(j - 1 for j in model.hayati if j >= 1),
        base_xyz=base[:3, 3],
        base_rpy=matrix_rpy(base[:3, :3]),
    )


def to_modified(model: RobotModel) -> RobotModel:
    """The same arm in modified DH; the last joint's ``a, alpha`` (and ``beta``) go into the tool point.

    Args:
        model: the arm, either convention (a modified one is returned as it is).

    Returns:
        A model with the same tool point at every configuration (to rounding), the same joint limits,
        compliance, scale and other ``extras``; link inertials moved into the new link frames. The last link's
        ``a, alpha`` become a tool offset, so the last frame, and :func:`.kinematics.tool_pose`'s orientation,
        differ from the standard model's unless they are zero.
    """
    if model.convention == "modified":
        return model
    return _inertials_moved(_to_modified(model), model)


def _to_modified(model: RobotModel) -> RobotModel:
    tool = (_link_x(model.a[-1], model.alpha[-1], model.beta[-1]) @ np.append(model.tool, 1.0))[:3]
    return replace(
        model,
        convention="modified",
        a=np.insert(model.a[:-1], 0, 0.0),
        alpha=np.insert(model.alpha[:-1], 0, 0.0),
        beta=np.insert(model.beta[:-1], 0, 0.0),
        hayati=tuple(j + 1 for j in model.hayati if j + 1 < model.n_joints),
        tool=tool,
    )


def convert(model: RobotModel, convention: str) -> RobotModel:
    """The same arm in ``convention``: :func:`to_standard` or :func:`to_modified`.

    Args:
        model: the arm, either convention.
        convention: ``"standard"`` or ``"modified"``.

    Raises:
        ValueError: another ``convention``.
    """
    if convention == "standard":
        return to_standard(model)
    if convention == "modified":
        return to_modified(model)
    raise ValueError(f"unknown convention {convention!r}")


def _inertials_moved(converted: RobotModel, model: RobotModel) -> RobotModel:
    """``converted`` with ``model``'s link inertials moved into its own link frames (a link's frame differs
    between the conventions: standard frame ``i`` sits on joint ``i+1``'s axis, modified frame ``i`` on joint
    ``i``'s), so that gravity torques do not change with the convention."""
    if not has_inertials(model):
        return converted
    moved = transfer_inertials(converted, model, ignore_base=False)
    assert moved is not None  # the same axes by construction
    return moved



