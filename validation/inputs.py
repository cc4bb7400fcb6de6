"""Checks across input files before anything is computed or written."""

from __future__ import annotations

import os
from pathlib import Path

from spherecal.correction import RobotModel, SpherecalError


class ValidationInputError(SpherecalError):
    """Input files that do not fit together (one line naming the file and the field)."""


def check_models(models: dict[str, RobotModel], files: dict[str, str]) -> None:
    """Every model has the joint count and the DH convention of the nominal one.

    Args:
        models: role (``"nominal"``, ``"calibrated"``, ``"truth"``) -> model; ``"nominal"`` first.
        files: role -> the file it came from (for the message).

    Raises:
        ValidationInputError: on the first mismatch.
    """
    reference = models["nominal"]
    for role, model in models.items():
        mismatch = reference.mismatch(model)
        if mismatch is not None:
            field, what = mismatch
            raise ValidationInputError(f"{files[role]}: field {field}: {what} as in the nominal {files['nominal']}")


def check_out_folder(path: str | os.PathLike, option: str = "--out") -> None:
    """Refuse an output folder that is an existing file (or under one), before a long run rather than after it.

    Raises:
        ValidationInputError: ``path`` or a parent of it exists and is not a directory.
    """
    if Path(path).exists() and not Path(path).is_dir():
        raise ValidationInputError(f"{path}: field '{option}': exists and is not a folder")
    _check_parents(path, option)


def check_out_file(path: str | os.PathLike, option: str) -> None:
    """Refuse an output file that is an existing folder or lies under a file, before anything is written.

    Raises:
        ValidationInputError: ``path`` is a directory, or a parent of it exists and is not one.
    """
    if Path(path).is_dir():
        raise ValidationInputError(f"{path}: field '{option}': is a folder, expected a file name")
    _check_parents(path, option)


def _check_parents(path: str | os.PathLike, option: str) -> None:
    for parent in Path(path).absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise ValidationInputError(f"{path}: field '{option}': {parent} is not a folder")
            return
