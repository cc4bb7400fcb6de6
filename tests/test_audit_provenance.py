"""Audit: every output records the command that made it, the versions, the seed and its inputs with their SHA-256."""

from __future__ import annotations

import hashlib
import sys

from spherecal.cli import main


def _sha256(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_tool_records_its_own_command_versions_and_inputs(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["export", "panda", "--format", "yaml", "--out", "cal.yaml"]) == 0
    argv = ["tool", "cal.yaml", "--offset", "0", "0", "0.2", "--out", "new tool.yaml"]
    monkeypatch.setattr(sys, "argv", ["spherecal", *argv])
    assert main(argv) == 0
    head = [line for line in (tmp_path / "new tool.yaml").read_text().splitlines() if line.startswith("#")]
    text = "\n".join(head)
    # before: only '# spherecal tool: cal.yaml with the tool at [np.float64(0.0), ...]': no version, no SHA-256
    assert "np.float64" not in text, text
    assert "# command: spherecal tool cal.yaml --offset 0 0 0.2 --out new tool.yaml" in head, text
    assert any(line.startswith("# versions: python ") and "spherecal " in line for line in head), text
    assert f"robot=cal.yaml (sha256 {_sha256(tmp_path / 'cal.yaml')})" in text, text
    assert "# seed: None" in head, text
