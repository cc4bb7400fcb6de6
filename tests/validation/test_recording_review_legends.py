"""No bar chart of a recording shows Rerun's legend (a review by screenshot): it names the entity path, which the
view's own name says better, and in the Joint coverage tab '/coverage/P2' stood over the top of P2's q6 bar (97 %)."""

from __future__ import annotations

import numpy as np

from spherecal.validation.viewer.recording import Recording, _blueprint_batches


def _legends(path) -> dict[str, bool | None]:
    """View origin -> whether its plot legend is visible (None: not set, Rerun shows it) of every bar chart view."""
    origins, kinds, visible = {}, {}, {}
    for entity, batch in _blueprint_batches(path):
        names = batch.schema.names
        if "ViewBlueprint:space_origin" in names:
            origins[entity] = str(batch.column("ViewBlueprint:space_origin").to_pylist()[0][0])
            kinds[entity] = str(batch.column("ViewBlueprint:class_identifier").to_pylist()[0][0])
        if "PlotLegend:visible" in names:
            visible[entity.rsplit("/", 1)[0]] = bool(batch.column("PlotLegend:visible").to_pylist()[0][0])
    return {origins[v]: visible.get(v) for v in origins if kinds[v] == "BarChart"}


def test_no_bar_chart_shows_a_legend(tmp_path, rng, panda) -> None:
    q = panda.random_configurations(40, rng)
    recording = Recording(tmp_path / "r.rrd")
    recording.coverage({"P1": q[:20], "P2": q[20:]}, panda.lower, panda.upper)
    recording.residuals(np.full(30, 1e-3), np.full(30, 1e-4))
    recording.workspace_errors("nominal", rng.normal(size=(40, 3)), np.full(40, 1e-3), "the mocap")
    recording.close()
    legends = _legends(tmp_path / "r.rrd")
    assert {"coverage/P1", "coverage/P2", "residuals/before", "errors/nominal/histogram"} <= set(legends)
    assert all(v is False for v in legends.values()), legends
