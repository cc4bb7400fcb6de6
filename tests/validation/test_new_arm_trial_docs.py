"""The guide's new-arm path: every command of it is one the command line takes (new-arm trial)."""

from __future__ import annotations

import shlex
from pathlib import Path

from spherecal.cli import build_parser

GUIDE = Path(__file__).parents[2] / "docs" / "guide.md"


def test_the_new_arm_path_parses():
    text = GUIDE.read_text()
    block = text.split("### A new arm: plan, simulate, calibrate, validate")[1].split("```bash")[1].split("```")[0]
    lines = [line.split("#")[0] for line in block.strip().splitlines()]
    assert [shlex.split(line)[1] for line in lines] == ["plan", "simulate", "calibrate", "validate", "export"]
    parser = build_parser()
    for line in lines:
        args = parser.parse_args(shlex.split(line)[1:])
        assert args.command == shlex.split(line)[1]
