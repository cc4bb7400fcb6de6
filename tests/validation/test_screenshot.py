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


def test_a_tab_is_put_in_front_in_a_copy_with_one_blueprint(tmp_path) -> None:
    """--tab K opened a blueprint file beside the recording and the two blueprints raced: 2 of 6 renders of a socket
    validation with --tab 0 showed the recording's own front tab. The copy holds the recording's data and only the
    blueprint with tab K in front."""
    import numpy as np
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.recording import Recording, read_entity_rows, read_layout

    recording = Recording(tmp_path / "r.rrd", application_id="spherecal_check")
    recording.fixtures(["P1", "P2"], np.array([[0.4, 0.0, 0.1], [0.4, 0.05, 0.1]]))
    recording.workspace_errors("nominal", np.random.default_rng(0).normal(0.4, 0.01, (30, 3)), np.full(30, 1e-3), "x")
    recording.coverage({"P1": np.zeros((3, 2)), "P2": np.ones((3, 2))}, np.full(2, -2.0), np.full(2, 2.0))
    recording.text("table", "a table", "A table")
    recording.close()
    copy = _screenshot_module().with_tab(tmp_path / "r.rrd", 1, tmp_path)
    assert read_entity_rows(copy) == read_entity_rows(tmp_path / "r.rrd")
    assert read_layout(copy) == read_layout(tmp_path / "r.rrd")
    reader = RrdReader(str(copy))
    assert len(reader.blueprints()) == 1
    names, active = {}, []
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ContainerBlueprint:display_name" in batch.schema.names:
            names[chunk.entity_path.strip("/")] = batch.column("ContainerBlueprint:display_name").to_pylist()[0][0]
        if "ContainerBlueprint:active_tab" in batch.schema.names:
            active += batch.column("ContainerBlueprint:active_tab").to_pylist()[0]
    assert [names[tab] for tab in active] == ["Joint coverage"]  # tabs: Errors, Joint coverage, Tables
