"""A recording's printed tables read as printed: one row per line, the columns in line (a review by screenshot).

As a Markdown code block the Tables tab wrapped every line longer than its panel: the demo's validation table (102
characters) put the 'vs exact tool point' std and max of each row on the next line, under the row's name, and the
plan's table its q5..q7 columns. The tables are plain text now, shown in a monospace font without wrapping."""

from __future__ import annotations

from rerun.chunk import RrdReader

from spherecal.validation.viewer.recording import Recording, _blueprint_batches

WIDE = "set                    model       |     mean      std      max |     mean      std      max\n" + (
    "random workspace       nominal     |    4.810    1.928   12.495 |    4.798    1.921   12.481")


def _document(path, entity: str) -> dict:
    for chunk in RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path.strip("/") == entity:
            batch = chunk.to_record_batch()
            return {n.split(":")[1]: batch.column(n).to_pylist()[0][0] for n in batch.schema.names if ":" in n}
    raise KeyError(entity)


def test_a_table_is_logged_as_printed_plain_text(tmp_path) -> None:
    recording = Recording(tmp_path / "t.rrd")
    recording.text("validation", WIDE, "Validation table (mm)")
    recording.text("provenance", "command: spherecal validate", "Provenance")
    recording.close()
    table = _document(tmp_path / "t.rrd", "tables/validation")
    assert table["media_type"] == "text/plain" and table["text"] == WIDE  # no code fence around it
    assert _document(tmp_path / "t.rrd", "tables/provenance")["media_type"] == "text/plain"


def test_every_table_view_is_monospace_and_unwrapped(tmp_path) -> None:
    recording = Recording(tmp_path / "t.rrd")
    recording.text("validation", WIDE, "Validation table (mm)")
    recording.text("calibration", "a table", "Calibration table (mm, deg)")
    recording.text("provenance", "command: spherecal validate", "Provenance")
    recording.close()
    formats = [{n.split(":")[1]: batch.column(n).to_pylist()[0][0] for n in batch.schema.names if ":" in n}
               for entity, batch in _blueprint_batches(tmp_path / "t.rrd") if entity.endswith("/TextDocumentFormat")]
    assert len(formats) == 3  # one per table view
    assert all(f == {"monospace": True, "word_wrap": False} for f in formats)
