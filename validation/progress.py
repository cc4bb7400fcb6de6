"""Progress bars on stderr (tqdm) for the long stages; silent when stderr is not a terminal."""

from __future__ import annotations

import shutil
import sys
from contextlib import contextmanager


@contextmanager
def progress_bar(total: float, desc: str, unit: str, quiet: bool = False, decimals: int = 0):
    """A tqdm bar on stderr, yielded as its ``update`` function (called with the amount done).

    The bar is off with ``quiet`` or when stderr is not a terminal (pipes, files, CI logs), so
    captured output holds only the printed results.

    Args:
        total: the amount to do (simulated seconds, configurations, ...).
        desc: what is being done, in plain words.
        unit: the unit of ``total`` as shown.
        quiet: no bar at all.
        decimals: decimals of the amounts shown.
    """
    from tqdm import tqdm  # function-level: only the commands that show progress need it

    disable = quiet or not sys.stderr.isatty()
    size = shutil.get_terminal_size((100, 20))  # a terminal that reports 0 x 0 (a pty) would hide the bar
    with tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=disable, leave=True, ncols=size.columns,
              nrows=size.lines,
              bar_format=f"{{desc}}: {{percentage:3.0f}}%|{{bar}}| {{n:.{decimals}f}}/{{total:.{decimals}f}} {{unit}} "
              "[{elapsed}<{remaining}]",
              ) as bar:
        yield bar.update
