"""Render a spherecal recording as the viewer opens it, to a PNG (the picture check of a layout).

    python bench/screenshot.py spherecal-demo/demo.rrd --out shot.png [--size 1600x1000] [--tab 2]

Needs a display stack: ``apt-get install xvfb mesa-vulkan-drivers`` (Mesa's software Vulkan under
a virtual X server); it runs ``xvfb-run rerun FILE.rrd --screenshot-to shot.png``. With ``--tab K``
a copy of the recording whose blueprint has tab ``K`` of the result panel in front (0: the first)
is opened instead, so every tab can be checked without clicking. Exits 1 with one line when the stack is
missing.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("RERUN_ANALYTICS", "0")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout's spherecal, as the tests use


def viewer() -> str | None:
    """The ``rerun`` viewer next to this Python, or on PATH."""
    here = Path(sys.executable).with_name("rerun")
    return str(here) if here.exists() else shutil.which("rerun")


def display_stack_missing() -> str | None:
    """Why no screenshot can be taken here, or None."""
    if shutil.which("xvfb-run") is None:
        return "xvfb-run not found (apt-get install xvfb mesa-vulkan-drivers)"
    if viewer() is None:
        return "the rerun viewer is not installed (pip install rerun-sdk)"
    return None


def with_tab(rrd: str | os.PathLike, tab: int, folder: Path) -> Path:
    """A copy of the recording in ``folder`` whose one blueprint, its layout's, has tab ``tab`` of the result panel in
    front. Opened beside the recording, a blueprint file (``.rbl``) raced the recording's own blueprint: the viewer
    showed whichever loaded last (2 of 6 renders of a socket validation with ``--tab 0`` showed Socket spread)."""
    import rerun as rr
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.blueprint import build_blueprint
    from spherecal.validation.viewer.recording import read_layout

    layout = read_layout(rrd)
    if not layout:
        raise RuntimeError(f"{rrd}: no spherecal layout in this recording")
    path = folder / f"tab{tab}.rrd"
    copy = rr.RecordingStream(layout["application_id"])
    copy.save(path)
    copy.send_chunks(RrdReader(str(rrd)).stream())
    blueprint = build_blueprint(layout["contents"], layout["title"], layout["bounds"], active_tab=tab)
    copy.send_blueprint(blueprint, make_active=True, make_default=True)
    copy.flush()
    copy.disconnect()
    return path


def screenshot(
    rrd: str | os.PathLike,
    out: str | os.PathLike,
    size: str = "1600x1000",
    tab: int | None = None,
    timeout: float = 180,
) -> Path:
    """Open ``rrd`` in the viewer under Xvfb and save what it shows to ``out`` (PNG); returns ``out``.

    With ``tab``, a copy of it with that tab of the result panel in front (:func:`with_tab`)."""
    out = Path(out).resolve()
    out.unlink(missing_ok=True)
    width, height = (int(v) for v in size.split("x"))
    env = {**os.environ, "CI": "1", "RUST_LOG": "error"}  # no analytics notice, no log toasts over the views
    with tempfile.TemporaryDirectory() as home:  # the viewer's own settings and caches stay out of $HOME
        shown = Path(rrd).resolve() if tab is None else with_tab(rrd, tab, Path(home))
        command = ["xvfb-run", "-a", "-s", f"-screen 0 {width + 64}x{height + 64}x24", viewer(), str(shown),
                   "--window-size", size, "--hide-welcome-screen", "--screenshot-to", str(out)]
        done = subprocess.run(command, env={**env, "HOME": home}, capture_output=True, text=True, timeout=timeout,
                              cwd=home)
    if not out.exists():
        raise RuntimeError(f"the viewer wrote no screenshot (exit {done.returncode}): {done.stderr.strip()[-400:]}")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rrd", help="the recording (.rrd)")
    parser.add_argument("--out", default="shot.png", help="PNG to write (shot.png)")
    parser.add_argument("--size", default="1600x1000", help="window size in points, WxH (1600x1000)")
    parser.add_argument("--tab", type=int, help="put this tab of the result panel in front (0: the first)")
    args = parser.parse_args(argv)
    missing = display_stack_missing()
    if missing:
        print(f"screenshot: error: {missing}", file=sys.stderr)
        return 1
    print(screenshot(args.rrd, args.out, args.size, args.tab))
    return 0


if __name__ == "__main__":
    sys.exit(main())
