"""Reading untrusted text: a whole file as UTF-8, one number of a text field; errors in one line."""

from __future__ import annotations

import math
import os
from pathlib import Path


def read_text(path: str | os.PathLike, error: type[Exception]) -> str:
    """The UTF-8 text of ``path``.

    Raises:
        error: ``"<path>: cannot read: <why>"`` (missing, unreadable, not UTF-8 with the byte offset).
    """
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except OSError as why:
        raise error(f"{path}: cannot read: {why.strerror or why}") from None
    except UnicodeDecodeError as why:
        raise error(f"{path}: cannot read: not UTF-8 text (byte {why.start})") from None


def finite_number(text: str, where: str, error: type[Exception]) -> float:
    """``text`` as a finite float.

    Raises:
        error: ``"<where>: expected a number, got '...'"`` or ``"<where>: must be finite, got 'nan'"``.
    """
    try:
        value = float(text)
    except ValueError:
        raise error(f"{where}: expected a number, got {text.strip()!r}") from None
    if not math.isfinite(value):
        raise error(f"{where}: must be finite, got {text.strip()!r}")
    return value
