"""What made an output: one provenance block, written by every command, the demo, the campaign and
the bench scripts.

The block (:func:`provenance`) is the same everywhere::

    command: spherecal calibrate --robot panda --samples out/samples.csv ...
    created: 2026-11-25T01:58:49+00:00     # UTC
    versions: {python: 3.12.3, spherecal: 0.1.0, numpy: 2.1.3, ...}
    seed: 0                                 # null when nothing random was drawn
    inputs:                                 # files and folders with their SHA-256, options as given
      samples: {path: out/samples.csv, sha256: 9f2c...}
      robot: {path: panda, sha256: embedded}
      loss: linear

YAML and JSON outputs hold it under a ``provenance`` key; CSV, Markdown, URDF, MJCF and the Rerun
recordings hold :func:`comment_block` of it in their comments.
"""

from __future__ import annotations

import hashlib
import os
import platform
import re
import shlex
import socket
import stat
import sys
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

#: Packages whose versions a result records.
PACKAGES: tuple[str, ...] = (
    "spherecal", "numpy", "scipy", "mujoco", "qpsolvers", "osqp", "rerun-sdk", "pyswarms", "rosbags",
)


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
    digest = hashlib.sha256()
    with open(path, "rb") as handle:  # in blocks: a recording of gigabytes is not held in memory
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def folder_digest(path: str | os.PathLike) -> str:
    r"""SHA-256 (hex) of a folder: of the lines ``<file's SHA-256>  <relative path>\n`` (``sha256sum``'s), one per
    regular file at any depth, in relative-path order (``/``-separated, sorted by code point).

    Links are followed as the importers follow them (a folder reached twice is read once: no loop); pipes,
    sockets and devices are skipped (reading them blocks); a file that cannot be read counts with the digest
    ``unreadable``. Every file is read in blocks: a bag folder of gigabytes is not held in memory. For
    ordinary names the same as ``find -L . -type f -printf '%P\n' | LC_ALL=C sort | xargs -d '\n' sha256sum |
    sha256sum`` run inside the folder.
    """
    lines = hashlib.sha256()
    for name, file in _regular_files(Path(path)):
        try:
            digest = file_digest(file)
        except OSError:
            digest = "unreadable"
        lines.update(f"{digest}  {name}\n".encode("utf-8", "surrogateescape"))
    return lines.hexdigest()


def _regular_files(root: Path) -> list[tuple[str, Path]]:
    """(relative path, path) of the regular files below ``root``, links followed, each folder once, sorted."""
    found: list[tuple[str, Path]] = []
    seen: set[str] = set()
    for folder, children, files in os.walk(root, followlinks=True):
        real = os.path.realpath(folder)
        if real in seen:  # a link back up, or a second link to one folder
            children[:] = []
            continue
        seen.add(real)
        children.sort()
        for name in files:
            file = Path(folder, name)
            try:
                regular = stat.S_ISREG(file.stat().st_mode)
            except OSError:  # a dangling link: nothing to read
                continue
            if regular:
                found.append((file.relative_to(root).as_posix(), file))
    return sorted(found)


def input_record(path: str | os.PathLike) -> dict[str, str]:
    """``{"path", "sha256"}`` of an input: the SHA-256 of a file (:func:`file_digest`) or of a folder (a
    recording folder: :func:`folder_digest`); a name that is neither (an embedded robot such as ``"panda"``)
    has ``"sha256": "embedded"``."""
    if Path(path).is_file():
        return {"path": str(path), "sha256": file_digest(path)}
    return {"path": str(path), "sha256": folder_digest(path) if Path(path).is_dir() else "embedded"}


def provenance(seed: int | None, inputs: dict[str, Any], command: list[str] | None = None,
               workers: dict[str, dict[str, str]] | None = None) -> dict[str, Any]:
    """The provenance block of an output: command line, time, versions, seed and inputs.

    Args:
        seed: the seed of the run (None when nothing random was drawn).
        inputs: name -> input. A path (:class:`os.PathLike`) is recorded by :func:`input_record`
            (path and SHA-256); pass file names as :class:`~pathlib.Path`. Anything else (options,
            numbers, strings) is recorded as given.
        command: the command line (``sys.argv``, its program path shortened to its name, when None).
        workers: worker -> its package versions, when other processes did the work (a pool, a Dask
            cluster: ``validation.parallel``); recorded under ``"workers"``.

    Returns:
        ``{"command", "created", "versions", "seed", "inputs"}`` and ``"workers"`` when given (YAML- and
        JSON-ready).
    """
    if command is None:
        command = [Path(sys.argv[0]).name, *sys.argv[1:]] if sys.argv and sys.argv[0] else []
    recorded = {
        key: _readable(input_record(value) if isinstance(value, os.PathLike) else value)
        for key, value in inputs.items()
    }
    info = {
        "command": shell_line(command),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "versions": versions(),
        "seed": seed,
        "inputs": recorded,
    }
    if workers:
        info["workers"] = {name: dict(packages) for name, packages in sorted(workers.items())}
    return info


def printable(text: str) -> str:
    """``text`` as UTF-8 can hold it: a byte of a file name that is not UTF-8 (``\\udcff`` in Python's
    ``surrogateescape``) as ``\\xff`` (writing it raised UnicodeEncodeError, a traceback instead of the file)."""
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def _readable(value: Any) -> Any:
    """An input record or option with every string :func:`printable` (in lists and dicts too)."""
    if isinstance(value, str):
        return printable(value)
    if isinstance(value, dict):
        return {_readable(k): _readable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_readable(v) for v in value]
    return value


#: What a plain quoted word cannot show on one line: control characters, and a file name's byte that is not UTF-8.
_UNQUOTABLE = re.compile(r"[\x00-\x1f\x7f\udc80-\udcff]")
_ESCAPES = {"\n": "\\n", "\t": "\\t", "\r": "\\r"}


def _shell_word(word: str) -> str:
    """One word of a command line as a POSIX shell reads it back: quoted when it holds a space or ``;`` (``shlex``),
    and as ``$'...'`` with escapes when it holds a newline, another control character or a byte that is not UTF-8
    (``\\xff``: the line stays one line of UTF-8)."""
    if not _UNQUOTABLE.search(word):
        return shlex.quote(word)

    def escape(match: re.Match) -> str:
        char = match.group()
        return _ESCAPES.get(char, f"\\x{(ord(char) - 0xDC00 if ord(char) >= 0xDC80 else ord(char)):02x}")

    return "$'" + _UNQUOTABLE.sub(escape, word.replace("\\", "\\\\").replace("'", "\\'")) + "'"


def shell_line(command: list) -> str:
    """The command line ``command`` (words) as one line a POSIX shell runs again as it was typed: ``--grid
    '0.4,0.5,2;-0.2,0.2,2;0.4,0.5,2'`` and ``--out 'my run'`` quoted (joined with spaces, the ``;`` ended the
    command and the space split the folder in two), a newline in a name escaped."""
    return " ".join(_shell_word(str(word)) for word in command)


def comment_block(info: dict[str, Any]) -> str:
    """A :func:`provenance` block as a few lines for the comments of CSV, Markdown, URDF and text files."""
    lines = [f"command: {info['command']}", f"created: {info['created']}", f"seed: {info['seed']}"]
    lines.append("versions: " + ", ".join(f"{k} {v}" for k, v in info["versions"].items()))
    inputs = []
    for key, value in info["inputs"].items():
        if isinstance(value, dict) and set(value) == {"path", "sha256"}:
            value = f"{value['path']} (sha256 {value['sha256']})"
        inputs.append(f"{key}={value}")
    lines.append("inputs: " + ", ".join(inputs))
    if info.get("workers"):
        lines.append("workers: " + _workers(info["workers"], info["versions"]))
    return "\n".join(lines)


def _workers(workers: dict[str, dict[str, str]], own: dict[str, str]) -> str:
    """``host pid 1, host pid 2: the versions above; other pid 3: numpy 2.0.0, ...`` (grouped by versions; the
    command's own process is ``host main process``)."""
    groups: dict[tuple, list[str]] = {}
    for name, packages in workers.items():
        groups.setdefault(tuple(sorted(packages.items())), []).append(name)
    parts = []
    for packages, names in groups.items():
        listed = "the versions above" if dict(packages) == own else ", ".join(f"{k} {v}" for k, v in packages)
        parts.append(f"{', '.join(names)}: {listed}")
    return "; ".join(parts)


def this_process() -> tuple[str, dict[str, str]]:
    """This process's name and package versions: one entry of a block's ``workers``. A worker process (of a pool, of a
    Dask cluster) is ``"host pid N"``; a process no other started, as the command itself running its tasks in this
    process (``--workers 1``), is ``"host main process"``: its pid, new at every run, made two runs of one command
    and seed differ beyond their creation time."""
    import multiprocessing  # not at --help (start-up)

    if multiprocessing.parent_process() is None:
        return f"{socket.gethostname()} main process", versions()
    return f"{socket.gethostname()} pid {os.getpid()}", versions()


def matches_record(path: str | os.PathLike, record: dict[str, Any]) -> bool:
    """True when ``path`` is a file whose SHA-256 is the one an input record (:func:`input_record`) holds:
    the same file a result was made from."""
    return Path(path).is_file() and file_digest(path) == record.get("sha256")


def matched_record(path: str | os.PathLike, record: dict[str, Any]) -> dict[str, str]:
    """The :func:`input_record` of ``path``, a file :func:`matches_record` found to be the one ``record`` names: its
    SHA-256 is the record's, so the file is not read a second time (an export's samples were hashed 7 times)."""
    return {"path": str(path), "sha256": str(record["sha256"])}
