"""The inertials file (``--inertials FILE``): link masses and centres of mass of an arm, for gravity torques, and
optionally their inertia tensors, for a dynamics stack (the URDF and MJCF exports write them).

Format (YAML, SI units)::

    # one entry per joint i, base to flange: the link that joint i moves, with everything rigidly on it
    inertials:
      - {mass: 4.970684, com: [0.003875, 0.002081, -0.04762]}   # [kg], [m] in DH frame i
      - {mass: 0.646926, com: [-0.003141, -0.02872, 0.003495],  # optional tensor about the centre of mass,
         inertia: [0.007962, -0.003925, 0.010254, 0.02811, 0.000704, 0.025995]}  # [kg m^2], axes of frame i,
      - ...                                                     # URDF order ixx ixy ixz iyy iyz izz
    payload: {mass: 0.76, com: [0.0, 0.0, 0.14]}                # optional: what the flange carries,
                                                                # [kg], [m] in the last DH frame

DH frame ``i`` is the frame :func:`correction.link_frames` gives for link ``i`` of the robot it is used with
(for a URDF, the frames ``spherecal`` derives from it: check them with ``link_frames``, or take the masses
from the URDF's own ``<inertial>`` elements, which are converted for you). No other key is allowed.
"""

from __future__ import annotations

import os
from dataclasses import replace

import yaml

from ..gravity import InertialsError, inertials_of
from ..model import RobotModel
from .suggest import close_names
from .text_input import read_text
from .yaml_safe import MAX_FILE_BYTES, load_yaml

KEYS = ("inertials", "payload")


def inertial_rows(root) -> dict[str, int]:
    """File line of every top-level key (``inertials``, ``payload``, and any other, for its refusal) and of each
    ``inertials[i]`` in the document's node tree."""
    rows: dict[str, int] = {}
    for key, value in getattr(root, "value", []) if isinstance(root, yaml.MappingNode) else []:
        if isinstance(getattr(key, "value", None), str):
            rows[key.value] = key.start_mark.line + 1
            if key.value == "inertials" and isinstance(value, yaml.SequenceNode):
                rows.update({f"inertials[{i}]": item.start_mark.line + 1 for i, item in enumerate(value.value)})
    return rows


def read_inertials(path: str | os.PathLike) -> dict:
    """The ``inertials`` (and ``payload``) blocks of an inertials file, unchecked against any robot.

    Raises:
        InertialsError: unreadable file, invalid YAML, a missing ``inertials`` list or an unknown key.
    """
    return _read(path)[0]


def _read(path: str | os.PathLike) -> tuple[dict, dict[str, int]]:
    """:func:`read_inertials` and the file line of each block and entry."""
    data, root = load_yaml(read_text(path, InertialsError, limit=MAX_FILE_BYTES), str(path), InertialsError)
    if not isinstance(data, dict):
        got = "an empty file" if data is None else type(data).__name__
        raise InertialsError(f"{path}: row 1, field 'inertials': expected a mapping with an 'inertials' list, got "
                             f"{got} (see correction.files.inertials_file)")
    rows = inertial_rows(root)
    unknown = [key for key in data if key not in KEYS]
    if unknown:  # a robot file given for an inertials file names its 'name' here; a misspelt block its spelling
        key = unknown[0]
        where = f"row {rows[key]}, " if key in rows else ""
        also = "; a robot file (name:, dh:, ...) is not an inertials file" if "dh" in data or "name" in data else ""
        near = close_names(key, [k for k in KEYS if k not in data], cutoff=0.8)
        hint = f"did you mean {near[0]!r}? " if near and not also else ""
        raise InertialsError(f"{path}: {where}field {key!r}: unknown key ({hint}an inertials file holds "
                             f"{', '.join(KEYS)}{also})")
    if "inertials" not in data:
        raise InertialsError(f"{path}: row 1, field 'inertials': missing; expected a mapping with an 'inertials' "
                             f"list (see correction.files.inertials_file)")
    return {key: data[key] for key in KEYS if key in data}, rows


def with_inertials_file(model: RobotModel, path: str | os.PathLike) -> RobotModel:
    """``model`` with the masses of an inertials file (replacing any it had), checked against its joints.

    Raises:
        InertialsError: one line naming the file and the field (``inertials[2].com``, wrong count, ...).
    """
    blocks, rows = _read(path)
    extras = {k: v for k, v in model.extras.items() if k not in KEYS}
    out = replace(model, extras={**extras, **blocks, "inertials_source": str(path)})
    inertials_of(out, source=str(path), rows=rows)  # every entry valid, one per joint
    return out
