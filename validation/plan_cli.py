"""`spherecal plan`: Rank candidate fixture positions by the calibration accuracy they predict."""

from __future__ import annotations

import argparse

HELP = "Rank candidate fixture positions by the calibration accuracy they predict."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal plan`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("plan")
