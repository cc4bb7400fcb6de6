"""Validation: simulated motion capture, registration, comparisons, Rerun recordings."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import apply_transform, fit_rigid_transform, perturb, tool_point
from spherecal.correction.layout import ANGLE, LENGTH
from spherecal.validation.compare import ValidationSet, compare, format_comparisons, parameter_deviations
from spherecal.validation.mocap import (
    MarkerCluster,
    MocapError,
    MocapMeasurement,
    SimulatedMocap,
    default_cluster,
    random_mocap_transform,
    read_mocap_csv,
    write_mocap_csv,
)


@pytest.fixture(scope="module")
def truth(panda):
    return perturb(panda, np.random.default_rng(7))


@pytest.fixture(scope="module")
def mocap(truth):
    return SimulatedMocap(truth, random_mocap_transform(np.random.default_rng(8)))


def test_registration_recovers_mocap_frame_from_noisy_markers(truth, mocap, rng) -> None:
    q = truth.random_configurations(2000, rng)
    measured = mocap.measure(q, rng)
    estimate = fit_rigid_transform(tool_point(truth, q), measured.tool)
    shift = np.linalg.norm(estimate[:3, 3] - mocap.transform[:3, 3])
    delta = np.linalg.inv(mocap.transform) @ estimate
    angle = np.arccos(np.clip((np.trace(delta[:3, :3]) - 1.0) / 2.0, -1.0, 1.0))
    assert shift < 0.05e-3 and np.rad2deg(angle) < 0.01
    # and the noise is really there: the tool points scatter by about the marker noise
    scatter = np.linalg.norm(apply_transform(mocap.transform, measured.exact_tool) - measured.tool, axis=1)
    assert 0.1e-3 < scatter.mean() < 0.6e-3


def test_markers_come_from_mujoco_and_the_cluster_gives_the_tool_point(truth, rng) -> None:
    mocap = SimulatedMocap(truth, np.eye(4), noise=0.0)
    q = truth.random_configurations(20, rng)
    measured = mocap.measure(q, rng)
    np.testing.assert_allclose(measured.exact_tool, tool_point(truth, q), atol=1e-12)
    np.testing.assert_allclose(measured.tool, measured.exact_tool, atol=1e-12)
    # markers keep their distances to the tool point (rigid cluster)
    expected = np.linalg.norm(mocap.cluster.markers - mocap.cluster.tool, axis=1)
    distances = np.linalg.norm(measured.markers - measured.tool[:, None], axis=2)
    np.testing.assert_allclose(distances, np.broadcast_to(expected, distances.shape), atol=1e-12)


def test_cluster_rejects_collinear_markers() -> None:
    with pytest.raises(ValueError, match="collinear"):
        MarkerCluster(markers=[[0, 0, 0], [1, 0, 0], [2, 0, 0]], tool=[0, 0, 0])


def test_compare_keeps_the_two_columns_apart(panda, truth, mocap, rng) -> None:
    q = truth.random_configurations(500, rng)
    measured = mocap.measure(q, rng)
    sets = [ValidationSet("random", q[:400], measured.tool[:400], measured.exact_tool[:400]),
            ValidationSet("P1", q[400:], measured.tool[400:], measured.exact_tool[400:])]
    result, other = compare({"nominal": panda, "truth": truth}, sets)
    assert other.vs_exact["truth"].count == 100 and other.name == "P1"
    assert result.vs_exact["truth"].max < 1e-9  # the true model is exact against the plant
    assert result.vs_exact["nominal"].mean > 1e-3  # a perturbed robot is millimetres off
    floor = result.floor.mean
    assert 0.1e-3 < floor < 0.6e-3
    assert result.vs_mocap["truth"].mean == pytest.approx(floor, rel=1e-9)
    text = format_comparisons([result])
    assert "mocap floor" in text and "vs exact" in text


def test_registration_removes_a_base_placement(panda, rng) -> None:
    moved = panda.with_params(panda.params + np.r_[np.zeros(panda.n_params - 6), 0.1, -0.2, 0.3, 0.1, 0.2, -0.3])
    q = panda.random_configurations(100, rng)
    (result,) = compare({"moved": moved}, [ValidationSet("moved", q, exact=tool_point(panda, q))])
    assert result.vs_exact["moved"].max < 1e-9 and not result.vs_mocap and result.floor is None


def test_parameter_deviations(panda, truth) -> None:
    deviations = parameter_deviations(panda, truth, truth)
    np.testing.assert_allclose(deviations.calibrated, 0.0)
    i = panda.param_index("alpha2")
    assert deviations.display(deviations.nominal)[i] == pytest.approx(np.rad2deg(panda.alpha[1] - truth.alpha[1]))
    assert "alpha2" in deviations.format()


@pytest.mark.parametrize("extras", [{"scale": [1e-3] * 7}, {"compliance": [1e-3] * 7},
                                    {"scale": [1e-3] * 7, "compliance": [1e-3] * 7}])
def test_parameter_deviations_of_a_scale_or_elastic_calibration_against_a_rigid_truth(panda, truth, extras) -> None:
    # validate --truth on an elastic+scale calibration raised 'operands could not be broadcast together with
    # shapes (51,) (44,)': only compliance was lifted to a common layout
    calibrated = replace(truth, extras={**truth.extras, **extras})
    deviations = parameter_deviations(panda, calibrated, truth)
    names = deviations.layout.names
    for key, values in extras.items():
        prefix = "c" if key == "compliance" else "s"
        rows = [names.index(f"{prefix}{j}") for j in range(1, 8)]
        np.testing.assert_allclose(deviations.calibrated[rows], values)  # the truth has none: 0
        np.testing.assert_allclose(deviations.nominal[rows], 0.0)
    geometric = [names.index(n) for n in truth.layout.names]
    np.testing.assert_allclose(deviations.calibrated[geometric], 0.0, atol=1e-15)
    np.testing.assert_allclose(deviations.nominal[geometric], panda.params - truth.params)


@pytest.mark.parametrize("markers", [False, True])
def test_mocap_csv_round_trip(tmp_path, truth, mocap, rng, markers) -> None:
    q = truth.random_configurations(10, rng)
    measured = mocap.measure(q, rng, t=np.arange(10) * 0.5)
    if not markers:
        measured = MocapMeasurement(q=measured.q, tool=measured.tool, t=measured.t)
    path = write_mocap_csv(tmp_path / "m.csv", measured, comment="seed 1")
    back = read_mocap_csv(path, truth.n_joints, cluster=mocap.cluster)
    np.testing.assert_array_equal(back.q, measured.q)
    np.testing.assert_array_equal(back.t, measured.t)
    np.testing.assert_allclose(back.tool, measured.tool, atol=1e-12)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda lines: lines.__setitem__(3, lines[3].replace(",", ",,", 1)),
         "row 4: field column 11: 11 columns, expected 10"),
        (lambda lines: lines.__setitem__(3, lines[3].rsplit(",", 1)[0]), "row 4: field z: 9 columns, expected 10"),
        (lambda lines: lines.__setitem__(2, ",".join(lines[2].split(",")[:-1] + [""])), "row 3: field z: missing"),
        (lambda lines: lines.__setitem__(5, lines[5].replace(lines[5].split(",")[2], "abc")), "row 6: field q3"),
        # the header named the row but not the field (a review): field header, or the column given twice
        (lambda lines: lines.__setitem__(0, "q1,q2,q3,x,y,z"), "row 1: field header: header 'q1,q2,q3,x,y,z' does "
                                                               "not match a 7-joint robot, expected 'q1,q2,q3,q4,q5,"
                                                               "q6,q7,x,y,z' or marker columns"),
        (lambda lines: lines.__setitem__(0, "q1,q2,q2,q4,q5,q6,q7,x,y,z"), "row 1: field q2: header 'q1,q2,q2,q4,"
                                                                           "q5,q6,q7,x,y,z' does not match a 7-joint "
                                                                           "robot (q2 given twice), expected"),
        (lambda lines: lines.__setitem__(0, "q1,q2,q3,q4,q5,q6,q7,m0_x,m0_y,m0_z,m1_x,m1_y,m1_z"),
         "row 1: field header: 2 marker columns need a cluster"),
    ],
)
def test_mocap_csv_errors_name_file_row_field(tmp_path, truth, rng, edit, message) -> None:
    q = truth.random_configurations(6, rng)
    path = write_mocap_csv(tmp_path / "m.csv", MocapMeasurement(q=q, tool=tool_point(truth, q)))
    lines = path.read_text().splitlines()
    edit(lines)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MocapError) as error:
        read_mocap_csv(path, truth.n_joints)
    text = str(error.value)
    assert "\n" not in text and str(path) in text and message in text


def test_mocap_csv_binary_byte_order_mark_crlf_whitespace_lines(tmp_path, truth, rng) -> None:
    # a binary file used to escape as a UnicodeDecodeError traceback; a BOM broke the header; a trailing
    # whitespace-only line was a 1-column data row
    q = truth.random_configurations(6, rng)
    path = write_mocap_csv(tmp_path / "m.csv", MocapMeasurement(q=q, tool=tool_point(truth, q)))
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    np.testing.assert_array_equal(read_mocap_csv(path, truth.n_joints).q, q)
    path.write_bytes(path.read_bytes().replace(b"\n", b"\r\n") + b"\r\n  \r\n\t\n")  # CRLF, whitespace lines
    np.testing.assert_array_equal(read_mocap_csv(path, truth.n_joints).q, q)
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xf0\x90\x80")
    with pytest.raises(MocapError, match="cannot read: not UTF-8"):
        read_mocap_csv(path, truth.n_joints)


def test_marker_columns_need_a_cluster(tmp_path, truth, mocap, rng) -> None:
    path = write_mocap_csv(tmp_path / "m.csv", mocap.measure(truth.random_configurations(5, rng), rng))
    with pytest.raises(MocapError, match="cluster"):
        read_mocap_csv(path, truth.n_joints)
    assert default_cluster(truth.tool).n_markers == 4


def _covered_column(origins: np.ndarray, radius: float) -> float:
    """The top [m] of the stretch of the base's z axis, from its foot up, that lies inside a link capsule (segments
    between consecutive origins, ``radius``), highest over the steps: by brute force, every millimetre of the axis
    against every capsule."""
    z = np.arange(0.0, 2.0, 1e-3)
    axis = np.stack([np.zeros_like(z), np.zeros_like(z), z], axis=-1)
    top = 0.0
    for step in origins:
        inside = np.zeros(len(z), dtype=bool)
        for a, b in zip(step[:-1], step[1:], strict=True):
            t = np.clip((axis - a) @ (b - a) / max((b - a) @ (b - a), 1e-12), 0.0, 1.0)
            inside |= np.linalg.norm(axis - (a + t[:, None] * (b - a)), axis=-1) <= radius
        if inside[0]:
            top = max(top, z[np.argmin(inside)] if not inside.all() else z[-1])
    return float(top)


def test_recording_holds_the_documented_entities_and_its_blueprint(tmp_path, panda, truth, rng) -> None:
    from spherecal.correction import link_frames
    from spherecal.validation.viewer.recording import (
        COLOURS,
        FIXTURE_COLOURS,
        LINK_RADIUS,
        Recording,
        read_entity_rows,
        read_view_names,
    )

    q = truth.random_configurations(40, rng)
    recording = Recording(tmp_path / "r.rrd", title="Robot")
    recording.fixtures(["P1", "P2"], np.zeros((2, 3)))
    recording.self_motion(truth, np.arange(40) * 0.01, q)
    recording.samples(tool_point(truth, q), ["P1"] * 20 + ["P2"] * 20)
    errors = np.linspace(0.0, 2e-3, 40)
    recording.workspace_errors("nominal", tool_point(panda, q), errors, "the mocap")
    recording.residuals(np.full(30, 1e-3), np.full(30, 1e-4))
    recording.parameter_changes(["a2", "alpha2", "d7 + tool_z"], [LENGTH, ANGLE, LENGTH], np.array([1e-3, 1e-3, -2e-4]),
                                np.array([1e-5, 1e-5, 1e-5]), np.array([1.1e-3, 1e-3, -2e-4]))
    recording.coverage({"P1": q[:20], "P2": q[20:]}, truth.lower, truth.upper)
    recording.text("calibration", "a table", "Calibration table")
    assert recording.close() == tmp_path / "r.rrd"
    rows = read_entity_rows(tmp_path / "r.rrd")
    # the arm: one capsule row per time step (plus the static radii/colours), the tool point likewise
    assert rows["world/robot/arm"] == rows["world/robot/tool"] == 41
    single = ["world/fixtures", "world/samples", "errors/nominal/points", "errors/nominal/colour_scale",
              "errors/nominal/histogram", "residuals/before", "residuals/after", "parameters/lengths/bars",
              "parameters/lengths/std", "parameters/lengths/truth", "parameters/angles/bars", "coverage/P1",
              "coverage/P2", "tables/calibration"]
    for path in single:
        assert rows[path] == 1, path
    views = read_view_names(tmp_path / "r.rrd")
    assert "Robot" in views and "Calibration table" in views
    # short enough for the title bar of an Errors view (27 characters): 'Nominal: error, mean 4.798 mm over 5000
    # points' showed as 'Nominal: error, mean 4.798 m'; what it is a distance to and over how many points is in the view
    assert "Nominal: mean 1.000 mm" in views
    scene = _scene(tmp_path / "r.rrd", "")
    assert scene["errors/nominal/heading"]["labels"][0].replace("\n", " ") == (
        "nominal: distance [mm] to the mocap, 40 points")
    assert "Residuals after calibration [mm]: rms 0.100 mm, bars 0 to 0.1 mm" in views
    assert any(v.startswith("P2: joint coverage") for v in views)  # the fixture first: a grid cuts the titles
    assert "Lengths [mm]: change, +-1 std, white dot = true change" in views
    # each bar chart in the colour of what it shows (Rerun's own palette gave P1's bars P3's colour): the histograms
    # the model's, as its points and socket spreads; the coverage the fixture's sphere's, as its samples
    packed = {name: int.from_bytes(bytes([*rgb, 255]), "big") for name, rgb in
              [*COLOURS.items(), ("P1", FIXTURE_COLOURS[0]), ("P2", FIXTURE_COLOURS[1])]}
    assert scene["errors/nominal/histogram"]["color"] == [packed["nominal"]]
    assert scene["residuals/before"]["color"] == [packed["nominal"]]
    assert scene["residuals/after"]["color"] == [packed["calibrated"]]
    assert [scene[f"coverage/{f}"]["color"] for f in ("P1", "P2")] == [[packed["P1"]], [packed["P2"]]]
    assert scene["world/samples"]["colors"] == [packed["P1"]] * 20 + [packed["P2"]] * 20
    # the base frame: which way x, y, z point and how long 0.25 m is, at the origin of the fixture centres' frame; z
    # out of the arm's links (at 0.25 m it ran inside the Panda's first link, 0.333 m high: a review)
    vectors = np.array(scene["world/base_frame"]["vectors"])
    np.testing.assert_allclose(vectors[:2], np.eye(3)[:2] * 0.25)
    up = vectors[2, 2]
    assert vectors[2, :2].tolist() == [0.0, 0.0] and up == pytest.approx(round(up / 0.05) * 0.05)
    covered = _covered_column(link_frames(truth, q)[:, :, :3, 3], LINK_RADIUS)
    assert 0.333 + LINK_RADIUS <= covered and covered + 0.1 <= up < covered + 0.15 + 1e-9, (covered, up)
    np.testing.assert_allclose(scene["world/base_frame"]["origins"], np.zeros((3, 3)))
    assert scene["world/base_frame"]["labels"] == ["x (250 mm)", "y", f"z ({up * 1e3:.0f} mm)"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.rrd"]


def test_samples_and_coverage_take_their_fixture_s_colour_whatever_the_order(tmp_path, truth, rng) -> None:
    """The samples were coloured by their labels' sorted order and the coverage bars by Rerun's palette, the fixture
    spheres by the order of the names given: with sockets named 'b', 'a' a socket's samples wore the other's colour."""
    from spherecal.validation.viewer.recording import FIXTURE_COLOURS, Recording

    q = truth.random_configurations(4, rng)
    recording = Recording(tmp_path / "o.rrd")
    recording.fixtures(["b (fit)", "a"], np.zeros((2, 3)))
    recording.samples(tool_point(truth, q), ["a", "a", "b", "b"])
    recording.coverage({"a": q[:2], "b": q[2:]}, truth.lower, truth.upper)
    recording.close()
    scene = _scene(tmp_path / "o.rrd", "")
    b, a = (int.from_bytes(bytes([*c, 255]), "big") for c in FIXTURE_COLOURS[:2])
    assert scene["world/samples"]["colors"] == [a, a, b, b]
    assert scene["coverage/a"]["color"] == [a] and scene["coverage/b"]["color"] == [b]


def test_samples_are_drawn_magnified_inside_wire_spheres(tmp_path, rng) -> None:
    """A reviewer found the recorded samples hidden inside the fixture spheres: tenths of a millimetre apart, they
    made one dot inside a solid 20 mm ball. The spheres are wire frames (0.4 of the distance between the nearest two,
    20 to 50 mm), the samples are drawn about their fixture's centre, their offsets magnified by one gain so that their
    95th percentile fills the sphere, and the first fixture's label says what the sphere stands for; world/fixtures
    is still one row."""
    from spherecal.validation.viewer.recording import FIXTURE_RADIUS, Recording, read_entity_rows, read_layout

    centres = np.array([[0.5, -0.25, 0.5], [0.5, 0.0, 0.4]])
    labels = np.repeat(["P1", "P2"], 300)
    points = centres[[0] * 300 + [1] * 300] + rng.normal(0.0, 0.25e-3, (600, 3))
    recording = Recording(tmp_path / "m.rrd")
    recording.fixtures(["P1", "P2 (fit)"], centres)
    recording.samples(points, labels)
    recording.close()
    scene = _scene(tmp_path / "m.rrd", "world/")
    fixtures, shown = scene["world/fixtures"], np.array(scene["world/samples"]["positions"])
    assert read_entity_rows(tmp_path / "m.rrd")["world/fixtures"] == 1
    assert fixtures["fill_mode"][0] != 3  # FillMode.Solid hid the samples
    radius = fixtures["half_sizes"][0][0]
    assert radius == pytest.approx(FIXTURE_RADIUS[1], rel=1e-6)  # 0.4 x 269 mm apart, at most 50 mm
    assert fixtures["labels"] == ["P1", "P2 (fit)"]  # the note covered the next socket's label: in the view's title
    title = read_layout(tmp_path / "m.rrd")["title"]
    assert title.endswith("; samples x50 about each fixture's centre, its sphere 1 mm")
    np.testing.assert_allclose(shown - centres[[0] * 300 + [1] * 300], 50 * (points - centres[[0] * 300 + [1] * 300]),
                               atol=1e-6)
    far = np.quantile(np.linalg.norm(shown - centres[[0] * 300 + [1] * 300], axis=1), 0.95)
    assert 0.4 * radius < far <= radius  # the scatter fills the sphere
    assert scene["world/samples"]["radii"][0] < 0  # of a size on the screen (ui points), not in metres


def test_the_tables_tab_opens_on_the_results_not_the_provenance(tmp_path) -> None:
    """validate and demo log the provenance first: the Tables tab showed it and hid the table a reviewer opens it
    for behind a second tab."""
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.recording import Recording

    recording = Recording(tmp_path / "t.rrd")
    recording.provenance({"command": "spherecal validate", "created": "now", "seed": 0, "versions": {}, "inputs": {}})
    recording.text("sockets", "a table", "Socket validation table (mm)")
    recording.close()
    reader = RrdReader(str(tmp_path / "t.rrd"))
    names = {}
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in batch.schema.names:
            names[chunk.entity_path.rsplit("/", 1)[-1]] = batch.column("ViewBlueprint:display_name").to_pylist()[0][0]
        if "ContainerBlueprint:display_name" in batch.schema.names and "ContainerBlueprint:contents" in \
                batch.schema.names and batch.column("ContainerBlueprint:display_name").to_pylist()[0] == ["Tables"]:
            order = [c.rsplit("/", 1)[-1] for c in batch.column("ContainerBlueprint:contents").to_pylist()[0]]
    assert [names[view] for view in order] == ["Socket validation table (mm)", "Provenance"]


def _scene(path, prefix: str) -> dict[str, dict[str, list]]:
    """Entity (without the leading /) -> {component: its first row} of a recording's entities under prefix."""
    from rerun.chunk import RrdReader

    scene = {}
    for chunk in RrdReader(str(path)).stream().to_chunks():
        entity = chunk.entity_path.strip("/")
        if entity.startswith(prefix):
            batch = chunk.to_record_batch()
            scene[entity] = {n.split(":")[1]: batch.column(n).to_pylist()[0] for n in batch.schema.names if ":" in n}
    return scene


def test_socket_spread_is_drawn_in_mm_around_each_model_s_mean(tmp_path, rng) -> None:
    """Around the calibrated mean, the nominal cloud stood where the nominal model puts the socket (7 to 13 mm away
    on MUKCa panda_2_clean) and the calibrated cluster outside it, as if that distance were the error compared: each
    cloud is drawn around its own mean, and the legend says how far apart the means are."""
    from spherecal.validation.viewer.recording import Recording, read_entity_rows, read_view_names

    centre = np.array([0.5, 0.1, 0.4])
    nominal = centre + np.array([2e-3, 0.0, 0.0]) + rng.normal(0, 1e-3, (50, 3))  # 2 mm off, 1.7 mm rms spread
    calibrated = centre + rng.normal(0, 5e-5, (50, 3))
    recording = Recording(tmp_path / "s.rrd")
    recording.socket_spread("S1", nominal, calibrated)
    with pytest.raises(ValueError, match="socket S2: nominal points must have shape"):
        recording.socket_spread("S2", nominal[:, :2], calibrated)
    recording.close()
    rows = read_entity_rows(tmp_path / "s.rrd")
    assert {k: v for k, v in rows.items() if k.startswith("sockets/")} == {
        "sockets/S1/legend": 1,
        **{f"sockets/S1/{key}{end}": 1 for key in ("nominal", "calibrated") for end in ("", "_mean")},
    }
    spread = [np.mean(np.linalg.norm(p - p.mean(0), axis=1)) * 1e3 for p in (nominal, calibrated)]  # the table's
    assert "S1: socket spread [mm]" in read_view_names(tmp_path / "s.rrd")  # its name first: the title is cut
    scene = _scene(tmp_path / "s.rrd", "sockets/S1/")
    # the socket's name in the view as well: a grid of 14 sockets showed 'Socket bac' of every title
    apart = np.linalg.norm(nominal.mean(0) - calibrated.mean(0)) * 1e3
    assert 1.0 < apart < 3.0
    assert scene["sockets/S1/legend"]["labels"] == [f"S1\ncalibrated: spread {spread[1]:.3f} mm",
                                                    f"nominal: spread {spread[0]:.3f} mm\nmeans {apart:.2f} mm apart"]
    # each model's points in mm from its own mean, a wire sphere as wide as its spread around it
    for key, points, value in zip(("nominal", "calibrated"), (nominal, calibrated), spread, strict=True):
        np.testing.assert_allclose(scene[f"sockets/S1/{key}"]["positions"], (points - points.mean(0)) * 1e3,
                                   atol=1e-4)
        assert scene[f"sockets/S1/{key}_mean"]["half_sizes"] == [pytest.approx([value] * 3, rel=1e-6)]
        assert np.allclose(scene[f"sockets/S1/{key}_mean"]["centers"], 0.0, atol=1e-9)


def test_saving_a_recording_writes_no_analytics_files(tmp_path) -> None:
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("RERUN_ANALYTICS", "XDG_CONFIG_HOME", "XDG_DATA_HOME")}
    env["HOME"] = str(tmp_path)
    code = (
        "import numpy as np; from spherecal.validation.viewer.recording import Recording;"
        f"r = Recording({str(tmp_path / 'r.rrd')!r}); r.fixtures(['P1'], np.zeros((1, 3))); r.close()"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "Welcome to Rerun" not in out.stdout + out.stderr
    assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == ["r.rrd"]


def test_a_colour_scale_beside_flat_points_is_tall_enough_to_read(tmp_path, rng) -> None:
    """Sockets on a plate lie within millimetres of one height: the scale beside them spans the points' largest
    extent (at least SCALE_HEIGHT), its spheres apart, not 21 spheres of 3 cm stacked in 0.6 mm (a review)."""
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.recording import SCALE_HEIGHT, Recording

    points = np.column_stack([rng.uniform(0.3, 0.7, 60), rng.uniform(-0.2, 0.2, 60), 0.1 + rng.normal(0, 3e-4, 60)])
    recording = Recording(tmp_path / "flat.rrd")
    recording.workspace_errors("calibrated", points, rng.uniform(0, 3e-4, 60), "its socket's mean point")
    recording.close()
    for chunk in RrdReader(str(tmp_path / "flat.rrd")).stream().to_chunks():
        if chunk.entity_path.endswith("colour_scale"):
            batch = chunk.to_record_batch()
            scale = np.array(batch.column("Points3D:positions").to_pylist()[0])
            radius = batch.column("Points3D:radii").to_pylist()[0][0]
    extent = np.max(points.max(0) - points.min(0))
    span = scale[:, 2].max() - scale[:, 2].min()
    assert span == pytest.approx(max(extent, SCALE_HEIGHT)) and 2 * radius < span / 20  # apart, one above another
    assert abs(np.mean(scale[:, 2]) - 0.1) < 1e-3  # centred on the points' height


def _pinhole(eye: np.ndarray, target: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N, 2) image-plane coordinates (right, up) / depth of points seen from eye towards target, z up."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    relative = points - eye
    return np.column_stack([relative @ right, relative @ up]) / (relative @ forward)[:, None]


def test_the_error_views_show_both_models_socket_clusters_clear_of_the_colour_scale(tmp_path, rng) -> None:
    """A socket validation on a real arm (MUKCa panda_4_clean front -> right): two held-out sockets 50 mm apart, the
    nominal model's predictions spread over several mm, the calibrated one's over 0.2 mm. The calibrated view's
    default camera framed one cluster out of the picture and put the other behind the scale's labels (the scale
    stood between the sockets, in front of them). Seen from each Errors view's default camera (read back from the
    blueprint; a pinhole of Rerun's 55 deg vertical field of view in a pane 0.45 as wide as tall, as the default
    window gives the two views side by side), every point is in the picture and left of the colour scale, clear of
    its labels (centred on its spheres, a fifth of the half-width wide); both views share one camera, so a
    millimetre on the screen is the same in both."""
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.recording import Recording, read_eyes

    sockets = np.array([[0.3984, -0.2293, 0.0177], [0.3987, -0.1794, 0.0179]])
    which = np.repeat([0, 1], 35)
    sets = {"nominal": sockets[which] + rng.normal(0, 4e-3, (70, 3)) * [1.0, 1.0, 0.4],
            "calibrated": sockets[which] + rng.normal(0, 1.5e-4, (70, 3))}
    errors = {k: np.linalg.norm(p - np.array([p[which == s].mean(0) for s in (0, 1)])[which], axis=1)
              for k, p in sets.items()}
    top = max(np.quantile(e, 0.99) for e in errors.values()) * 1e3
    recording = Recording(tmp_path / "sockets.rrd")
    for key, points in sets.items():
        recording.workspace_errors(key, points, errors[key], "its socket's mean point", top)
    recording.close()
    logged = {}
    for chunk in RrdReader(str(tmp_path / "sockets.rrd")).stream().to_chunks():
        if chunk.entity_path.startswith("/errors/") and not chunk.entity_path.endswith("histogram"):
            logged[chunk.entity_path.strip("/")] = np.array(chunk.to_record_batch().column("Points3D:positions")
                                                            .to_pylist()[0])
    eyes = read_eyes(tmp_path / "sockets.rrd")
    np.testing.assert_allclose(np.concatenate(eyes["errors/nominal"]), np.concatenate(eyes["errors/calibrated"]))
    half_height = np.tan(np.radians(55.0) / 2)
    half_width = 0.45 * half_height
    for key in sets:
        np.testing.assert_allclose(logged[f"errors/{key}/points"], sets[key])
        eye = eyes[f"errors/{key}"]
        points, scale = (_pinhole(*eye, logged[f"errors/{key}/{e}"]) for e in ("points", "colour_scale"))
        for seen in (points, scale):
            assert np.all(np.abs(seen) < [half_width, half_height]), key  # in the picture
        assert points[:, 0].max() < scale[:, 0].min() - 0.2 * half_width, key  # clear of the labels' left half


def test_the_error_views_show_one_colour_scale_in_one_place(tmp_path, rng) -> None:
    """The Errors views share one camera; each drew its colour scale as tall as its own model's points (67 mm beside
    the nominal predictions of a socket validation, 50 mm beside the calibrated ones) and beside them, so the same
    labels stood at different heights on the screen, as if a millimetre of the scale differed between the views.
    Both models' scales are one: the same spheres in the same place, colours and labels, and a point's colour is the
    scale's at its error in either view."""
    from spherecal.validation.viewer.recording import Recording
    from spherecal.validation.viewer.recording_shapes import colour_ramp

    sockets = np.array([[0.3984, -0.2293, 0.0177], [0.3987, -0.1794, 0.0179]])
    which = np.repeat([0, 1], 30)
    sets = {"nominal": sockets[which] + rng.normal(0, 6e-3, (60, 3)), "calibrated": sockets[which]
            + rng.normal(0, 1.5e-4, (60, 3))}
    errors = {"nominal": rng.uniform(0, 15e-3, 60), "calibrated": rng.uniform(0, 5e-4, 60)}
    recording = Recording(tmp_path / "e.rrd")
    for key, points in sets.items():
        recording.workspace_errors(key, points, errors[key], "its socket's mean point", 14.0)
    recording.close()
    scene = _scene(tmp_path / "e.rrd", "errors/")
    nominal, calibrated = scene["errors/nominal/colour_scale"], scene["errors/calibrated/colour_scale"]
    assert nominal["labels"][0] == "0.00 mm" and nominal["labels"][-1] == ">= 14.00 mm"
    for component in ("positions", "radii", "colors", "labels"):
        assert nominal[component] == calibrated[component], component
    scale = {label: colour for label, colour in zip(nominal["labels"], nominal["colors"], strict=True) if label}
    ramp = colour_ramp(np.array([0.0, 0.25, 0.5, 0.75, 1.0]))
    assert list(scale.values()) == [int.from_bytes(bytes([*c, 255]), "big") for c in ramp]  # RGBA as Rerun packs it
    for key in sets:
        expected = [int.from_bytes(bytes([*c, 255]), "big") for c in colour_ramp(errors[key] * 1e3 / 14.0)]
        assert scene[f"errors/{key}/points"]["colors"] == expected, key


#: A socket view as the default window shows two sockets stacked in its right panel (about 555 x 390 points), and a
#: label as Rerun draws it there (the picture check): 20 points high, 6.5 points per character wide, centred under
#: its point.
SOCKET_PANE, LABEL_HEIGHT, LABEL_CHARACTER = np.array([555.0, 390.0]), 20.0, 6.5


def test_the_socket_views_show_the_calibrated_cluster_and_every_label_apart(tmp_path, rng) -> None:
    """A held-out socket of a real arm (MUKCa panda_4_clean right_h0): the nominal model's predictions spread about
    10 mm, their mean 1 mm beside the calibrated one; the calibrated model's spread 0.24 mm. The calibrated points lay
    under its mean marker (a filled point three times as wide as the dots) and the two means' labels were drawn one
    over the other (a render). Seen from the socket view's default camera (read back from the blueprint; a pinhole of
    Rerun's 55 deg field of view in a pane of the default window), nothing wider than the dots is drawn over the
    calibrated cluster, every point, wire sphere (each model's spread around its mean) and label is in the picture,
    and no label covers a point, a sphere's outline or another label."""
    from spherecal.validation.viewer.recording import Recording, read_eyes

    centre = np.array([0.3984, -0.2293, 0.0177])
    nominal = centre + np.array([1e-3, 0.5e-3, 0.0]) + rng.normal(0, 7e-3, (37, 3)) * [1.0, 1.0, 0.3]
    calibrated = centre + rng.normal(0, 1.5e-4, (37, 3))
    recording = Recording(tmp_path / "s.rrd")
    recording.socket_spread("right_h0", nominal, calibrated)
    recording.close()
    scene = _scene(tmp_path / "s.rrd", "sockets/right_h0/")
    eye = read_eyes(tmp_path / "s.rrd")["sockets/right_h0"]
    unit = 2 * np.tan(np.radians(55.0) / 2) / SOCKET_PANE[1]  # picture per point of the screen
    half = 0.5 * SOCKET_PANE * unit
    dots = {k: _pinhole(*eye, np.array(scene[f"sockets/right_h0/{k}"]["positions"])) for k in ("nominal", "calibrated")}
    dot = abs(scene["sockets/right_h0/calibrated"]["radii"][0]) * unit
    low, high = dots["calibrated"].min(axis=0) - dot, dots["calibrated"].max(axis=0) + dot
    boxes, outlines = [], []  # (left, bottom, right, top) of each label; the wire spheres' outlines
    forward = (eye[1] - eye[0]) / np.linalg.norm(eye[1] - eye[0])
    across = np.cross(forward, [0.0, 0.0, 1.0]) / np.linalg.norm(np.cross(forward, [0.0, 0.0, 1.0]))
    rim = np.array([across, -across, np.cross(across, forward), -np.cross(across, forward)])
    for entity, row in scene.items():
        assert row.get("fill_mode", [None])[0] != 3, entity  # no solid ellipsoid (FillMode.Solid)
        for centre_mm, size in zip(row.get("centers", []), row.get("half_sizes", []), strict=True):
            outlines.append(_pinhole(*eye, np.array(centre_mm) + size[0] * rim))
        if "positions" not in row or entity.rsplit("/", 1)[1] in dots:
            continue
        seen = _pinhole(*eye, np.array(row["positions"]))
        radius = abs(row["radii"][0]) * unit
        if radius > dot:  # a marker wider than the dots, not over the calibrated cluster
            gap = np.linalg.norm(np.maximum(0.0, np.maximum(low - seen, seen - high)), axis=1)
            assert np.all(gap > radius), entity
        for (x, y), label in zip(seen, row.get("labels") or [], strict=False):
            lines = label.split("\n")  # a line of 20 points each, as wide as the longest
            width = max(map(len, lines)) * LABEL_CHARACTER * unit
            boxes.append((x - width / 2, y - radius - len(lines) * LABEL_HEIGHT * unit, x + width / 2, y - radius))
    assert len(boxes) == 2  # one per model
    assert len(outlines) == 2  # one per model
    every = np.vstack([*dots.values(), *outlines])
    for left, bottom, right, top in boxes:
        assert -half[0] < left and right < half[0] and -half[1] < bottom and top < half[1]  # in the picture
        inside = (every[:, 0] > left) & (every[:, 0] < right) & (every[:, 1] > bottom) & (every[:, 1] < top)
        assert not inside.any(), (left, bottom, right, top)  # no point under a label
    assert np.all(np.abs(every) < half)
    (l0, b0, r0, t0), (l1, b1, r1, t1) = boxes
    assert r0 < l1 or r1 < l0 or t0 < b1 or t1 < b0  # the labels apart


def test_a_viewer_that_cannot_start_is_one_line_and_leaves_nothing(tmp_path, monkeypatch) -> None:
    """--spawn without a Rerun viewer on PATH (or a display) ended in a traceback of 30 lines (a review: a message
    naming 'None'); it is one line naming --spawn, and a staged .rrd is removed."""
    import rerun

    from spherecal.correction.files.atomic import OutputError
    from spherecal.validation.viewer.recording import Recording

    def no_viewer(self, *args, **kwargs):
        raise RuntimeError("Failed to find Rerun Viewer executable in PATH.\n\n    You can install ...")

    monkeypatch.setattr(rerun.RecordingStream, "spawn", no_viewer)
    for path in (None, tmp_path / "v.rrd"):
        with pytest.raises(OutputError) as refused:
            Recording(path, spawn=True)
        assert str(refused.value).startswith("field '--spawn': cannot start a Rerun viewer: Failed to find Rerun "
                                             "Viewer")
        assert "\n" not in str(refused.value)
    assert list(tmp_path.iterdir()) == []


def test_the_robot_view_frames_everything_in_it(tmp_path, rng) -> None:
    """plan --samples on MUKCa panda_2_clean: 48 candidate sockets on a 0.5 x 0.9 m table beside the arm; the 3D
    view's camera stood 0.9 of the box's diagonal away, and the nearest rows of candidates ran out of the bottom of
    the picture. Seen from the view's default camera (a pinhole of Rerun's 55 deg vertical field of view in a pane
    0.95 as wide as tall, the robot view beside the result tabs), every fixture is in the picture."""
    from spherecal.validation.viewer.recording import Recording, read_eyes

    grid = np.array([[x, y, 0.016] for x in np.linspace(0.06, 0.55, 5) for y in np.linspace(-0.42, 0.48, 5)])
    recording = Recording(tmp_path / "w.rrd")
    recording.fixtures([f"G{k}" for k in range(len(grid))], grid)
    recording.text("plan", "a table", "Plan")
    recording.close()
    seen = _pinhole(*read_eyes(tmp_path / "w.rrd")["world"], np.vstack([grid, np.zeros((1, 3))]))
    half_height = np.tan(np.radians(55.0) / 2)
    assert np.all(np.abs(seen) < [0.95 * half_height, half_height])


def test_link_capsules_scale_with_the_arm_the_panda_keeping_40_mm(tmp_path, panda, truth, rng) -> None:
    """A review: the links were drawn 0.04 m thick on any arm (the Panda's size), a Kinova Gen3 lite's 0.835 m chain
    as thick as the Panda's 1.286 m one. The radius follows the chain's length, to the millimetre: the Panda and a
    calibration of it keep 0.04 m (their recordings unchanged), the Gen3 lite gets 0.04 x 0.835 / 1.286 = 0.026 m;
    the tool segment keeps its 12 mm."""
    from spherecal.correction import load_robot
    from spherecal.validation.viewer.recording import LINK_RADIUS, TOOL_RADIUS, Recording

    lite = load_robot("kinova_gen3_lite")
    expected = {"panda": 0.04, "truth": 0.04, "lite": round(0.04 * lite.chain_length / 1.286, 3)}
    assert LINK_RADIUS == 0.04 and expected["lite"] == 0.026
    for name, model in {"panda": panda, "truth": truth, "lite": lite}.items():
        q = model.random_configurations(5, rng)
        recording = Recording(tmp_path / f"{name}.rrd")
        recording.self_motion(model, np.arange(5) * 0.01, q)
        assert recording.close() == tmp_path / f"{name}.rrd"
        radii = _scene(tmp_path / f"{name}.rrd", "world/robot/arm")["world/robot/arm"]["radii"]
        assert len(radii) == model.n_joints + 1  # n links from the base, then the tool segment
        # Rerun stores radii as float32
        np.testing.assert_allclose(radii, [expected[name]] * model.n_joints + [TOOL_RADIUS], rtol=1e-6)
