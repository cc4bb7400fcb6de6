"""`spherecal simulate`: self-motion at spherical-joint fixtures on a perturbed (true) robot."""

from __future__ import annotations

import argparse

HELP = "Simulate self-motion at spherical-joint fixtures on a perturbed (true) robot and write samples."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal simulate`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("simulate")
