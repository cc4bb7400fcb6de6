"""What made a result file: package versions, seed, inputs (recorded in every file we write)."""

from __future__ import annotations

import sys
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from spherecal.correction.files.provenance import PACKAGES, file_digest, versions

__all__ = ["PACKAGES", "comment_block", "file_digest", "provenance", "versions"]

def provenance(
    seed: int | None,
    inputs: dict[str, Any],
    command: list[str] | None = None,
    workers: dict[str, dict[str, str]] | None = None,
) -> dict[str, Any]:
    """The block written into every result: command line, time, versions, seed and inputs.

    Args:
        seed: the seed of the run (None when nothing random was drawn).
        inputs: the options and input files (paths are recorded with their SHA-256).
        command: the command line (``sys.argv`` when None).
        workers: worker -> its package versions, when other processes did the work (a pool, a Dask
            cluster: :class:`validation.parallel.Outcome`); recorded under ``"workers"``.
    """
    recorded = {}
    for key, value in inputs.items():
        if isinstance(value, Path) and value.is_file():
            recorded[key] = {"path": str(value), "sha256": file_digest(value)}
        elif isinstance(value, Path):
            recorded[key] = str(value)
        else:
            recorded[key] = value
    info = {
        "command": " ".join(sys.argv if command is None else command),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "versions": versions(),
        "seed": seed,
        "inputs": recorded,
    }
    if workers:
        info["workers"] = {name: dict(packages) for name, packages in sorted(workers.items())}
    return info


def comment_block(info: dict[str, Any]) -> str:
    """The provenance as a few lines for ``#`` comment headers of CSV and text files."""
    lines = [f"command: {info['command']}", f"created: {info['created']}", f"seed: {info['seed']}"]
    lines.append("versions: " + ", ".join(f"{k} {v}" for k, v in info["versions"].items()))
    lines.append("inputs: " + ", ".join(f"{k}={v}" for k, v in info["inputs"].items()))
    if info.get("workers"):
        lines.append("workers: " + _workers(info["workers"], info["versions"]))
    return "\n".join(lines)


def _workers(workers: dict[str, dict[str, str]], own: dict[str, str]) -> str:
    """``host pid 1, host pid 2: the versions above; other pid 3: numpy 2.0.0, ...`` (grouped by versions)."""
    groups: dict[tuple, list[str]] = {}
    for name, packages in workers.items():
        groups.setdefault(tuple(sorted(packages.items())), []).append(name)
    parts = []
    for packages, names in groups.items():
        listed = "the versions above" if dict(packages) == own else ", ".join(f"{k} {v}" for k, v in packages)
        parts.append(f"{', '.join(names)}: {listed}")
    return "; ".join(parts)
