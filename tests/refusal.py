"""Shared by the refusal tests: run a command, assert one line, exit 1, inputs unchanged, nothing written."""

from __future__ import annotations

import os
from pathlib import Path

from spherecal.cli import main


def snapshot(folder: Path) -> dict[str, tuple[bytes, int] | None]:
    """Every path under ``folder``: (content, mtime in ns) of files, None for folders."""
    found: dict[str, tuple[bytes, int] | None] = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs:
            found[os.path.join(root, name)] = None
        for name in files:
            path = os.path.join(root, name)
            if os.path.islink(path) and not os.path.exists(path):
                found[path] = (b"<dangling>", 0)
                continue
            if not os.path.isfile(path):  # a pipe or device: reading it would block; its kind is what matters
                found[path] = (b"<special>", os.stat(path).st_mode)
                continue
            found[path] = (Path(path).read_bytes(), os.stat(path).st_mtime_ns)
    return found


def refused(argv: list[str], folder: Path, capsys, *expected: str) -> str:
    """Run ``spherecal argv``: exit status 1, one error line on stderr (after the warnings the command gave before it,
    each on its own line, and before the indented lines of a long refusal's detail) that with them contains every
    ``expected`` text, and nothing under ``folder`` changed (inputs' content and mtime, no file added or removed)."""
    capsys.readouterr()  # what earlier commands of the test printed is not this refusal's
    before = snapshot(folder)
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    err = captured.err
    assert status == 1, (status, err)
    lines = err.rstrip("\n").splitlines()
    warned = [line for line in lines if line.startswith(f"spherecal {argv[0]}: warning: ")]
    assert lines[:len(warned)] == warned, err
    error, *details = lines[len(warned):]
    assert error.startswith(f"spherecal {argv[0]}: error: "), err
    assert all(line.startswith("  ") and line.strip() for line in details), err  # a long refusal's detail
    for text in expected:
        assert text in err, (text, err)
    after = snapshot(folder)
    assert after == before, sorted(set(after) ^ set(before)) or "an input changed"
    return err
