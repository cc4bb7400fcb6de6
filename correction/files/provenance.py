"""What made a result file: package versions and input digests (every result file records them)."""

from __future__ import annotations

import hashlib
import os
import platform
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

#: Packages whose versions a result records.
PACKAGES: tuple[str, ...] = ("spherecal", "numpy", "scipy", "mujoco", "qpsolvers", "osqp", "rerun-sdk")


def versions(packages: tuple[str, ...] = PACKAGES) -> dict[str, str]:
    """Installed versions of Python and of ``packages`` (``"not installed"`` when absent)."""
    out = {"python": platform.python_version()}
    for package in packages:
        try:
            out[package] = version(package)
        except PackageNotFoundError:
            out[package] = "not installed"
    return out


def file_digest(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes (hex)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def input_record(path: str | os.PathLike) -> dict[str, str]:
    """``{"path", "sha256"}`` of an input file; an embedded robot (``"panda"``) is named as such."""
    return {"path": str(path), "sha256": file_digest(path) if Path(path).is_file() else "embedded"}
