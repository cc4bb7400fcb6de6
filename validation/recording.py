"""Rerun recordings of a calibration and its validation (a live viewer or an ``.rrd`` file).

Entity paths (documented in the README, checked by the tests):

==============================  ==============  ===========  =====================================
path                            archetype       timeline     rows
==============================  ==============  ===========  =====================================
``world/fixtures``              Points3D        static       1 (one point per fixture, labelled)
``world/robot/links``           LineStrips3D    ``time``     one per logged self-motion step
``world/robot/tool``            Points3D        ``time``     one per logged self-motion step
``world/samples``               Points3D        static       1 (true tool points of the samples)
``validation/measured``         Points3D        static       1 (mocap tool points, base frame)
``validation/nominal``          Points3D        static       1 (nominal-predicted tool points)
``validation/calibrated``       Points3D        static       1 (calibrated-predicted tool points)
``validation/errors/<model>``   Arrows3D        static       1 (predicted -> measured, per point)
``plots/error/<model>``         Scalars         ``sample``   one per validation configuration [mm]
``plots/residual``              Scalars         ``sample``   one per calibration sample [mm]
``coverage/q<i>``               BarChart        static       1 (histogram of joint i over its range)
==============================  ==============  ===========  =====================================

Rerun is imported only when a recording is made. Saving a recording with the Python SDK writes
no analytics file and no notice (a test checks it under an empty HOME); ``RERUN_ANALYTICS=0`` is set
unless the user set it. The ``rerun`` 0.41 viewer binary (``--spawn``, ``rerun file.rrd``) ignores
that variable: it stays quiet with ``CI=1`` in its environment or after ``rerun analytics disable``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, apply_transform, fit_rigid_transform, link_frames, tool_point
from spherecal.correction.atomic import OutputError

COLOURS = {
    "measured": (30, 30, 30),
    "nominal": (220, 60, 50),
    "calibrated": (40, 120, 220),
    "truth": (40, 170, 80),
}


def _rerun():
    os.environ.setdefault("RERUN_ANALYTICS", "0")
    import rerun  # Rerun: heavy, only when a recording is written

    return rerun


class Recording:
    """A Rerun recording stream that writes an ``.rrd`` file (atomically, on close) or feeds a viewer.

    Args:
        rrd: output file, or None.
        spawn: also start (or connect to) a live viewer.
        application_id: the Rerun application name.
    """

    def __init__(self, rrd: str | os.PathLike | None = None, spawn: bool = False, application_id: str = "spherecal"):
        if rrd is None and not spawn:
            raise ValueError("a recording needs an .rrd path or spawn=True")
        self.rr = _rerun()
        self.stream = self.rr.RecordingStream(application_id)
        self.path = None if rrd is None else Path(rrd)
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
            self.stream.spawn(connect=self.path is None)

    # --------------------------------------------------------------------- scene
    def fixtures(self, names: list[str], positions: np.ndarray) -> None:
        """The fixtures (ball centres) as labelled points, base frame [m]; positions (F, 3)."""
        self.stream.log(
            "world/fixtures",
            self.rr.Points3D(np.asarray(positions), labels=list(names), radii=0.012, colors=(250, 170, 20)),
            static=True,
        )

    def self_motion(self, model: RobotModel, t: np.ndarray, q: np.ndarray) -> None:
        """The robot's links (joint origins joined) and tool point per time step.

        Args:
            model: the robot drawn (the true one in a simulation).
            t: (T,) time stamps [s]; several fixtures may be concatenated (strictly increasing).
            q: (T, n) joint angles [rad].
        """
        origins = link_frames(model, q)[:, :, :3, 3]
        tips = tool_point(model, q)
        strips = np.concatenate([origins, tips[:, None]], axis=1)
        rr = self.rr
        times = rr.TimeColumn("time", duration=np.asarray(t, dtype=float))
        self.stream.send_columns(
            "world/robot/links",
            indexes=[times],
            columns=rr.LineStrips3D.columns(strips=strips[:, None]).partition([1] * len(strips)),
        )
        self.stream.send_columns("world/robot/tool", indexes=[times], columns=rr.Points3D.columns(positions=tips))

    def samples(self, points: np.ndarray, labels: list[str] | np.ndarray) -> None:
        """The recorded calibration samples' tool points (N, 3) [m], labelled by fixture."""
        self.stream.log(
            "world/samples",
            self.rr.Points3D(np.asarray(points), radii=0.002, class_ids=_class_ids(labels)),
            static=True,
        )

    # ---------------------------------------------------------------- validation
    def validation(self, measured: np.ndarray, predicted: dict[str, np.ndarray]) -> None:
        """Measured (mocap) tool points against each model's predictions (the paper's Fig. 8).

        The mocap points are brought into the base frame with the registration of the last model
        (the calibrated one, normally); each model's points are drawn as predicted, and its error
        vectors go from its prediction to the measurement registered onto that model.

        Args:
            measured: (N, 3) mocap tool points in the mocap frame [m].
            predicted: model name -> (N, 3) predicted tool points in the base frame [m].
        """
        measured = np.asarray(measured)
        for key, points in predicted.items():
            registered = apply_transform(fit_rigid_transform(measured, points), measured)
            self.stream.log(
                f"validation/{key}", self.rr.Points3D(points, radii=0.002, colors=_colour(key)), static=True
            )
            self.stream.log(
                f"validation/errors/{key}",
                self.rr.Arrows3D(origins=points, vectors=registered - points, colors=_colour(key)),
                static=True,
            )
        self.stream.log(
            "validation/measured", self.rr.Points3D(registered, radii=0.002, colors=COLOURS["measured"]), static=True
        )

    def series(self, path: str, values: np.ndarray) -> None:
        """A time series on the ``sample`` timeline (one row per value), e.g. errors in mm."""
        values = np.asarray(values, dtype=float)
        rr = self.rr
        self.stream.send_columns(
            path,
            indexes=[rr.TimeColumn("sample", sequence=np.arange(len(values)))],
            columns=rr.Scalars.columns(scalars=values),
        )

    def coverage(self, q: np.ndarray, lower: np.ndarray, upper: np.ndarray, bins: int = 36) -> None:
        """Per-joint histograms of the recorded angles over each joint's range (the paper's Fig. 5).

        Args:
            q: (N, n) joint angles [rad].
            lower, upper: (n,) joint limits [rad].
            bins: bins per joint.
        """
        for i in range(q.shape[1]):
            counts, edges = np.histogram(q[:, i], bins=bins, range=(lower[i], upper[i]))
            centres = np.rad2deg(0.5 * (edges[:-1] + edges[1:]))
            self.stream.log(
                f"coverage/q{i + 1}",
                self.rr.BarChart(counts, abscissa=centres, widths=np.full(bins, np.rad2deg(edges[1] - edges[0]))),
                static=True,
            )

    # -------------------------------------------------------------------- close
    def close(self) -> Path | None:
        """Flush, close the sink and move the ``.rrd`` into place; returns its path."""
        try:
            self.stream.flush()
            self.stream.disconnect()
            if self.path is None:
                return None
            os.replace(self._tmp, self.path)
        except Exception as error:  # Rerun raises its own types; the user sees one line
            self.abort()
            raise OutputError(f"{self.path}: cannot write the recording: {_first_line(error)}") from None
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


def _class_ids(labels) -> np.ndarray:
    _, ids = np.unique(np.asarray(labels), return_inverse=True)
    return ids.astype(np.uint16)


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
