"""`spherecal export`: Export a calibrated robot file as URDF, MJCF or YAML."""

from __future__ import annotations

import argparse

HELP = "Export a calibrated robot file as URDF, MJCF or YAML."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal export`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("export")
