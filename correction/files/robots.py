"""Any robot description by path or name: a robot file (YAML), a URDF, or an embedded robot.

Link inertials (for gravity torques and the elastic model), in this order: an ``inertials`` file given by
the caller (:mod:`.inertials_file`); the description's own (a robot file's ``inertials:`` block, a URDF's
``<inertial>`` elements); else those of an embedded arm whose joint axes the chain shares
(:func:`embedded_inertials`: the Panda, FR3, iiwa14 and Gen3 lite, each file citing its source and licence).
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable
from dataclasses import replace
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from ..gravity import has_inertials
from ..inertials import transfer_inertials
from ..model import RobotModel
from .inertials_file import with_inertials_file
from .robot_file import EMBEDDED_ROBOTS, RobotFileError, robot_from_dict
from .suggest import close_names
from .text_input import read_text
from .urdf_to_dh import NearlyParallelAxesWarning, load_urdf
from .yaml_safe import MAX_FILE_BYTES, load_yaml

#: Tool link of each embedded URDF (the flange; the Gen3 lite's gripper tool frame).
URDF_TIPS: dict[str, str] = {"iiwa14.urdf": "iiwa_link_ee_kuka", "gen3lite.urdf": "tool_frame"}
#: Embedded arms whose published inertials a matching chain receives: name -> (file, source in one line).
INERTIAL_DONORS: dict[str, tuple[str, str]] = {
    "franka_panda": ("panda.yaml", "Gaz et al. 2019 via franka_ros, Apache-2.0"),
    "franka_fr3": ("fr3.yaml", "franka_description, Apache-2.0"),
    "kuka_iiwa14": ("iiwa14.urdf", "Drake's iiwa14 model, BSD-3-Clause"),
    "kinova_gen3_lite": ("gen3lite.urdf", "Kinova's description via MUKCa, MIT / BSD-3-Clause"),
}


def _embedded(file: str, source: str) -> RobotModel:
    """An embedded robot description by file name."""
    resource = resources.files("spherecal.correction").joinpath("data", file)
    if file.endswith(".urdf"):
        with resources.as_file(resource) as path, warnings.catch_warnings():
            warnings.simplefilter("ignore", NearlyParallelAxesWarning)  # the Gen3 lite's joints 2-3
            return load_urdf(path, tip_link=URDF_TIPS[file])
    data, root = load_yaml(resource.read_text(), source, RobotFileError)
    return robot_from_dict(data, source=source, root=root)


@cache
def _donor(file: str, name: str) -> RobotModel:
    """An embedded arm as an inertials donor, read once per process (only read, never handed out)."""
    return _embedded(file, name)


def embedded_inertials(model: RobotModel) -> tuple[RobotModel, str] | None:
    """``model`` with the published inertials of the embedded arm whose joint axes it shares.

    Among the embedded arms of the same joint count whose axes coincide with ``model``'s (within
    :data:`correction.inertials.AXIS_DISTANCE_TOL` and ``AXIS_ANGLE_TOL``), the one with the closest joint
    limits (the Panda and the FR3 share their geometry, not their limits).

    Returns:
        ``(model with inertials, one line naming the arm and the source)``, or None when no arm matches.
    """
    best = None
    for name, (file, source) in INERTIAL_DONORS.items():
        donor = _donor(file, name)
        if donor.n_joints != model.n_joints:
            continue
        moved = transfer_inertials(model, donor)
        if moved is None:
            continue
        gap = float(np.abs(donor.lower - model.lower).sum() + np.abs(donor.upper - model.upper).sum())
        if best is None or gap < best[0]:
            best = (gap, name, source, moved)
    if best is None:
        return None
    _, name, source, moved = best
    label = f"{name} ({source}; data/{INERTIAL_DONORS[name][0]})"
    moved = replace(moved, extras={**moved.extras, "inertials_source": f"embedded {label}"})
    return moved, (f"{model.name}: no link inertials in the description; its joint axes match the embedded {name}, "
                   f"whose published inertials it takes ({source}); --inertials FILE to give your own")


def _load(path_or_name: str | os.PathLike, tip_link: str | None, base_link: str | None) -> RobotModel:
    key = str(path_or_name)
    if key.lower().endswith(".urdf"):
        return load_urdf(path_or_name, tip_link=tip_link, base_link=base_link)
    if Path(key).is_dir():  # before the link options: a folder is no robot description of any kind
        raise RobotFileError(f"{key}: cannot read: Is a directory (expected a robot file or a .urdf)")
    if key in EMBEDDED_ROBOTS and not Path(key).exists():
        _refuse_links(key, tip_link, base_link)
        return _embedded(EMBEDDED_ROBOTS[key], key)
    path = Path(path_or_name)
    unknown = unknown_name(key)  # a name, not a path: say which exist
    if unknown is not None:
        raise RobotFileError(f"{key}: cannot read: {unknown}")
    text = read_text(path, RobotFileError, limit=MAX_FILE_BYTES)
    if _xml_root(text) == "robot":  # a URDF whatever its ending: 'export --format urdf --out arm.xml' (ROS's)
        return load_urdf(path_or_name, tip_link=tip_link, base_link=base_link)
    _refuse_links(key, tip_link, base_link)
    _refuse_xml(text, key)
    data, root = load_yaml(text, str(path), RobotFileError)  # bounded: size, depth, aliases; no duplicate keys
    return robot_from_dict(data, source=str(path), root=root)


def unknown_name(path_or_name: str | os.PathLike) -> str | None:
    """Why ``path_or_name`` names no robot, when it is a bare name (no folder, no ending) that is neither a file nor
    an embedded robot: ``"no such file, nor an embedded robot (did you mean 'iiwa14'? embedded: panda, ...)"``;
    None for anything else (an embedded name, an existing file, a path, which :func:`load_robot` reads or refuses
    itself). The command line names its option with it (``field '--robot': ...``)."""
    key = str(path_or_name)
    path = Path(key)
    if key in EMBEDDED_ROBOTS or os.path.lexists(path) or path.suffix or len(path.parts) != 1:
        return None
    near = close_names(key.lower(), EMBEDDED_ROBOTS, cutoff=0.6, n=2)
    said = f"did you mean {' or '.join(map(repr, near))}? embedded: " if near else ""
    return f"no such file, nor an embedded robot ({said}{', '.join(EMBEDDED_ROBOTS)})"


def is_urdf(path_or_name: str | os.PathLike) -> bool:
    """Whether ``path_or_name`` is read as a URDF (its link options apply): named ``.urdf``, or a file whose XML root
    is ``<robot>`` whatever its ending (an embedded name, a robot file or an unreadable path: False)."""
    key = str(path_or_name)
    if key.lower().endswith(".urdf"):
        return True
    try:
        with open(key, "rb") as handle:
            head = handle.read(100_000).decode("utf-8", "replace")
    except OSError:
        return False
    return _xml_root(head) == "robot"


def _refuse_links(source: str, tip_link: str | None, base_link: str | None) -> None:
    """Refuse a URDF's link options for a description that is no URDF (a robot file, an embedded name)."""
    for option, value in (("--tip-link", tip_link), ("--base-link", base_link)):
        if value is not None:
            raise RobotFileError(f"{source}: field '{option}': {value!r} is only for a URDF robot description "
                                 "(<robot>)")


#: The first element of an XML document (after the declaration, comments and a DOCTYPE).
_XML_ROOT = re.compile(r"\A\ufeff?\s*(?:<\?.*?\?>\s*|<!--.*?-->\s*|<!DOCTYPE[^>]*>\s*)*<([A-Za-z_][\w:.-]*)", re.S)


def _xml_root(text: str) -> str | None:
    """The name of the root element of an XML document (``robot``: a URDF), None for text that is not XML."""
    match = _XML_ROOT.match(text[:100_000])
    return None if match is None else match.group(1)


def _refuse_xml(text: str, source: str) -> None:
    """Refuse an XML document other than a URDF in a file read as a robot file (YAML): an exported MJCF, any other
    XML (was: 'expected a mapping at the top level, got str'). A URDF (``<robot>``) is read as one whatever its
    name (:func:`_load`).

    Raises:
        RobotFileError: one line naming the file and what it holds.
    """
    root = _xml_root(text)
    if root is None:
        return
    if root == "mujoco":
        why = "an MJCF model (<mujoco>): give the robot file (YAML) it was exported from, or the arm's URDF (.urdf)"
    else:
        why = f"an XML document (<{root}>), not a robot file (YAML) or a URDF (.urdf)"
    raise RobotFileError(f"{source}: row 1: {why}")


@cache
def reference_robot(name: str) -> RobotModel:
    """The embedded robot ``name`` (``"panda"``, ...: :func:`load_robot`'s names), read once per process: a reference
    that code compares with or measures (a chain matched against the Panda's, the arm default fixtures were chosen
    on). Shared by every caller: never change it, and hand out :func:`load_robot`'s own copy instead."""
    return load_robot(name)


def load_robot(
    path_or_name: str | os.PathLike, tip_link: str | None = None, base_link: str | None = None,
    inertials: str | os.PathLike | None = None, report: Callable[[str], None] | None = None,
) -> RobotModel:
    """Load a robot file, a URDF (``.urdf``), or an embedded robot by name (``"panda"``, ``"fr3"``).

    Args:
        path_or_name: YAML robot file, URDF file or embedded name.
        tip_link, base_link: URDF only: the chain to convert (see :func:`.urdf_to_dh.load_urdf`).
        inertials: an inertials file (:mod:`.inertials_file`) whose masses replace the description's.
        report: called with one line when the inertials come from a matching embedded arm
            (:func:`embedded_inertials`); the commands print it.

    Raises:
        RobotFileError: unreadable file, invalid YAML or URDF, an invalid field (one line).
        InertialsError: an invalid inertials file (one line naming the file and the field).
    """
    model = _load(path_or_name, tip_link, base_link)
    if inertials is not None:
        return with_inertials_file(model, inertials)
    if has_inertials(model):
        return model
    matched = embedded_inertials(model)
    if matched is None:
        return model
    if report is not None:
        report(matched[1])
    return matched[0]
