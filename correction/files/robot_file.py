"""Reading and writing robot files (YAML).

Schema (other top-level keys are kept in :attr:`RobotModel.extras` and written back)::

    name: franka_panda
    convention: modified          # or: standard
    joints:                       # base to flange, metres and radians
      - {a: 0.0, alpha: 0.0, d: 0.333, theta: 0.0, lower: -2.8973, upper: 2.8973}
                                  # optional per joint: beta (Hayati angle, radians; see RobotModel)
    tool: [0.0, 0.0, 0.107]       # tool point in the last joint's frame, metres
    base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # optional
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import SpherecalError
from ..gravity import InertialsError, inertials_of
from ..model import CONVENTIONS, JOINT_FIELDS, RobotModel
from .atomic import atomic_write_text
from .inertials_file import inertial_rows
from .suggest import close_names
from .yaml_safe import dump_yaml, node_line

JOINT_KEYS: tuple[str, ...] = JOINT_FIELDS + ("lower", "upper")
#: Optional per-joint key: a joint with ``beta`` carries a Hayati angle (see RobotModel.hayati).
OPTIONAL_JOINT_KEYS: tuple[str, ...] = ("beta",)
_KNOWN_KEYS = ("name", "convention", "joints", "tool", "base")
#: Every top-level key spherecal reads or writes (others are kept unread, unless one is a misspelling of these).
READ_KEYS = _KNOWN_KEYS + ("inertials", "payload", "inertials_source", "compliance", "scale", "calibration",
                           "joint_names", "tool_swap", "urdf", "source")
#: Most joints of a robot file (the URDF reader's chain bound): a serial arm has 6-7.
MAX_JOINTS = 64
#: Robots shipped inside the package, loadable by name.
EMBEDDED_ROBOTS: dict[str, str] = {
    "panda": "panda.yaml", "franka_panda": "panda.yaml", "fr3": "fr3.yaml", "franka_fr3": "fr3.yaml",
    "iiwa14": "iiwa14.urdf", "kuka_iiwa14": "iiwa14.urdf",
    "gen3lite": "gen3lite.urdf", "kinova_gen3_lite": "gen3lite.urdf",
}


#: Largest length (a, d, tool, base position) a robot file may give [m]: an arm is not 10 m long.
MAX_LENGTH = 10.0
#: Largest angle (alpha, theta, beta, base rpy, joint limits) [rad]: two turns either way.
MAX_ANGLE = 4 * math.pi
_LENGTH, _ANGLE = (MAX_LENGTH, "m"), (MAX_ANGLE, "rad")
_BOUNDS = {"a": _LENGTH, "d": _LENGTH, "alpha": _ANGLE, "theta": _ANGLE, "beta": _ANGLE, "lower": _ANGLE,
           "upper": _ANGLE}


class RobotFileError(SpherecalError):
    """A robot file that cannot be read; the message names the file and the field."""


def _located(source: str, root: Any) -> Callable[[str], str]:
    """``at(field)``: the message prefix ``"FILE: row N, field 'F'"`` of a field such as ``joints[1].alpha``, its
    row the line of that node in ``root`` (the document's node tree; without one, no row)."""

    def at(field: str) -> str:
        if root is None:
            return f"{source}: field '{field}'"
        path = [int(index) if index else key for key, index in re.findall(r"([^.\[\]]+)|\[(\d+)\]", field)]
        return f"{source}: row {node_line(root, *path, key_line=True)}, field '{field}'"

    return at


def _number(value: Any, where: str, bound: tuple[float, str] | None = None) -> float:
    """A finite number; with ``bound = (limit, unit)`` also ``|value| <= limit`` (a physical magnitude).
    ``where`` is the message prefix (``"FILE: row N, field 'F'"``)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RobotFileError(f"{where}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise RobotFileError(f"{where}: must be finite, got {value!r}")
    if bound is not None and abs(value) > bound[0]:
        raise RobotFileError(f"{where}: {value!r} {bound[1]} is not physical (at most {bound[0]:g} {bound[1]} "
                             f"in magnitude; the file is in metres and radians)")
    return float(value)


def _vector3(value: Any, at: Callable[[str], str], field: str, bound: tuple[float, str] | None = None) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise RobotFileError(f"{at(field)}: expected a list of 3 numbers, got {value!r}")
    return [_number(v, at(f"{field}[{k}]"), bound) for k, v in enumerate(value)]


def _no_unknown_keys(mapping: dict, known: tuple[str, ...], at: Callable[[str], str], field: str) -> None:
    """A misspelt key would otherwise be dropped and its value read as zero."""
    unknown = [key for key in mapping if key not in known]
    if unknown:
        raise RobotFileError(f"{at(f'{field}.{unknown[0]}')}: unknown key {unknown[0]!r} (expected {', '.join(known)})")


def robot_from_dict(data: Any, source: str = "<robot>", root: Any = None) -> RobotModel:
    """Validate a parsed robot file and build the model.

    Args:
        data: the parsed YAML document.
        source: file name used in error messages.
        root: the document's node tree (:func:`load_yaml`'s second value), for the row of each message; None
            (a mapping built in code): messages name the field only.

    Raises:
        RobotFileError: one line naming ``source``, the row and the offending field.
    """
    at = _located(source, root)
    if not isinstance(data, dict):
        raise RobotFileError(f"{at('')}: expected a mapping at the top level, got {type(data).__name__}")
    if not any(key in data for key in _KNOWN_KEYS):  # another tool's file (a ROS parameter file, a DH table)
        found = ", ".join(repr(k) for k in list(data)[:4])
        raise RobotFileError(f"{at(str(next(iter(data), '')))}: not a spherecal robot file (keys {found}; "
                             f"expected {', '.join(_KNOWN_KEYS)}: see correction.files.robot_file)")
    for key in data:  # a misspelt block would be kept unread: 'inertial' left the embedded arm's masses in use
        near = close_names(key, READ_KEYS, cutoff=0.8)
        if key not in READ_KEYS and near and near[0] not in data:
            raise RobotFileError(f"{at(str(key))}: unknown key (did you mean {near[0]!r}? as written, "
                                 "it would be ignored)")
    for key in ("name", "convention", "joints", "tool"):
        if key not in data:
            raise RobotFileError(f"{at(key)}: missing key '{key}'")
    name = data["name"]
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{at('name')}: expected a non-empty string, got {name!r}")
    convention = data["convention"]
    if convention not in CONVENTIONS:
        raise RobotFileError(
            f"{at('convention')}: unknown convention {convention!r} (expected 'standard' or 'modified')"
        )
    joints = data["joints"]
    if not isinstance(joints, list) or not joints:
        raise RobotFileError(f"{at('joints')}: expected a non-empty list of joint mappings")
    if len(joints) > MAX_JOINTS:
        raise RobotFileError(f"{at('joints')}: {len(joints)} joints, at most {MAX_JOINTS} (not a serial arm)")
    columns: dict[str, list[float]] = {key: [] for key in JOINT_KEYS + OPTIONAL_JOINT_KEYS}
    hayati: list[int] = []
    for i, joint in enumerate(joints):
        field = f"joints[{i}]"
        if not isinstance(joint, dict):
            raise RobotFileError(f"{at(field)}: expected a mapping, got {joint!r}")
        _no_unknown_keys(joint, JOINT_KEYS + OPTIONAL_JOINT_KEYS, at, field)
        for key in JOINT_KEYS:
            if key not in joint:
                raise RobotFileError(f"{at(f'{field}.{key}')}: missing key '{key}'")
            columns[key].append(_number(joint[key], at(f"{field}.{key}"), _BOUNDS[key]))
        columns["beta"].append(_number(joint.get("beta", 0.0), at(f"{field}.beta"), _ANGLE))
        if "beta" in joint:
            hayati.append(i)
        if not columns["lower"][-1] < columns["upper"][-1]:
            raise RobotFileError(
                f"{at(f'{field}.lower')}: must be below upper, got lower {columns['lower'][-1]} >= upper "
                f"{columns['upper'][-1]}"
            )
    tool = _vector3(data["tool"], at, "tool", _LENGTH)
    base_xyz, base_rpy = [0.0] * 3, [0.0] * 3
    base = data.get("base")
    if base is not None:
        if not isinstance(base, dict):
            raise RobotFileError(f"{at('base')}: expected a mapping with xyz and rpy, got {base!r}")
        _no_unknown_keys(base, ("xyz", "rpy"), at, "base")
        base_xyz = _vector3(base.get("xyz", [0.0] * 3), at, "base.xyz", _LENGTH)
        base_rpy = _vector3(base.get("rpy", [0.0] * 3), at, "base.rpy", _ANGLE)
    extras = {k: v for k, v in data.items() if k not in _KNOWN_KEYS}
    _check_extras(extras, len(joints), source, root)
    return RobotModel(
        name=name,
        convention=convention,
        a=columns["a"],
        alpha=columns["alpha"],
        d=columns["d"],
        theta=columns["theta"],
        lower=columns["lower"],
        upper=columns["upper"],
        beta=columns["beta"],
        hayati=tuple(hayati),
        tool=tool,
        base_xyz=base_xyz,
        base_rpy=base_rpy,
        extras=extras,
    )


#: Per-joint lists a robot file may carry beside the geometry: key -> unit named in the message.
_JOINT_VECTORS = {"compliance": "[rad/Nm]", "scale": "(dimensionless)"}


def _check_extras(extras: dict, n: int, source: str, root: Any = None) -> None:
    """The optional blocks the library reads (``compliance``, ``scale``, ``joint_names``, ``inertials``,
    ``payload``) have one entry per joint and valid values; others are kept unread.

    Raises:
        RobotFileError: one line naming ``source``, the row (with ``root``, the node tree) and the field.
    """
    at = _located(source, root)
    for key, unit in _JOINT_VECTORS.items():
        if key not in extras:
            continue
        values = extras[key]
        if (not isinstance(values, list) or len(values) != n
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                           for v in values)):
            raise RobotFileError(f"{at(key)}: expected a list of {n} finite numbers {unit}, "
                                 f"got {values!r}")
    if "calibration" in extras and not isinstance(extras["calibration"], dict):
        # validate reads which samples trained the model from this block: without it, they pass as held out
        raise RobotFileError(f"{at('calibration')}: expected the mapping calibrate writes (or no such "
                             f"key), got {type(extras['calibration']).__name__} {str(extras['calibration'])[:40]!r}")
    _refuse_removed_terms(extras, at)
    if "joint_names" in extras:
        names = extras["joint_names"]
        if (not isinstance(names, list) or len(names) != n
                or not all(isinstance(v, str) and v for v in names)):
            raise RobotFileError(f"{at('joint_names')}: expected a list of {n} joint names, got {names!r}")
        twice = next((v for k, v in enumerate(names) if v in names[:k]), None)
        if twice is not None:
            again = names.index(twice, names.index(twice) + 1)
            raise RobotFileError(f"{at(f'joint_names[{again}]')}: {twice!r} is named twice")
    if "inertials" in extras:
        probe = RobotModel(name=source, convention="modified", a=[0.0] * n, alpha=[0.0] * n, d=[0.0] * n,
                           theta=[0.0] * n, lower=[-1.0] * n, upper=[1.0] * n, tool=[0.0] * 3,
                           extras={k: extras[k] for k in ("inertials", "payload") if k in extras})
        try:
            inertials_of(probe, source, inertial_rows(root))
        except InertialsError as error:
            raise RobotFileError(str(error)) from None


#: Per-joint lists -> the prefix of their parameters' names in ``calibration.identified`` (``c2``, ``s4``).
_TERM_PREFIX = {"compliance": "c", "scale": "s"}


def _refuse_removed_terms(extras: dict, at) -> None:
    """Refuse a calibrated file whose ``calibration.identified`` lists compliances or scales while its
    ``compliance`` / ``scale`` list is gone (edited by hand): it loaded as the rigid geometry, the terms the
    calibration fitted with it silently dropped (a review: 0.363 against 0.315 mm held out on an iiwa14).

    Raises:
        RobotFileError: one line naming the missing key and the terms the calibration identified.
    """
    block = extras.get("calibration")
    identified = block.get("identified") if isinstance(block, dict) else None
    if not isinstance(identified, list):
        return
    for key, prefix in _TERM_PREFIX.items():
        terms = [v for v in identified if isinstance(v, str) and re.fullmatch(rf"{prefix}\d+", v)]
        if terms and key not in extras:
            raise RobotFileError(
                f"{at(key)}: missing, while calibration.identified lists {', '.join(terms)}: the geometry was "
                f"calibrated together with them and is not the arm's without them; restore the '{key}' list (or "
                "calibrate with --model dh for a geometry-only file)")


def check_robot(model: RobotModel, source: str) -> None:
    """Apply the robot file's checks (finite, physical lengths and angles, lower < upper) to a model
    built another way (a URDF), so every robot enters with the same ranges.

    Raises:
        RobotFileError: one line naming ``source`` and the field (``joints[i].a``, ``tool[2]``, ...).
    """
    robot_from_dict({k: v for k, v in robot_to_dict(model).items() if k in _KNOWN_KEYS}, source)


def _plain(value: Any) -> Any:
    """numpy scalars and arrays to plain Python, recursively (floats keep every bit)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def robot_to_dict(model: RobotModel) -> dict:
    """The robot-file mapping of a model (plain Python types, exact floats)."""
    joints = []
    for i in range(model.n_joints):
        keys = JOINT_KEYS[:2] + ("beta",) + JOINT_KEYS[2:] if i in model.hayati else JOINT_KEYS
        joints.append({key: float(getattr(model, key)[i]) for key in keys})
    data: dict[str, Any] = {
        "name": model.name,
        "convention": model.convention,
        "joints": joints,
        "tool": [float(v) for v in model.tool],
        "base": {
            "xyz": [float(v) for v in model.base_xyz],
            "rpy": [float(v) for v in model.base_rpy],
        },
    }
    data.update(_plain(model.extras))
    return data


def dump_robot(model: RobotModel, header: str = "") -> str:
    """YAML text of a robot file; ``header`` lines are written as comments on top."""
    comments = "".join(f"# {line}\n" for line in header.splitlines())
    body = dump_yaml(robot_to_dict(model), sort_keys=False, default_flow_style=None, width=1000)
    return comments + "# spherecal robot file: metres and radians\n" + body


def save_robot(model: RobotModel, path: str | os.PathLike, header: str = "") -> Path:
    """Write a robot file atomically (temporary file, rename); floats round-trip exactly."""
    return atomic_write_text(path, dump_robot(model, header))


def forced_calibration(model) -> str | None:
    """One line when ``model`` is a calibration written with ``--force`` although its self-check found the
    data inconsistent (``calibration.self_check.verdict: inconsistent``), naming the first failed check."""
    block = model.extras.get("calibration")
    check = block.get("self_check") if isinstance(block, dict) else None
    if not isinstance(check, dict) or check.get("verdict") != "inconsistent":
        return None
    failed = check.get("failed") or ["(no reason recorded)"]
    return f"the calibration was forced (--force): its self-check found the data INCONSISTENT: {failed[0]}"
