"""Atomic file writes: a result file is either complete or absent."""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

from ..errors import SpherecalError


class OutputError(SpherecalError):
    """A result file that cannot be written (a directory in the way, no permission, disk full)."""


def refuse_special_file(path: Path, option: str | None = None) -> None:
    """Refuse an existing output that is not a regular file (``/dev/null``, ``/dev/full``, a pipe,
    a socket): the rename that makes a write atomic would replace the device node itself.

    Raises:
        OutputError: one line naming ``path`` (and ``option`` when given).
    """
    try:
        mode = os.stat(path).st_mode
    except OSError:  # absent (or unreadable: the write reports it)
        return
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        field = f" field '{option}':" if option else ""
        raise OutputError(f"{path}:{field} is a device, pipe or socket, not a regular file (expected a file name to "
                          "write)")


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder and a rename.

    A reader never sees a half-written file, and a failure leaves no partial output.
    """
    path = Path(path)
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, rename).

    Raises:
        OutputError: the file cannot be written (one line naming ``path``); nothing is left behind.
    """
    path = Path(path)
    refuse_special_file(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as error:
        raise OutputError(f"{path}: cannot write: {error.strerror or error}") from None
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a result file is as open as any other
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except OSError as error:
        Path(tmp).unlink(missing_ok=True)
        raise OutputError(f"{path}: cannot write: {error.strerror or error}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
