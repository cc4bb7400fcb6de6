"""`spherecal validate`: Compare nominal and calibrated models against the truth or motion-capture data."""

from __future__ import annotations

import argparse

HELP = "Compare nominal and calibrated models against the truth or motion-capture data."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal validate`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("validate")
