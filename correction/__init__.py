"""Kinematic model of a serial arm: parameters, robot files, batched FK and Jacobians, and the
spherical-joint data files (samples and fixtures).

This is what a controller imports: it depends on nothing else of spherecal.
"""

from .chain import Frames, frames, link_frames
from .conversion import convert, to_modified, to_standard
from .errors import SpherecalError
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
from .perturb import perturb
from .rigid import apply_transform, fit_rigid_transform, registered_errors
from .tool import ToolError, ToolSwap, with_tool

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
]
