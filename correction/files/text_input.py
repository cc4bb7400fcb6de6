"""Reading untrusted text: a whole file as UTF-8, one number of a text field; errors in one line."""

from __future__ import annotations

import math
import os
from pathlib import Path

#: Largest text file read whole [bytes] (robot files, URDFs, fixtures: kilobytes to a few megabytes). A
#: device such as ``/dev/zero`` or ``/dev/urandom`` never ends: it is refused at this size, not read forever.
MAX_TEXT_BYTES = 64_000_000


def read_text(path: str | os.PathLike, error: type[Exception], encoding: str = "utf-8",
              limit: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of ``path``, at most ``limit`` bytes.

    Args:
        encoding: ``"utf-8"``, or ``"utf-8-sig"`` to drop a byte-order mark.
        limit: the largest file accepted [bytes].

    Raises:
        error: ``"<path>: cannot read: <why>"`` (missing, unreadable, larger than ``limit``, not UTF-8
            with the byte offset).
    """
    path = Path(path)
    try:
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except OSError as why:
        raise error(f"{path}: cannot read: {why.strerror or why}") from None
    if len(data) > limit:
        raise error(f"{path}: cannot read: larger than {limit} bytes (a device or a file of another kind?)")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as why:
        raise error(f"{path}: cannot read: not UTF-8 text (byte {why.start})") from None


def plain_float(text: str) -> float:
    """``float(text)`` for the numbers a file of ours holds: ASCII digits, sign, point, exponent, nan/inf.

    Python's ``float`` also takes other scripts' digits (``'\u0661'``, Arabic-Indic one, is 1.0; full-width
    ``'\uff15'`` is 5.0) and underscores (``'1_0'`` is 10.0): in a CSV cell these are a corrupted or
    foreign-locale value, not a number.

    Raises:
        ValueError: not such a number.
    """
    if not text.isascii() or "_" in text:
        raise ValueError(f"not a plain number: {text!r}")
    return float(text)


def finite_number(text: str, where: str, error: type[Exception]) -> float:
    """``text`` as a finite float.

    Raises:
        error: ``"<where>: expected a number, got '...'"`` or ``"<where>: must be finite, got 'nan'"``.
    """
    try:
        value = plain_float(text)
    except ValueError:
        raise error(f"{where}: expected a number, got {text.strip()!r}") from None
    if not math.isfinite(value):
        raise error(f"{where}: must be finite, got {text.strip()!r}")
    return value
