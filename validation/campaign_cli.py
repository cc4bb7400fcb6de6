"""`spherecal campaign`: Run the paper's simulated protocol (fixture sets x noise levels) and print its error table."""

from __future__ import annotations

import argparse

HELP = "Run the paper's simulated protocol (fixture sets x noise levels) and print its error table."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal campaign`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("campaign")
