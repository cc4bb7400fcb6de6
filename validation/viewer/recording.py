"""Rerun recordings of a calibration and its validation (a live viewer or an ``.rrd`` file).

Every recording carries a blueprint (:mod:`validation.blueprint`): a large 3D view of the robot and
the fixtures first, beside it one tab per kind of result that was logged. Entity paths (documented
in the README, checked by the tests):

===================================  =============  ==========  ======================================
path                                 archetype      timeline    what
===================================  =============  ==========  ======================================
``world/fixtures``                   Ellipsoids3D   static      a wire sphere per fixture, labels apart (Points3D)
``world/base_frame``                 Arrows3D       static      the base frame's x, y, z, 0.25 m (z out of the arm)
``world/robot/arm``                  Capsules3D     ``time``    one capsule per link, per logged step
``world/robot/tool``                 Points3D       ``time``    the tool point, per logged step
``world/samples``                    Points3D       static      calibration samples, scatter magnified
``errors/<model>/points``            Points3D       static      workspace tool points coloured by error
``errors/<model>/colour_scale``      Points3D       static      the colour scale, labelled in mm
``errors/<model>/heading``           Points3D       static      what the error is a distance to, labelled
``errors/<model>/histogram``         BarChart       static      error histogram [mm]
``residuals/<before|after>``         BarChart       static      calibration residual histogram [mm]
``parameters/<lengths|angles>/*``    2D shapes      static      change per parameter, +-1 std, truth
``coverage/<fixture>``               BarChart       static      share of each joint's range, one turn at most [%]
``sockets/<fixture>/<model>``        Points3D       static      predicted tool points, mm from their mean
``sockets/<fixture>/<model>_mean``   Ellipsoids3D   static      wire sphere: the mean point, spread [mm]
``sockets/<fixture>/legend``         Points3D       static      each model's spread, labelled
``tables/<name>``                    TextDocument   static      the printed tables
``tables/provenance``                TextDocument   static      command, versions, seed, inputs (SHA-256)
===================================  =============  ==========  ======================================

A recording of ``validate`` or ``demo`` also carries its provenance block as the recording property
``spherecal_provenance`` (JSON), the block its JSON report holds (:meth:`Recording.provenance`). Every command's
recording has the id of its run (:func:`recording_id`: from the block's seed, inputs and versions), the same for
two runs alike.

Histograms and bars are static, so they show whatever the timeline selector is on. Rerun is imported
only when a recording is made. Saving a recording with the Python SDK writes no analytics file and
no notice (a test checks it under an empty HOME); ``RERUN_ANALYTICS=0`` is set unless the user set
it. The ``rerun`` 0.41 viewer binary (``--spawn``, ``rerun file.rrd``) ignores that variable: it stays
quiet with ``CI=1`` in its environment or after ``rerun analytics disable``.
"""

from __future__ import annotations

import json
import os
import textwrap
import uuid
from pathlib import Path

import numpy as np

from spherecal.controller.exploration import joint_coverage
from spherecal.controller.reach import size_vs_panda
from spherecal.correction import RobotModel, link_frames, tool_point
from spherecal.correction.files.atomic import OutputError
from spherecal.correction.files.provenance import comment_block
from spherecal.correction.layout import ParamKind

from .blueprint import FIELD_OF_VIEW, TABS, build_blueprint, union_box, view_axes, world_eye_distance
from .recording_shapes import (
    BAR_HEIGHT,
    capsules,
    colour_ramp,
    covered_axis_height,
    histogram,
    magnification,
    parameter_bars,
)

COLOURS = {
    "measured": (30, 30, 30),
    "nominal": (220, 60, 50),
    "calibrated": (40, 120, 220),
    "truth": (40, 170, 80),
}
FIXTURE_COLOURS = [(250, 170, 20), (160, 80, 200), (20, 170, 170), (200, 90, 60), (90, 160, 40)]
#: Least height of a colour scale [m]: the points' largest extent when larger (a workspace spans metres, two sockets
#: on a plate 50 mm, one socket's predictions a few mm). The scale's place, its spheres and the room left for its
#: labels follow that height, so the view frames the points and the scale alike.
SCALE_HEIGHT = 0.01
#: Least and largest radius of a fixture's wire sphere in the 3D view [m]: 0.4 of the distance to the nearest other
#: fixture between them (MUKCa's plate holds its sockets 50 mm apart, a simulation's fixtures stand 0.25 m apart: at
#: 20 mm, plan --samples' default camera showed each socket's magnified samples as one dot).
FIXTURE_RADIUS = (0.02, 0.05)
#: Capsule radius of the Panda's links and of the tool segment [m]; another arm's links are scaled by its size
#: (:func:`link_radius`), the tool segment is not (a tool is as thick on any arm).
LINK_RADIUS, TOOL_RADIUS = 0.04, 0.012
#: Length of the base frame's arrows in the 3D view [m]: out of the base link's 40 mm capsule (0.1 m barely left it).
AXIS_LENGTH = 0.25
#: How far the base frame's z arrow reaches beyond the links that stand on that axis [m]
#: (:func:`.recording_shapes.covered_axis_height`): at 0.25 m it ran inside the Panda's first link (0.333 m), its head
#: hidden (a review).
AXIS_CLEARANCE = 0.1
#: Height of the main 3D view in the default window [points] (:data:`validation.viewer.blueprint.WORLD_ASPECT`), and a
#: label's row height, width per character and padding there [points] (Rerun's labels, measured on screenshots): how
#: much room a fixture's label takes in metres at the default camera (:func:`_label_places`).
WORLD_VIEW_HEIGHT, LABEL_ROW, LABEL_CHAR, LABEL_PAD = 920.0, 24.0, 7.5, 12.0


#: The namespace of the recording ids derived from a run (:func:`recording_id`): a UUID drawn once, fixed here.
RECORDING_NAMESPACE = uuid.UUID("d7b6b826-b8ae-4544-8bcf-5e7aae4e54ad")
#: The fields of a provenance block (``correction.files.provenance.provenance``) that name the run a recording is of.
RUN_FIELDS = ("seed", "inputs", "versions")


def link_radius(model: RobotModel) -> float:
    """The capsule radius [m] of ``model``'s links in the 3D view: :data:`LINK_RADIUS` (the Panda's, 0.04 m) scaled by
    the arm's size (:func:`controller.reach.size_vs_panda`, as :func:`controller.reach.base_radius` scales the base
    column), to the millimetre. The Panda (and a calibration of it, millimetres off) keeps 0.04 m; an iiwa14 gets
    0.037 m, a Kinova Gen3 lite 0.026 m: a fixed 0.04 m drew a small arm's links too thick for its size."""
    return round(LINK_RADIUS * size_vs_panda(model), 3)


def recording_id(application_id: str, run: dict) -> str:
    """The Rerun recording id of a run: a name-based UUID (version 5, :data:`RECORDING_NAMESPACE`) of the application
    and of the run's seed, inputs (options as given, input files by their SHA-256) and package versions, from its
    provenance block (:data:`RUN_FIELDS`). Two runs alike get one id; the block's creation time, command line (a
    program path) and workers (process ids) play no part. Rerun's default, a random id per process, made two
    otherwise identical runs' recordings differ (a review).

    Args:
        application_id: the recording's Rerun application name.
        run: the run's provenance block.
    """
    key = {"application_id": application_id, **{name: run.get(name) for name in RUN_FIELDS}}
    return str(uuid.uuid5(RECORDING_NAMESPACE, json.dumps(key, sort_keys=True, default=str)))


def _rerun():
    os.environ.setdefault("RERUN_ANALYTICS", "0")
    import rerun  # Rerun: heavy, only when a recording is written

    return rerun


def spawn_viewer(instead: str) -> None:
    """Start the Rerun viewer now, by rerun's own spawn (the ``rerun`` executable on PATH, unless a viewer already
    listens on its port), so that a run with ``--spawn`` is refused before its work, not after it; a recording that
    spawns later connects to it. ``instead``: the remedy the refusal offers.

    Raises:
        OutputError: no viewer could be started, one line as ``field '--spawn': cannot start a Rerun viewer: ...``.
    """
    _spawn(_rerun().RecordingStream("spherecal"), False, instead)


def _spawn(stream, connect: bool, instead: str) -> None:
    """``stream.spawn(connect=connect)``; a viewer that cannot start (none on PATH, no display) is one line naming
    ``--spawn`` and ``instead``, the remedy.

    Raises:
        OutputError: the viewer could not be started.
    """
    try:
        stream.spawn(connect=connect)
    except Exception as error:  # Rerun raises its own types; the user sees one line
        raise OutputError(f"field '--spawn': cannot start a Rerun viewer: {_first_line(error)} ({instead})") from None


class Recording:
    """A Rerun recording stream that writes an ``.rrd`` file (atomically, on close) or feeds a viewer.

    What is logged is remembered (``self.contents``) so that :meth:`close` sends a blueprint with a
    view for each of them, in the same layout for every command.

    Args:
        rrd: output file, or None.
        spawn: also start (or connect to) a live viewer.
        application_id: the Rerun application name.
        title: name of the main 3D view.
        run: the provenance block of the run recorded: its recording id is derived from it (:func:`recording_id`),
            the same for two runs alike; None: a random id of its own.
    """

    def __init__(
        self,
        rrd: str | os.PathLike | None = None,
        spawn: bool = False,
        application_id: str = "spherecal",
        title: str = "Robot and fixtures",
        run: dict | None = None,
    ):
        if rrd is None and not spawn:
            raise ValueError("a recording needs an .rrd path or spawn=True")
        self.rr = _rerun()
        # Rerun's default id is one per process: two recordings of one process shared it, two runs alike differed
        identity = recording_id(application_id, run) if run is not None else str(uuid.uuid4())
        self.stream = self.rr.RecordingStream(application_id, recording_id=identity)
        self.application_id = application_id
        self.path = None if rrd is None else Path(rrd)
        self.contents: dict[str, dict[str, str]] = {"world": {}}
        self.title = title
        self.bounds: dict[str, np.ndarray] = {}
        self._scales: dict[str, tuple[np.ndarray, float]] = {}  # model -> its Errors points [m], scale top [mm]
        self._against: dict[str, str] = {}  # model -> what its Errors are distances to
        self._fixture_colours: dict[str, tuple[int, int, int]] = {}  # fixture name -> its colour in every view
        self._fixture_places: dict[str, np.ndarray] = {}  # fixture name -> its centre in the 3D view [m]
        self._sample_note = ""  # what the fixtures' spheres stand for when samples() magnified the samples
        self._fixture_radius = FIXTURE_RADIUS[0]  # of the fixtures' wire spheres [m]
        self._fixture_scene = None  # names, centres [m] and colours of the fixtures, logged on closing
        self._axis_covered = 0.0  # how high the arm's links stand on the base's z axis [m] (covered_axis_height)
        self._tmp = None
        if self.path is not None:
            self._tmp = self.path.with_name(f".{self.path.name}.tmp")
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self.stream.save(self._tmp)
            except Exception as error:  # Rerun raises its own types; the user sees one line
                self.abort()
                raise OutputError(f"{self.path}: cannot write the recording: {_first_line(error)}") from None
        if spawn:
            try:
                _spawn(self.stream, self.path is None, "or write the recording with --rrd FILE and open it elsewhere")
            except OutputError:  # nothing left behind
                self.abort()
                raise

    def _note(self, section: str, key: str, name: str) -> None:
        self.contents.setdefault(section, {})[key] = name

    def extend_bounds(self, origin: str, points: np.ndarray) -> None:
        """Grow the (2, 3) bounding box of a 3D view's contents (its camera is aimed at it) [m]."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        box = np.array([points.min(axis=0), points.max(axis=0)])
        self.bounds[origin] = union_box([box, self.bounds[origin]]) if origin in self.bounds else box

    # --------------------------------------------------------------------- scene
    def fixtures(self, names: list[str], positions: np.ndarray) -> None:
        """The fixtures (ball centres) as labelled wire spheres, base frame [m]; positions (F, 3). Their radius is 0.4
        of the distance between the nearest two, within :data:`FIXTURE_RADIUS`. Solid, they hid what stood inside
        them: the samples (:meth:`samples`), the tool point of the self-motion, a plan's chosen candidate and its
        colour."""
        positions = np.asarray(positions, dtype=float).reshape(-1, 3)
        apart = np.linalg.norm(positions[:, None] - positions[None], axis=-1) + np.diag(np.full(len(positions), np.inf))
        nearest = float(apart.min()) if len(positions) > 1 else np.inf
        self._fixture_radius = float(np.clip(0.4 * nearest, *FIXTURE_RADIUS))
        colours = [FIXTURE_COLOURS[k % len(FIXTURE_COLOURS)] for k in range(len(positions))]
        for name, colour, place in zip(names, colours, positions, strict=True):
            for key in (name, name.split(" (")[0]):  # 'P1 (fit)' is fixture P1
                self._fixture_colours.setdefault(key, colour)
                self._fixture_places.setdefault(key, place)
        self.extend_bounds("world", positions)
        self._fixture_scene = (list(names), positions, colours)  # logged on closing, its labels apart (_log_fixtures)

    def _log_fixtures(self) -> None:
        """The fixtures' wire spheres (:meth:`fixtures`) and their labels, one row of ``world/fixtures``: the labels
        are points of their own (Rerun puts a point's label under it), each under its fixture's centre unless it
        would cover another's label at the default camera, then moved up on the screen by a label's height until
        it does not (:func:`_label_places`). Centred on their spheres, the labels of a plate's sockets 50 mm apart
        were drawn one over the other ('back_left_h0' over 'back_left_h1' on MUKCa panda_2_clean)."""
        if self._fixture_scene is None:
            return
        names, positions, colours = self._fixture_scene
        tabs = any(self.contents.get(section) for section in TABS)
        places = _label_places(positions, names, world_eye_distance(self.bounds["world"], tabs))
        rr = self.rr
        self.stream.log(
            "world/fixtures",
            rr.Ellipsoids3D(
                centers=positions, half_sizes=np.full((len(positions), 3), self._fixture_radius), colors=colours,
                labels=names, show_labels=False, fill_mode="majorwireframe", line_radii=rr.Radius.ui_points(1.0),
            ),
            rr.Points3D(places, radii=rr.Radius.ui_points(0.5), colors=colours, labels=names, show_labels=True),
            static=True,
        )

    def self_motion(self, model: RobotModel, t: np.ndarray, q: np.ndarray) -> None:
        """The robot as a solid arm (a capsule along every link) and its tool point, animated on ``time``.

        Args:
            model: the robot drawn (the true one in a simulation, the calibrated one on real data).
            t: (T,) time stamps [s]; several fixtures may be concatenated (strictly increasing).
            q: (T, n) joint angles [rad].
        """
        origins = link_frames(model, q)[:, :, :3, 3]
        tips = tool_point(model, q)
        self.extend_bounds("world", origins)
        radius = link_radius(model)
        self._axis_covered = max(self._axis_covered, covered_axis_height(origins, radius))
        lengths, translations, quaternions = capsules(np.concatenate([origins, tips[:, None]], axis=1))
        segments = lengths.shape[1]
        rr = self.rr
        radii = np.full(segments, radius)
        radii[-1] = TOOL_RADIUS
        colours = np.tile(np.array([205, 205, 210], dtype=np.uint8), (segments, 1))
        colours[-1] = (250, 140, 30)
        self.stream.log(
            "world/robot/arm", rr.Capsules3D.from_fields(radii=radii, colors=colours, fill_mode="solid"), static=True
        )
        times = rr.TimeColumn("time", duration=np.asarray(t, dtype=float))
        columns = rr.Capsules3D.columns(
            lengths=lengths.reshape(-1),
            translations=translations.reshape(-1, 3),
            quaternions=quaternions.reshape(-1, 4),
        )
        self.stream.send_columns("world/robot/arm", indexes=[times], columns=columns.partition([segments] * len(t)))
        self.stream.log("world/robot/tool", rr.Points3D.from_fields(radii=0.008, colors=(250, 140, 30)), static=True)
        self.stream.send_columns("world/robot/tool", indexes=[times], columns=rr.Points3D.columns(positions=tips))

    def fixture_colour(self, name: str, k: int) -> tuple[int, int, int]:
        """The colour of fixture ``name`` in the 3D view (:meth:`fixtures`), else the ``k``-th of the palette: a
        fixture's samples and coverage bars are drawn in its sphere's colour."""
        return self._fixture_colours.get(name) or FIXTURE_COLOURS[k % len(FIXTURE_COLOURS)]

    def samples(self, points: np.ndarray, labels: list[str] | np.ndarray) -> None:
        """The recorded calibration samples' tool points (N, 3) [m], coloured by fixture, their scatter magnified.

        Each sample is drawn at its fixture's centre (:meth:`fixtures`, else the mean of its samples) plus its offset
        from it times one gain for all fixtures (:func:`.recording_shapes.magnification`): the 95th percentile of the
        offsets fills the fixture's wire sphere, whose radius then stands for a round figure, named in the main 3D
        view's title (``samples x40 about each fixture's centre, its sphere 0.5 mm``). Drawn where they are, tenths of a
        millimetre apart, the samples made one dot hidden inside the fixture's 20 mm sphere (a reviewer's finding).
        The dots are of one size on the screen.
        """
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        names, ids = np.unique(np.asarray(labels), return_inverse=True)
        ids = np.ravel(ids)
        palette = [self.fixture_colour(str(name), k) for k, name in enumerate(names)]
        colours = np.array([palette[i] for i in ids], dtype=np.uint8).reshape(-1, 3)
        centres = np.array([self._fixture_places.get(str(name), points[ids == k].mean(axis=0))
                            for k, name in enumerate(names)]).reshape(-1, 3)
        offsets = points - centres[ids]
        gain, reach = magnification(offsets, self._fixture_radius)
        shown = centres[ids] + gain * offsets
        self.stream.log("world/samples", self.rr.Points3D(shown, radii=self.rr.Radius.ui_points(2.0), colors=colours),
                        static=True)
        self.extend_bounds("world", shown)
        if gain > 1:  # in the main view's title (:meth:`close`)
            self._sample_note = f"samples x{gain:.3g} about each fixture's centre, its sphere {reach * 1e3:.3g} mm"

    def colour_legend(self, name: str, points: np.ndarray, colours: np.ndarray, labels: list[str],
                      heading: str) -> None:
        """A colour scale in the 3D view of the robot (``world/<name>``): spheres in ``colours`` (S, 3) from bottom
        to top, labelled ``labels`` (S,; empty strings for none), beside points (N, 3) [m] as the default camera sees
        them (:func:`_scale_beside`), with ``heading`` above it (what the colours mean). Rerun has no colour bar:
        a plan's candidates were coloured and nothing said what a colour meant (a reviewer's finding)."""
        colours = np.asarray(colours, dtype=np.uint8).reshape(-1, 3)
        steps = np.linspace(0.0, 1.0, len(colours))
        scale, height = _scale_beside(np.asarray(points, dtype=float).reshape(-1, 3), steps)
        right, up, _ = view_axes()
        top = scale[-1] + 0.08 * height * (1 + heading.count("\n")) * up  # its label centred on it
        rr = self.rr
        self.stream.log(f"world/{name}", rr.Points3D(scale, radii=min(0.02, 0.5 * height / max(len(steps), 1)),
                                                      colors=colours, labels=list(labels), show_labels=True),
                        static=True)
        self.stream.log(f"world/{name}_heading", rr.Points3D(top[None], radii=rr.Radius.ui_points(0.5),
                                                              colors=(235, 235, 235), labels=[heading],
                                                              show_labels=True), static=True)
        self.extend_bounds("world", np.vstack([scale, top, scale[-1] + 0.3 * height * right]))

    # ---------------------------------------------------------------- results
    def workspace_errors(
        self, key: str, points: np.ndarray, errors: np.ndarray, against: str, top: float | None = None
    ) -> None:
        """One model's tool points coloured by their error, a histogram, and on closing a labelled colour scale
        (:meth:`_colour_scales`: one place and size for every model's).

        Args:
            key: model name (``"nominal"``, ``"calibrated"``).
            points: (N, 3) the model's predicted tool points, base frame [m].
            errors: (N,) their errors after registration [m].
            against: what the errors are measured against (``"the mocap"``), for the table.
            top: error at the top of the colour scale [mm] (give every model the same one to compare
                them side by side); default the 99th percentile of ``errors``.
        """
        points, mm = np.asarray(points, dtype=float), np.asarray(errors, dtype=float) * 1e3
        if top is None:
            top = float(np.quantile(mm, 0.99)) if mm.size else 1.0
        rr = self.rr
        dots = rr.Points3D(points, radii=rr.Radius.ui_points(2.5), colors=colour_ramp(mm / top))
        self.stream.log(f"errors/{key}/points", dots, static=True)
        counts, left, width = histogram(mm)
        chart = rr.BarChart(counts, abscissa=left, widths=width, color=_colour(key))
        self.stream.log(f"errors/{key}/histogram", chart, static=True)
        self.extend_bounds(f"errors/{key}", points)
        self._scales[key] = (points, top)  # the colour scales, on closing: one beside every model's points
        self._against[key] = against
        # short enough for the view's title bar: 'Nominal: error, mean 4.798 mm over 5000 points' was cut to
        # 'Nominal: error, mean 4.798 m' (metres?) and the calibrated one lost its unit; what the error is a
        # distance to, and over how many points, is the heading in the view (_colour_scales)
        self._note("errors", key, f"{key.capitalize()}: mean {mm.mean():.3f} mm")

    def _colour_scales(self) -> None:
        """Each Errors view's colour scale, labelled in mm up to its model's ``top``, all of them in one place and of
        one size: beside the union of the models' points (:func:`_scale_beside`). The views share one camera; a scale
        as tall as its own model's points stood elsewhere and taller in one view than in the other with the same
        labels, as if a millimetre of it differed between the views."""
        if not self._scales:
            return
        steps = np.linspace(0.0, 1.0, 21)
        scale, height = _scale_beside(np.vstack([points for points, _ in self._scales.values()]), steps)
        label_room = scale[-1] + 0.25 * height * view_axes()[0]  # the labels, centred on the spheres
        heading = _heading_place(np.vstack([points for points, _ in self._scales.values()] + [scale]), height)
        for key, (points, top) in self._scales.items():
            labels = [f"{s * top:.2f} mm" if k % 5 == 0 else "" for k, s in enumerate(steps)]
            labels[-1] = f">= {top:.2f} mm"
            self.stream.log(
                f"errors/{key}/colour_scale",
                self.rr.Points3D(scale, radii=min(0.03, 0.02 * height), colors=colour_ramp(steps), labels=labels,
                                 show_labels=True),
                static=True,
            )
            # in lines that fit the narrow view (a label is one line unless broken)
            text = "\n".join(textwrap.wrap(f"{key}: distance [mm] to {self._against[key]}, {len(points)} points", 32))
            self.stream.log(
                f"errors/{key}/heading",
                self.rr.Points3D(heading, radii=self.rr.Radius.ui_points(0.5), colors=_colour(key), labels=[text],
                                 show_labels=True),
                static=True,
            )
            self.extend_bounds(f"errors/{key}", np.vstack([scale, label_room, heading]))

    def _base_frame(self) -> None:
        """The robot's base frame in the 3D view (``world/base_frame``): arrows of :data:`AXIS_LENGTH` along x, y, z
        (red, green, blue), labelled. Without them nothing in the view said which way x was or how long a metre was,
        so a fixture centre printed by calibrate ('centre P1 [m]: [0.4998 -0.2504 0.4992]') could not be found.
        The z arrow reaches :data:`AXIS_CLEARANCE` beyond the links standing on that axis (a round length, labelled
        when it is not x's): inside the Panda's first link, 0.333 m high, a 0.25 m arrow was hidden."""
        if "world" not in self.bounds:
            return
        up = max(AXIS_LENGTH, np.ceil((self._axis_covered + AXIS_CLEARANCE) / 0.05) * 0.05)  # to 50 mm
        axes = np.diag([AXIS_LENGTH, AXIS_LENGTH, up])
        self.stream.log(
            "world/base_frame",
            self.rr.Arrows3D(vectors=axes, origins=np.zeros((3, 3)), radii=0.004, show_labels=True,
                             colors=[(230, 70, 70), (70, 200, 90), (80, 130, 240)],
                             labels=[f"x ({AXIS_LENGTH * 1e3:.0f} mm)", "y",
                                     "z" if up == AXIS_LENGTH else f"z ({up * 1e3:.0f} mm)"]),
            static=True,
        )
        self.extend_bounds("world", np.vstack([np.zeros(3), axes]))

    def residuals(self, before: np.ndarray, after: np.ndarray) -> None:
        """Histograms of the calibration residuals (N,) [m] before and after calibration."""
        for key, values, model in (("before", before, "nominal"), ("after", after, "calibrated")):
            mm = np.asarray(values, dtype=float) * 1e3
            counts, left, width = histogram(mm)
            chart = self.rr.BarChart(counts, abscissa=left, widths=width, color=_colour(model))
            self.stream.log(f"residuals/{key}", chart, static=True)
            rms = float(np.sqrt(np.mean(mm**2)))
            # the bars run from 0 to the largest residual: the axis may label 0 alone (before: 0 to 13 mm)
            top = float(mm.max()) if mm.size else 0.0
            self._note("residuals", key, f"Residuals {key} calibration [mm]: rms {rms:.3f} mm, bars 0 to {top:.3g} mm")

    def parameter_changes(
        self,
        names: list[str],
        kinds: list[ParamKind],
        change: np.ndarray,
        std: np.ndarray,
        truth: np.ndarray | None = None,
    ) -> None:
        """Bars of the identified parameters' changes (calibrated minus nominal) with +-1 std whiskers.

        Each parameter kind gets a panel in its display unit from the parameter layout (lengths mm,
        angles deg, compliances urad/Nm); the bar labels carry the values. With ``truth`` (true minus
        nominal, simulation) a black dot marks where each bar should end.

        Args:
            names: (P,) parameter names.
            kinds: (P,) their :class:`~spherecal.correction.layout.ParamKind`.
            change, std: (P,) in each kind's unit [m, rad, rad/Nm].
            truth: (P,) likewise, or None.
        """
        rr = self.rr
        for group, shapes in parameter_bars(names, kinds, change, std, truth).items():
            base = f"parameters/{group}"
            white = (235, 235, 235)
            log = self.stream.log
            log(f"{base}/bars", rr.Boxes2D(mins=shapes["mins"], sizes=shapes["sizes"], colors=shapes["colours"]),
                static=True)
            log(f"{base}/names", rr.Points2D(shapes["names"], radii=0.01, colors=white, labels=shapes["labels"],
                                             show_labels=True), static=True)
            log(f"{base}/std", rr.LineStrips2D(shapes["whiskers"], colors=white, radii=0.03), static=True)
            log(f"{base}/zero", rr.LineStrips2D([shapes["zero"]], colors=(140, 140, 140), radii=0.01), static=True)
            log(f"{base}/scale", rr.LineStrips2D([shapes["scale"]], colors=white, radii=0.04,
                                                 labels=[shapes["scale_label"]], show_labels=True), static=True)
            if "truth" in shapes:
                log(f"{base}/truth", rr.Points2D(shapes["truth"], radii=0.12, colors=white), static=True)
            unit = shapes["unit"]
            what = ", white dot = true change" if "truth" in shapes else ""
            self._note("parameters", group, f"{group.capitalize()} [{unit}]: change, +-1 std{what}")
            top = BAR_HEIGHT + 1.2
            self.bounds[base] = np.array([[-3.2, -top, 0.0], [len(shapes["labels"]) + 0.2, top, 0.0]])

    def coverage(self, per_fixture: dict[str, np.ndarray], lower: np.ndarray, upper: np.ndarray) -> None:
        """Share of each joint's range visited at each fixture (bars q1..qn, percent; the paper's Fig. 5).

        A joint whose range is longer than one turn (a UR's +-2 pi) is measured against one turn, all the
        kinematics can tell apart: a full turn of it reads 100 %
        (:func:`spherecal.controller.exploration.joint_coverage`).

        Args:
            per_fixture: fixture name -> (K, n) joint angles [rad] recorded there.
            lower, upper: (n,) joint limits [rad].
        """
        for k, (name, q) in enumerate(per_fixture.items()):
            share = 100 * joint_coverage(q, lower, upper)
            chart = self.rr.BarChart(share, abscissa=np.arange(share.size) + 0.6, widths=np.full(share.size, 0.8),
                                     color=self.fixture_colour(name, k))  # its sphere's colour in the 3D view
            self.stream.log(f"coverage/{name}", chart, static=True)
            # the fixture's name first: in a grid of 14 the title bar showed 'Joint cover' of every view
            self._note("coverage", name, f"{name}: joint coverage, % of each joint's range, a turn at most "
                                         f"(q1..q{share.size}), lowest {share.min():.0f} %")

    def socket_spread(self, fixture: str, nominal: np.ndarray, calibrated: np.ndarray) -> None:
        """A held-out socket: the tool points each model predicts there, in mm around that model's own mean.

        A socket-only validation has no measured position: a good model puts every configuration's
        tool point at one point, so the spread of the predictions is its error. The points are drawn
        in a view of their own, each model's in millimetres from its own mean point, all of one size, so the two
        clouds share a centre: a wire sphere as wide as each model's spread (the mean distance from it, the socket
        table's figure). A legend names the socket and each model's spread in its colour, the calibrated one above the
        points and the nominal one below them as the default camera sees them (:func:`_legend_places`), with how far
        apart the two models put the socket's mean point (no error of either: its true place is not known). A filled
        marker at each mean hid the calibrated points (a few tenths of a mm beside several mm) and put the two labels
        one over the other; drawn around the calibrated mean, the nominal cloud stood where the nominal model puts the
        socket, 7 to 13 mm away on MUKCa panda_2_clean, and the calibrated cluster outside it, as if that distance
        were the error compared.

        Args:
            fixture: the socket's name (entity ``sockets/<fixture>``).
            nominal, calibrated: (N, 3) tool points predicted by each model at that socket [m].
        """
        sets = {"nominal": np.asarray(nominal, dtype=float), "calibrated": np.asarray(calibrated, dtype=float)}
        for key, points in sets.items():
            if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
                raise ValueError(f"socket {fixture}: {key} points must have shape (N, 3), got {points.shape}")
        apart = float(np.linalg.norm(sets["nominal"].mean(axis=0) - sets["calibrated"].mean(axis=0))) * 1e3
        rr, labels, drawn = self.rr, {}, []
        right, up, _ = view_axes()
        for key, points in sets.items():
            mm = (points - points.mean(axis=0)) * 1e3
            mean = np.zeros(3)
            spread = float(np.mean(np.linalg.norm(mm - mean, axis=1)))  # the socket table's figure
            self.stream.log(f"sockets/{fixture}/{key}", rr.Points3D(mm, radii=rr.Radius.ui_points(2.0),
                                                                     colors=_colour(key)), static=True)
            self.stream.log(f"sockets/{fixture}/{key}_mean",
                            rr.Ellipsoids3D(centers=mean[None], radii=[spread], colors=_colour(key),
                                            line_radii=rr.Radius.ui_points(0.75), fill_mode="majorwireframe"),
                            static=True)
            drawn += [mm, mean + spread * np.array([right, -right, up, -up])]  # the sphere's outline on the screen
            labels[key] = f"{key}: spread {spread:.3f} mm"
        labels["calibrated"] = f"{fixture}\n{labels['calibrated']}"  # the title bar shows its first 10 characters
        labels["nominal"] += f"\nmeans {apart:.2f} mm apart"
        drawn = np.vstack(drawn)
        places, room = _legend_places(drawn, lines=(2, 2))
        self.stream.log(
            f"sockets/{fixture}/legend",
            rr.Points3D(places, radii=rr.Radius.ui_points(0.5), colors=[_colour("calibrated"), _colour("nominal")],
                        labels=[labels["calibrated"], labels["nominal"]], show_labels=True),
            static=True,
        )
        self.extend_bounds(f"sockets/{fixture}", np.vstack([drawn, places, room]))
        self._note("sockets", fixture, f"{fixture}: socket spread [mm]")  # its name first: the title bar is narrow

    def provenance(self, block: dict) -> None:
        """The provenance block (:func:`correction.files.provenance.provenance`: command, versions, seed, inputs with
        their SHA-256) as a text panel (``tables/provenance``) and as the recording property ``spherecal_provenance``
        (JSON), as every other output of the command records it."""
        self.text("provenance", comment_block(block), "Provenance")
        self.stream.send_property("spherecal_provenance", self.rr.AnyValues(provenance=json.dumps(block)))

    def text(self, name: str, text: str, title: str) -> None:
        """A printed table as a text panel (``tables/<name>``)."""
        # plain text, in a monospace font and unwrapped (the view's format: validation.viewer.blueprint): as a
        # Markdown code block the view wrapped every line longer than its width, and a table's columns ran into the
        # next row ('std max' of the exact tool point under 'random workspace')
        document = self.rr.TextDocument(text, media_type=self.rr.MediaType.TEXT)
        self.stream.log(f"tables/{name}", document, static=True)
        self._note("tables", name, title)

    # -------------------------------------------------------------------- close
    def close(self) -> Path | None:
        """Log the Errors views' colour scales, send the blueprint, flush, close the sink and move the
        ``.rrd`` into place; returns its path.

        Raises:
            OutputError: Rerun could not write the file (one line); nothing is left behind.
        """
        try:
            self._colour_scales()
            self._base_frame()
            self._log_fixtures()  # after everything that frames the view: its labels follow the default camera
            # what the fixtures' spheres stand for when samples() magnified the samples, in the main view's title: in
            # the first fixture's label it covered the next socket's label, a plate's sockets centimetres apart
            title = f"{self.title}; {self._sample_note}" if self._sample_note else self.title
            blueprint = build_blueprint(self.contents, title, self.bounds)
            self.stream.send_blueprint(blueprint, make_active=True, make_default=True)
            bounds = {k: v.tolist() for k, v in self.bounds.items()}
            layout = {"contents": self.contents, "title": title, "bounds": bounds}
            layout["application_id"] = self.application_id
            self.stream.send_property("spherecal_layout", self.rr.AnyValues(layout=json.dumps(layout)))
            self.stream.flush()
            self.stream.disconnect()
            if self.path is None:
                return None
            os.replace(self._tmp, self.path)
        except Exception as error:  # Rerun raises its own types; the user sees one line
            self.abort()
            where = (f"{self.path}: cannot write the recording" if self.path is not None else
                     "field '--spawn': cannot stream the recording to a Rerun viewer (no display? write it with --rrd "
                     "FILE)")
            raise OutputError(f"{where}: {_first_line(error)}") from None
        return self.path

    def abort(self) -> None:
        """Drop the recording: no file is left behind."""
        try:
            self.stream.disconnect()
        finally:
            if self._tmp is not None:
                self._tmp.unlink(missing_ok=True)


def _first_line(error: BaseException) -> str:
    text = str(getattr(error, "strerror", None) or error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def _scale_beside(points: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, float]:
    """(S, 3) places of a colour scale's spheres at ``steps`` (S,) of its height, and that height [m], beside
    points (N, 3) [m] as the default camera sees them (:func:`validation.blueprint.view_axes`).

    The scale is as tall as the points' largest extent (at least :data:`SCALE_HEIGHT`): sockets on a flat plate span
    millimetres in z, and a scale that tall stacked its spheres into one ball with every label on top of the others.
    It stands right of the points on the screen, 0.4 of its height beyond them (room for its labels, centred
    on its spheres), as near the eye as the nearest point (perspective moves it out, not in), and centred on their
    height when they are flatter than it. Placed beyond the points' largest x at their mean y, it stood between two
    sockets and in front of them: the calibrated model's clusters hid behind its labels or fell out of the picture.
    """
    low, high = points.min(axis=0), points.max(axis=0)
    height = max(float(np.max(high - low)), SCALE_HEIGHT)
    bottom = 0.5 * (low[2] + high[2]) - 0.5 * height if high[2] - low[2] < height else low[2]
    right = view_axes()[0]
    near = np.cross((0.0, 0.0, 1.0), right)  # horizontal, towards the eye
    place = (np.max(points @ right) + 0.4 * height) * right + np.max(points @ near) * near
    return np.column_stack([np.full((len(steps), 2), place[:2]), bottom + steps * height]), height


def _heading_place(points: np.ndarray, height: float) -> np.ndarray:
    """(1, 3) place of a heading label above points (N, 3) [m] as the default camera sees them, centred across them:
    0.4 of ``height`` above their top on the screen (its label, three lines high, is centred on it: at 0.15 it
    covered the colour scale's top label and the highest points)."""
    right, up, _ = view_axes()
    middle = points.mean(axis=0)
    middle += (0.5 * (np.max(points @ right) + np.min(points @ right)) - middle @ right) * right
    return (middle + (np.max(points @ up) - middle @ up + 0.4 * height) * up)[None]


def _legend_places(points: np.ndarray, lines: tuple[int, int] = (1, 1)) -> tuple[np.ndarray, np.ndarray]:
    """(2, 3) places of two labelled points, above and below points (N, 3) as the default camera sees them
    (:func:`validation.blueprint.view_axes`), centred across them, and (2, 3) corners of the room their labels take
    (which Rerun centres under each point), in the points' unit; ``lines``: the lines of the upper and lower labels.

    The upper stands 0.3 of the points' largest extent on the screen per line of its label above them (its label
    hangs between it and the points), the lower just below them; labels at two nearby means were drawn one over the
    other.
    """
    right, up, _ = view_axes()
    size = max(float(np.ptp(points @ right)), float(np.ptp(points @ up)), 1e-9)
    middle = points.mean(axis=0)
    middle += (0.5 * (np.max(points @ right) + np.min(points @ right)) - middle @ right) * right
    places = np.array([middle + (np.max(points @ up) - middle @ up + 0.3 * lines[0] * size) * up,
                       middle + (np.min(points @ up) - middle @ up - 0.05 * size) * up])
    room = places[1] - 0.2 * lines[1] * size * up + np.outer([-0.6, 0.6], size * right)
    return places, room


def _label_places(positions: np.ndarray, names: list[str], distance: float) -> np.ndarray:
    """(F, 3) places [m] of the points that carry fixtures' labels (Rerun draws a label centred under its point) at
    fixture centres (F, 3) [m], seen by the main view's default camera from ``distance`` [m]
    (:func:`validation.viewer.blueprint.view_axes`): from the lowest on the screen up, each at its fixture's centre,
    or moved up the screen to one label's height above the highest label it would cover (the size of a label in
    metres from :data:`LABEL_ROW`, :data:`LABEL_CHAR` and :data:`LABEL_PAD` at that distance)."""
    positions = np.asarray(positions, dtype=float).reshape(-1, 3)
    right, up, _ = view_axes()
    metre = WORLD_VIEW_HEIGHT / (2 * distance * np.tan(FIELD_OF_VIEW / 2))  # points per metre at the look target
    row = LABEL_ROW / metre
    widths = np.array([(LABEL_CHAR * len(name) + LABEL_PAD) / metre for name in names])
    across, height = positions @ right, positions @ up
    levels, placed = height.copy(), []
    for i in np.argsort(height, kind="stable"):
        while True:
            covered = [levels[j] for j in placed if abs(across[i] - across[j]) < 0.5 * (widths[i] + widths[j])
                       and abs(levels[i] - levels[j]) < 0.999 * row]
            if not covered:
                break
            levels[i] = max(covered) + row
        placed.append(i)
    return positions + (levels - height)[:, None] * up


def _colour(key: str) -> tuple[int, int, int]:
    return COLOURS.get(key, (120, 120, 120))


def read_entity_rows(path: str | os.PathLike) -> dict[str, int]:
    """Rows per entity path of a saved recording (``/__properties`` left out), for tests and checks."""
    from rerun.chunk import RrdReader  # Rerun: heavy, only when a recording is written

    _rerun()
    counts: dict[str, int] = {}
    for chunk in RrdReader(str(path)).stream().to_chunks():
        entity = chunk.entity_path.lstrip("/")
        if entity.startswith("__"):
            continue
        counts[entity] = counts.get(entity, 0) + chunk.num_rows
    return counts


def _read_property(path: str | os.PathLike, name: str, field: str) -> dict:
    """The JSON value ``field`` of the recording property ``name`` of a saved recording, or {} if it has none."""
    from rerun.chunk import RrdReader  # Rerun: heavy, only when a recording is written

    _rerun()
    for chunk in RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path.endswith(name):
            batch = chunk.to_record_batch()
            column = next(n for n in batch.schema.names if n.endswith(field))
            return json.loads(batch.column(column).to_pylist()[0][0])
    return {}


def read_layout(path: str | os.PathLike) -> dict:
    """What a recording's blueprint was built from (``contents``, ``title``, ``bounds``,
    ``application_id``; see :func:`validation.blueprint.build_blueprint`), or {} if it has none."""
    return _read_property(path, "spherecal_layout", "layout")


def read_provenance(path: str | os.PathLike) -> dict:
    """The provenance block a saved recording carries (:meth:`Recording.provenance`), or {} if it has none."""
    return _read_property(path, "spherecal_provenance", "provenance")


def _blueprint_batches(path: str | os.PathLike):
    """The record batches of a saved recording's blueprint chunks, with their entity paths."""
    from rerun.chunk import RrdReader  # Rerun: heavy, only when a recording is written

    _rerun()
    reader = RrdReader(str(path))
    for store in reader.blueprints():
        for chunk in reader.stream(store=store).to_chunks():
            yield chunk.entity_path, chunk.to_record_batch()


def read_view_names(path: str | os.PathLike) -> list[str]:
    """Display names of the views in a saved recording's blueprint (empty when it has none)."""
    names = []
    for _, batch in _blueprint_batches(path):
        column = "ViewBlueprint:display_name"
        if column in batch.schema.names:
            names += [str(v[0]) for v in batch.column(column).to_pylist() if v]
    return names


def read_eyes(path: str | os.PathLike) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """View origin -> (eye position, look target) [m] of each 3D view's default camera in a saved recording's
    blueprint (:func:`validation.blueprint.camera`), for tests and checks."""
    origins, eyes = {}, {}
    for entity, batch in _blueprint_batches(path):
        names = batch.schema.names
        if "ViewBlueprint:space_origin" in names:
            origins[entity] = str(batch.column("ViewBlueprint:space_origin").to_pylist()[0][0])
        if "EyeControls3D:position" in names:
            position, target = (np.array(batch.column(f"EyeControls3D:{n}").to_pylist()[0][0], dtype=float)
                                for n in ("position", "look_target"))
            eyes[entity.rsplit("/", 1)[0]] = (position, target)
    return {origins[view]: eye for view, eye in eyes.items() if view in origins}
