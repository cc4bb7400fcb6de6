"""Kinematic model of a serial arm: parameters, robot files, batched FK and Jacobians, and the
spherical-joint data files (samples and fixtures).

This is what a controller imports: it depends on nothing else of spherecal. Arrays are metres and radians,
batched with the sample axis first: ``q`` (N, n) joint angles [rad] of an n-joint arm, or (n,) for one
configuration. Every name below is importable from ``spherecal.correction`` and documented in the module that
defines it (the API reference lists them by group):

* the model: :class:`~.model.RobotModel`, :func:`~.files.robots.load_robot`, :func:`~.files.urdf_to_dh.load_urdf`,
  robot files (:func:`~.files.robot_file.save_robot`, ...), :func:`~.perturbation.perturb`, :func:`~.tool.with_tool`,
  :func:`~.conversion.convert`, the elastic and scaled models (:func:`~.elastic.with_stiffness`,
  :func:`~.scale.with_scale`);
* kinematics on measured angles: :func:`~.kinematics.tool_point`, :func:`~.kinematics.tool_pose`,
  :func:`~.kinematics.joint_jacobian`, :func:`~.kinematics.pose_jacobian`, :func:`~.kinematics.param_jacobian`;
  on link angles: :func:`~.chain.link_frames`, :func:`~.gravity.gravity_torques`;
* the data files: samples (:class:`~.files.samples.Dataset`) and fixtures;
* the exceptions, all :class:`~.errors.SpherecalError`: :class:`~.kinematics.JointAngleError`,
  :class:`~.files.robot_file.RobotFileError`, :class:`~.gravity.InertialsError`, :class:`~.scale.ScaleError`,
  :class:`~.tool.ToolError`, :class:`~.files.samples.DatasetError`, :class:`~.errors.ShapeError` (joint angles of
  the wrong shape: a ``ValueError`` too).
"""

from .chain import Frames, frames, link_frames
from .conversion import convert, to_modified, to_standard
from .elastic import with_compliance, with_stiffness
from .errors import ShapeError, SpherecalError
from .files.atomic import atomic_write_bytes, atomic_write_text
from .files.fixtures import FixtureSpec, format_fixtures, read_fixtures, write_fixtures
from .files.robot_file import (
    RobotFileError,
    dump_robot,
    robot_from_dict,
    robot_to_dict,
    save_robot,
)
from .files.robots import load_robot
from .files.samples import Dataset, DatasetError
from .files.samples_csv import format_samples, read_samples, write_samples
from .files.urdf_to_dh import NearlyParallelAxesWarning, load_urdf
from .gravity import InertialsError, gravity_torques, has_inertials, inertials_of
from .kinematics import (
    JointAngleError,
    joint_jacobian,
    link_angle_jacobian,
    param_jacobian,
    pose_jacobian,
    tool_point,
    tool_pose,
)
from .model import RobotModel, geometric_part, matrix_rpy, param_names, pose_matrix, rpy_matrix
from .perturbation import perturb
from .rigid import apply_transform, fit_rigid_transform, registered_errors
from .scale import ScaleError, with_scale
from .tool import CarriedTipWarning, ToolError, ToolSwap, with_tool

__all__ = [
    "Dataset",
    "DatasetError",
    "FixtureSpec",
    "format_fixtures",
    "format_samples",
    "read_fixtures",
    "read_samples",
    "write_fixtures",
    "write_samples",
    "Frames",
    "InertialsError",
    "JointAngleError",
    "NearlyParallelAxesWarning",
    "RobotFileError",
    "RobotModel",
    "ShapeError",
    "SpherecalError",
    "apply_transform",
    "atomic_write_bytes",
    "atomic_write_text",
    "convert",
    "dump_robot",
    "fit_rigid_transform",
    "frames",
    "geometric_part",
    "gravity_torques",
    "has_inertials",
    "inertials_of",
    "joint_jacobian",
    "link_angle_jacobian",
    "link_frames",
    "load_robot",
    "load_urdf",
    "matrix_rpy",
    "param_jacobian",
    "param_names",
    "perturb",
    "pose_jacobian",
    "pose_matrix",
    "registered_errors",
    "robot_from_dict",
    "robot_to_dict",
    "rpy_matrix",
    "save_robot",
    "to_modified",
    "to_standard",
    "tool_point",
    "tool_pose",
    "ToolError",
    "ToolSwap",
    "with_tool",
    "CarriedTipWarning",
    "ScaleError",
    "with_compliance",
    "with_scale",
    "with_stiffness",
]
