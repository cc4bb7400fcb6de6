"""Audit: the same command with the same seed writes the same bytes, but for the creation time."""

from __future__ import annotations

import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path


def _spherecal(cwd: Path, *argv: str) -> None:
    done = subprocess.run([sys.executable, "-m", "spherecal", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr


def _without_created(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if not line.startswith("# created: ")]


def test_plan_with_one_worker_twice_writes_the_same_fixtures_file(tmp_path) -> None:
    plan = ["plan", "--grid", "0.4,0.5,2;-0.2,0.2,2;0.4,0.5,2", "--per-fixture", "50", "--workers", "1"]
    for run in ("one", "two"):
        (tmp_path / run).mkdir()
        _spherecal(tmp_path / run, *plan, "--fixtures-out", "fixtures.yaml")
    one, two = (_without_created(tmp_path / run / "fixtures.yaml") for run in ("one", "two"))
    # before: '# workers: host pid 498: ...' against 'host pid 524': the pid of the command's own process
    assert one == two, [(a, b) for a, b in zip(one, two, strict=False) if a != b]
    assert any(line.startswith("# workers: ") and "main process" in line for line in one), one


def test_a_pool_worker_is_still_named_by_its_pid() -> None:
    from spherecal.correction.files.provenance import this_process

    with ProcessPoolExecutor(max_workers=1) as pool:
        name, _ = pool.submit(this_process).result()
    assert " pid " in name and this_process()[0].endswith(" main process")
