"""Any robot description by path or name: a robot file (YAML), a URDF, or an embedded robot."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from ..model import RobotModel
from .robot_file import EMBEDDED_ROBOTS, RobotFileError, robot_from_dict
from .text_input import read_text
from .urdf_to_dh import load_urdf
from .yaml_safe import load_yaml


def load_robot(
    path_or_name: str | os.PathLike, tip_link: str | None = None, base_link: str | None = None
) -> RobotModel:
    """Load a robot file, a URDF (``.urdf``), or an embedded robot by name (``"panda"``).

    Args:
        path_or_name: YAML robot file, URDF file or embedded name.
        tip_link, base_link: URDF only: the chain to convert (see :func:`correction.urdf_to_dh.load_urdf`).

    Raises:
        RobotFileError: unreadable file, invalid YAML or URDF, an invalid field (one line).
    """
    key = str(path_or_name)
    if key.lower().endswith(".urdf"):
        return load_urdf(path_or_name, tip_link=tip_link, base_link=base_link)
    if Path(key).is_dir():  # before the link options: a folder is no robot description of any kind
        raise RobotFileError(f"{key}: cannot read: Is a directory (expected a robot file or a .urdf)")
    for option, value in (("tip link", tip_link), ("base link", base_link)):
        if value is not None:
            raise RobotFileError(f"{key}: a {option} ({value!r}) is only for a URDF robot description (.urdf)")
    if key in EMBEDDED_ROBOTS and not Path(key).exists():
        text = resources.files("spherecal.correction").joinpath("data", EMBEDDED_ROBOTS[key]).read_text()
        return robot_from_dict(load_yaml(text, key, RobotFileError)[0], source=key)
    path = Path(path_or_name)
    text = read_text(path, RobotFileError)
    data, _ = load_yaml(text, str(path), RobotFileError)  # bounded: size, depth, aliases; no duplicate keys
    return robot_from_dict(data, source=str(path))
