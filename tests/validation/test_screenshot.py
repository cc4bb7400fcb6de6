"""The picture check: a short demo recording rendered by the Rerun viewer under Xvfb (slow; skipped
without xvfb-run). Look at the PNG yourself when the layout changes: this only checks it is a picture."""

from __future__ import annotations

import importlib.util
import struct
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]


def _screenshot_module():
    spec = importlib.util.spec_from_file_location("bench_screenshot", ROOT / "bench" / "screenshot.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _png_pixels(path: Path) -> tuple[int, int, bytes]:
    """Width, height and the decompressed (filtered) scan lines of a PNG."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    position, idat, size = 8, b"", (0, 0)
    while position < len(data):
        length, kind = struct.unpack(">I4s", data[position : position + 8])
        body = data[position + 8 : position + 8 + length]
        if kind == b"IHDR":
            size = struct.unpack(">II", body[:8])
        elif kind == b"IDAT":
            idat += body
        position += 12 + length
    return size[0], size[1], zlib.decompress(idat)


@pytest.mark.slow
def test_the_viewer_renders_the_demo_recording(tmp_path) -> None:
    screenshot = _screenshot_module()
    missing = screenshot.display_stack_missing()
    if missing:
        pytest.skip(missing)
    from spherecal.cli import main

    out = tmp_path / "demo"
    args = ["demo", "--out", str(out), "--seconds", "1", "--samples", "60", "--configurations", "200", "--quiet"]
    assert main(args) == 0
    for tab in (None, 2):
        png = screenshot.screenshot(out / "demo.rrd", tmp_path / f"shot{tab}.png", size="1200x800", tab=tab)
        width, height, pixels = _png_pixels(png)
        assert width >= 1200 and height >= 800  # at least the window (the viewer may render at 2x)
        assert len(set(pixels[:: max(1, len(pixels) // 200000)])) > 30  # a picture, not a blank window
