"""`spherecal calibrate`: Identify DH parameters from spherical-joint samples and write a calibrated robot file."""

from __future__ import annotations

import argparse

HELP = "Identify DH parameters from spherical-joint samples and write a calibrated robot file."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal calibrate`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("calibrate")
