"""Files an output folder already holds: an earlier run's own outputs may be replaced, anything else not.

``simulate --out DIR`` writes ``samples.csv``, ``fixtures.yaml`` and ``truth.yaml``: run again into the
same folder, it replaces its own earlier outputs (a new seed, more seconds), but a folder that holds a
real recording (``import``'s ``samples.csv`` and ``fixtures.yaml``, a user's own files) must not lose it
to simulated data. A file is the earlier run's own when it carries the run's provenance block:

- a YAML file (``fixtures.yaml``, ``truth.yaml``) holds a top-level ``block`` mapping (``simulation:``)
  with a ``provenance`` mapping;
- any other file (``samples.csv``) starts with ``#`` lines equal to
  :func:`~.provenance.comment_block` of the provenance of one of those YAML files in the same folder
  (the files of one run share one block; an imported ``samples.csv`` has its import's block instead).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import SpherecalError
from .atomic import OutputError
from .provenance import comment_block
from .text_input import read_text
from .yaml_safe import MAX_FILE_BYTES, load_yaml

#: Bytes of a CSV file read for its leading comment lines.
HEAD_BYTES = 16_384


def _provenance(path: Path, block: str) -> dict[str, Any] | None:
    """The ``block.provenance`` mapping of a YAML file, or None (not YAML, no such block, unreadable)."""
    try:
        data, _ = load_yaml(read_text(path, SpherecalError, limit=MAX_FILE_BYTES), str(path))
    except (SpherecalError, OSError, UnicodeDecodeError):
        return None
    own = data.get(block) if isinstance(data, dict) else None
    made = own.get("provenance") if isinstance(own, dict) else None
    return made if isinstance(made, dict) else None


def _leading_comments(path: Path) -> list[str]:
    """The ``#`` lines a text file starts with, ``#`` and one space removed."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(HEAD_BYTES).decode("utf-8", errors="replace")
    except OSError:
        return []
    lines = []
    for line in head.splitlines():
        if not line.startswith("#"):
            break
        lines.append(line[2:] if line.startswith("# ") else line[1:])
    return lines


def leading_comments(path: str | os.PathLike) -> list[str]:
    """The ``#`` lines a text file starts with (its first :data:`HEAD_BYTES`), ``#`` and one space removed."""
    return _leading_comments(Path(path))


def written_by(path: str | os.PathLike, command: str) -> bool:
    """Whether an existing file carries the provenance of an earlier ``command`` run (``spherecal plan``): a JSON
    report whose ``provenance.command`` starts with it, or a text file (CSV, Markdown) whose leading comment holds
    the line ``command: <command> ...`` (``# `` lines, or an opening ``<!--``). The command line is the one
    :func:`~.provenance.provenance` recorded (the program's name, ``spherecal``, then its arguments): a run through
    another entry point does not count as one, and its outputs are kept (the safe way round)."""
    path = Path(path)
    # the program as its name or a path to it (outputs written before the path was shortened: /work/venv/bin/...)
    program, _, sub = command.partition(" ")
    pattern = re.compile(rf"(?:\S*/)?{re.escape(program)} {re.escape(sub)} ")
    if path.suffix == ".json":
        try:
            data = json.loads(read_text(path, SpherecalError, limit=MAX_FILE_BYTES))
        except (SpherecalError, OSError, UnicodeDecodeError, ValueError):
            return False
        made = data.get("provenance") if isinstance(data, dict) else None
        return isinstance(made, dict) and pattern.match(f"{made.get('command', '')} ") is not None
    try:
        with open(path, "rb") as handle:
            head = handle.read(HEAD_BYTES).decode("utf-8", errors="replace").splitlines()[:3]
    except OSError:
        return False
    lines = [line.lstrip("#<!- ") for line in head]
    # the line as the JSON's command, with a space after it: a run without arguments ('command: spherecal campaign')
    # did not match, and could not be run again into its own folder (h10's docs walk-through)
    return any(line.startswith("command: ") and pattern.match(f"{line[len('command: '):].rstrip()} ") for line in lines)


def refuse_unless_own(files: list[str | os.PathLike], option: str, command: str,
                      own: Callable[[Path], bool]) -> None:
    """Refuse to replace an existing file among ``files`` for which ``own`` is False.

    Args:
        files: the files the command will write (some may exist).
        option: the option naming their folder (``--out``), for the message.
        command: the command, for the message (``spherecal demo``).
        own: whether an existing file is an earlier run's own output.

    Raises:
        OutputError: one line naming the first such file and the option.
    """
    for path in map(Path, files):
        if path.is_file() and not own(path):
            raise OutputError(
                f"{path}: field '{option}': exists and was not written by an earlier `{command}` (a recording "
                "or your own file); choose a new folder or move it away"
            )


def refuse_foreign_files(files: list[str | os.PathLike], option: str, block: str, command: str) -> None:
    """Refuse to replace an existing file among ``files`` that an earlier ``command`` run did not write.

    Args:
        files: the files the command will write (some may exist).
        option: the option naming their folder (``--out``), for the message.
        block: the top-level YAML key the command writes its provenance under (``simulation``).
        command: the command, for the message (``spherecal simulate``).

    Raises:
        OutputError: one line naming the first such file and the option.
    """
    paths = [Path(f) for f in files]
    existing = [p for p in paths if p.is_file()]
    if not existing:
        return
    blocks = []  # comment blocks of the earlier run's YAML files present here
    for path in paths:
        if path.is_file() and path.suffix in (".yaml", ".yml"):
            made = _provenance(path, block)
            if made is not None:
                try:
                    blocks.append(comment_block(made).splitlines())
                except (KeyError, TypeError, AttributeError):
                    pass
    for path in existing:
        if path.suffix in (".yaml", ".yml"):
            own = _provenance(path, block) is not None
        else:
            comments = _leading_comments(path)
            own = any(comments[: len(lines)] == lines for lines in blocks if lines)
        if not own:
            raise OutputError(
                f"{path}: field '{option}': exists and was not written by an earlier `{command}` (a recording "
                f"or your own file: no '{block}' provenance); choose a new folder or move it away"
            )
