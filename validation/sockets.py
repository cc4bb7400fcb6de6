"""Validation without motion capture: how well each model keeps a socket's tool points together.

A ball held in a socket does not move, so a correct model predicts the same tool point for every
configuration recorded there. Per fixture, the *spread* is the mean distance of the predicted tool
points from their mean (MUKCa's "MAE"; their "test MAE" on placements not used for fitting); per
known distance, the *distance error* is the distance between the two fixtures' mean points minus the
known one. Both are computed for every model (nominal, calibrated) on the same samples.

A fixture whose samples the calibrated file says it was trained on (``calibration.trained_on``: digests
of the joint angles, :mod:`spherecal.identification.training`) was used in the fit, whatever it is
called: it is marked, and the held-out summary leaves it out. A spread from fewer than
:data:`MIN_DISTINCT` distinct configurations is not measurable (None, printed as such), not zero.
Beside each held-out socket's measured spread, the spread the calibration predicts there
(:class:`spherecal.identification.prediction.HeldOut`): the parameter error from the covariance the file
records (its samples' part at the socket's noise, the prior's at the arm's deviations) through the recorded
configurations, the socket's own noise (the white part of the training residual by maximum likelihood, at most the
declared noise) and a fresh draw of the arm's unmodelled joint-angle error (the residual's smooth part over joint
space, and any beyond the declared noise, :mod:`spherecal.identification.joint_error`), less their mean over the
socket.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.robot_file import RobotFileError, forced_calibration
from spherecal.correction.files.samples import Dataset, DatasetError, configuration_hashes, configurations_digest
from spherecal.correction.tool import TIP_MOVED, calibrated_tool, tip_moved
from spherecal.identification.identifiability import symmetric_root
from spherecal.identification.joint_error import LENGTH
from spherecal.identification.prediction import HeldOut
from spherecal.identification.problem import samples_location
from spherecal.identification.training import trained_digests, trained_sketch

#: Largest mean spread [m] at a socket that still describes this arm: a ball held in a socket stays within its
#: own size, and the nominal model of a real arm spreads it by millimetres (MUKCa's Pandas 8 mm mean, 19 mm at
#: most; the calibration's self-check refuses residuals over 10 mm per axis). Where every model spreads it
#: further, the samples are of another arm (an iiwa's recording on a Panda's files: 112-195 mm) or in another unit.
MAX_SPREAD = 0.05
#: A held-out spread within this factor of the predicted one (either way) is as expected; beyond it above, a remark.
BAND = 2.0
#: Fewest distinct configurations (1e-9 rad apart) a spread is measured from: with one the spread is 0
#: whatever the model, with two it is half their distance.
MIN_DISTINCT = 3


@dataclass(frozen=True)
class FixtureSpread:
    """One fixture's predicted tool points around their mean, per model.

    Attributes:
        name: fixture.
        count: samples.
        held_out: False when the fixture was used to calibrate.
        mean, max: model -> mean and largest distance from the mean point [m] (None: not measurable).
        centre: model -> (3,) mean predicted tool point [m].
        distinct: distinct configurations among the samples.
        predicted: the calibrated model's predicted mean spread [m] (None: the file records no prediction).
    """

    name: str
    count: int
    held_out: bool
    mean: dict[str, float | None]
    max: dict[str, float | None]
    centre: dict[str, np.ndarray]
    distinct: int = 0
    predicted: float | None = None

    @property
    def measurable(self) -> bool:
        """At least :data:`MIN_DISTINCT` distinct configurations."""
        return self.distinct >= MIN_DISTINCT


@dataclass(frozen=True)
class DistanceCheck:
    """A known distance against each model's fixture means.

    Attributes:
        a, b: fixtures.
        known: the known distance [m].
        held_out: False when either fixture was used to calibrate.
        measured: model -> distance between the two mean points [m].
    """

    a: str
    b: str
    known: float
    held_out: bool
    measured: dict[str, float]

    def error(self, model: str) -> float:
        """Measured minus known [m]."""
        return self.measured[model] - self.known


@dataclass(frozen=True)
class SocketReport:
    """Spread per fixture and distance errors, per model (metres); ``joint_error``: the unmodelled joint-angle
    error [rad] the prediction includes (0: none)."""

    models: tuple[str, ...]
    fixtures: list[FixtureSpread]
    distances: list[DistanceCheck]
    source: str
    joint_error: float = 0.0

    def summary(self, model: str) -> tuple[float | None, float | None]:
        """Held-out mean spread [m] (mean over fixtures) and mean ``|distance error|`` [m] (each None if none).

        None, not NaN: the report is JSON, and NaN is not JSON (``null`` is).
        """
        spread = [f.mean[model] for f in self.fixtures if f.held_out and f.measurable]
        errors = [abs(d.error(model)) for d in self.distances if d.held_out]
        return (float(np.mean(spread)) if spread else None, float(np.mean(errors)) if errors else None)

    def predicted_summary(self) -> float | None:
        """Mean predicted spread of the measurable held-out sockets [m] (None without predictions)."""
        values = [f.predicted for f in self.fixtures if f.held_out and f.measurable and f.predicted is not None]
        return float(np.mean(values)) if values else None

    def format(self) -> str:
        """The printed tables (mm)."""
        head = " ".join(f"{m + ' mean':>16} {m + ' max':>15}" for m in self.models)
        predicted = any(f.predicted is not None for f in self.fixtures)
        # columns under their heads whatever the names' length (a user trial: MUKCa's 'gen3lite_raised_frontright_h0'
        # and 'iiwa14_almostcenter_h0 (fit)' pushed their rows' figures out from under the heads)
        label = {f.name: f.name + ("" if f.held_out else " (fit)") for f in self.fixtures}
        width = max([22, *(len(v) for v in label.values())])
        lines = [
            f"tool-point spread per socket [mm] (no mocap: distance of each predicted point from the fixture's mean), "
            f"{self.source}",
            f"{'fixture':<{width}} {'samples':>7} {head}" + (f" {'predicted mean':>15}" if predicted else ""),
        ]
        for f in self.fixtures:
            if f.measurable:
                cells = " ".join(f"{f.mean[m] * 1e3:16.3f} {f.max[m] * 1e3:15.3f}" for m in self.models)
            else:
                cells = f"not measurable: {f.distinct} distinct configuration{'s' * (f.distinct != 1)} " \
                        f"(at least {MIN_DISTINCT} needed)"
            if predicted and f.measurable:
                cells += f" {f.predicted * 1e3:15.3f}" if f.held_out and f.predicted is not None else f" {'-':>15}"
            lines.append(f"{label[f.name]:<{width}} {f.count:>7} {cells}")
        if self.distances:
            head = " ".join(f"{m + ' error':>16}" for m in self.models)
            names = [f"{d.a} - {d.b}" + ("" if d.held_out else " (fit)") for d in self.distances]
            span = max([40, *(len(n) for n in names)])
            lines += [
                "",
                "known distances [mm] (distance between the fixtures' mean points minus the known one)",
                f"{'fixtures':<{span}} {'known':>8} {head}",
            ]
            for d, name in zip(self.distances, names, strict=True):
                cells = " ".join(f"{d.error(m) * 1e3:16.3f}" for m in self.models)
                lines.append(f"{name:<{span}} {d.known * 1e3:8.3f} {cells}")
        held = sum(f.held_out and f.measurable for f in self.fixtures)
        fixtures = f"{held} fixture{'s' * (held != 1)}"
        lines.append("")
        if held == 0:
            lines.append("no measurable held-out fixture (every fixture used in the fit, or too few distinct "
                         "configurations): this is no held-out check")
        for m in self.models:
            spread, error = self.summary(m)
            text = "" if error is None else f"   mean |distance error| {error * 1e3:.3f} mm"  # none held out: not said
            mae = f"{'-':>8}" if spread is None else f"{spread * 1e3:8.3f}"
            lines.append(f"held-out ({fixtures}) {m:<11} test MAE {mae} mm{text}")
        forecast = self.predicted_summary()
        if forecast is not None:
            lines.append(f"held-out ({fixtures}) predicted   test MAE {forecast * 1e3:8.3f} mm (the calibration's "
                         f"own prediction for these configurations; measured within {1 / BAND:g}x-{BAND:g}x of it is "
                         "as expected)")
            measured = self.summary("calibrated")[0] if "calibrated" in self.models else None
            if measured is not None and measured * BAND < forecast:  # above the band is a remark (:func:`remarks`)
                lines.append(f"  measured {measured * 1e3:.3f} mm is {measured / forecast:.2g}x of it, below the band: "
                             "better than the calibration predicted (its prediction is cautious here)")
            if self.joint_error > 0:
                lines.append(f"  the prediction includes the arm's unmodelled joint-angle error, "
                             f"{self.joint_error * 1e3:.2g} mrad per joint, that its training residuals show")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """Plain data (metres) for a JSON result file."""
        return {
            "source": self.source,
            "units": "m",
            "fixtures": {
                f.name: {
                    "samples": f.count,
                    "held_out": f.held_out,
                    "spread_mean": f.mean,
                    "spread_max": f.max,
                    "distinct_configurations": f.distinct,
                    "spread_predicted": f.predicted,
                    "centre": {m: [float(v) for v in c] for m, c in f.centre.items()},
                }
                for f in self.fixtures
            },
            "distances": [
                {
                    "a": d.a,
                    "b": d.b,
                    "known": d.known,
                    "held_out": d.held_out,
                    "measured": d.measured,
                    "error": {m: d.error(m) for m in self.models},
                }
                for d in self.distances
            ],
            "held_out": {
                **{m: {"test_mae": self.summary(m)[0], "distance_error_mean_abs": self.summary(m)[1]}
                   for m in self.models},
                "predicted_test_mae": self.predicted_summary(),
                "predicted_joint_error_rad": self.joint_error,
            },
        }


def fitted_fixtures(model: RobotModel, dataset: Dataset | None = None) -> set[str]:
    """Fixtures of ``dataset`` the calibrated file was trained on, recognised by content.

    A fixture counts as trained on when the digest of its joint angles
    (:func:`~spherecal.correction.files.samples.configurations_digest`) is one the file's
    ``calibration.trained_on`` records, whatever the fixture is called, or when one of its samples is in a
    trained fixture's sketch (:mod:`spherecal.identification.training`: a subset or superset of the training
    samples, e.g. the recording imported again with another subsample, was counted as held out). A file that
    records no digests (written before them) falls back to the names of ``calibration.samples_per_fixture``.
    """
    block = model.extras.get("calibration")
    digests = trained_digests(block)
    if digests is not None and dataset is not None:
        sketch = np.array(sorted(trained_sketch(block)), dtype=np.uint64)
        shared = np.isin(configuration_hashes(dataset.q), sketch) if sketch.size else np.zeros(dataset.n_samples, bool)
        return {name for name in dataset.fixture_names
                if configurations_digest(dataset.for_fixture(name)) in digests or shared[dataset.labels == name].any()}
    used = block.get("samples_per_fixture") if isinstance(block, dict) else None
    return set(used) if isinstance(used, dict) else set()


#: Largest socket noise [m], unmodelled joint-angle error [rad], correlation length [rad] and parameter variance
#: [m^2 or rad^2] a prediction record may hold: beyond, the number was not written by a calibration.
RECORD_BOUNDS = {"noise": (0.1, "m"), "joint_error": (0.1, "rad"), "length": (1e3, "rad"),
                 "variance": (1.0, "m^2, rad^2")}


def recorded_prediction(model: RobotModel, source: str = "calibrated file") -> HeldOut | None:
    """What the calibrated file predicts at sockets it did not see (its self-check's ``prediction`` record): the
    parameter covariance (``R R^T`` over every parameter of ``model``, its samples' part at the socket's noise, with
    the bias of the arm's unmodelled joint-angle error), the socket's own noise [m] (std
    per axis; ``noise_m`` in files written before it was recorded) and that joint-angle error [rad]; None when it
    records none (or not in a form this version reads).

    Raises:
        RobotFileError: a recorded number that no calibration writes (negative, NaN/inf, or beyond
            :data:`RECORD_BOUNDS`: a hand edit), one line naming ``source`` and the field; it printed a predicted
            spread of 1597 mm for a socket noise of -1 m, or NaN and overflow warnings.
    """
    block = model.extras.get("calibration")
    check = block.get("self_check") if isinstance(block, dict) else None
    record = check.get("prediction") if isinstance(check, dict) else None
    try:
        names = list(record["parameters"])
        covariance = np.asarray(record["covariance"], dtype=float).reshape(len(names), len(names))
        noise_key = "socket_noise_m" if "socket_noise_m" in record else "noise_m"
        noise = float(record[noise_key])
        joint_error = float(record.get("joint_error_rad", 0.0))
        length = float(record.get("joint_error_length_rad", LENGTH))
        index = [model.param_names.index(n) for n in names]
    except (TypeError, KeyError, ValueError):
        return None
    field = f"{source}: field 'calibration.self_check.prediction."
    for key, value, kind in ((noise_key, noise, "noise"), ("joint_error_rad", joint_error, "joint_error"),
                             ("joint_error_length_rad", length, "length")):
        bound, unit = RECORD_BOUNDS[kind]
        if not (0.0 <= value <= bound) or (kind == "length" and value == 0.0):
            raise RobotFileError(f"{field}{key}': {value!r} is not what a calibration records (expected a number "
                                 f"{'above' if kind == 'length' else 'from'} 0 to {bound:g} {unit})")
    variances, largest = np.diag(covariance), RECORD_BOUNDS["variance"][0]
    if not np.all(np.isfinite(covariance)) or not np.all((variances >= 0) & (variances <= largest)):
        raise RobotFileError(f"{field}covariance': not a covariance (expected finite numbers with a diagonal from 0 "
                             f"to {RECORD_BOUNDS['variance'][0]:g} {RECORD_BOUNDS['variance'][1]})")
    root = np.zeros((model.n_params, len(names)))
    root[index] = symmetric_root(covariance)
    return HeldOut(root, noise, joint_error, length)


def _distinct(q: np.ndarray) -> int:
    return int(np.unique(np.round(q / 1e-9), axis=0).shape[0]) if len(q) else 0


def socket_validation(
    models: dict[str, RobotModel], dataset: Dataset, spec: FixtureSpec | None = None, fitted: set[str] = frozenset(),
    prediction: HeldOut | None = None,
) -> SocketReport:
    """Spread per fixture and known-distance errors of each model on recorded socket samples.

    Args:
        models: model name -> model (e.g. ``{"nominal": ..., "calibrated": ...}``).
        dataset: the samples (joint angles per fixture).
        spec: the fixtures' known distances, or None.
        fitted: fixtures used to calibrate (marked; left out of the held-out summary).
        prediction: :func:`recorded_prediction`: predicted spreads of held-out fixtures.

    Returns:
        The report; fixtures with fewer than :data:`MIN_DISTINCT` distinct configurations have no spread.
    """
    fixtures = []
    for name in dataset.fixture_names:
        q = dataset.for_fixture(name)
        distinct = _distinct(q)
        mean, largest, centre = {}, {}, {}
        for key, model in models.items():
            points = tool_point(model, q)
            centre[key] = points.mean(axis=0)
            distance = np.linalg.norm(points - centre[key], axis=1)
            measurable = distinct >= MIN_DISTINCT
            mean[key] = float(distance.mean()) if measurable else None
            largest[key] = float(distance.max()) if measurable else None
        predicted = None
        if prediction is not None and name not in fitted and distinct >= MIN_DISTINCT:
            predicted = float(prediction.spreads(models["calibrated"], [q])[0])
        fixtures.append(FixtureSpread(name, int(q.shape[0]), name not in fitted, mean, largest, centre, distinct,
                                      predicted))
    _of_this_arm(fixtures, dataset)
    by_name = {f.name: f for f in fixtures}
    distances = []
    for a, b, known in spec.distances if spec is not None else []:
        measured = {key: float(np.linalg.norm(by_name[a].centre[key] - by_name[b].centre[key])) for key in models}
        distances.append(DistanceCheck(a, b, known, a not in fitted and b not in fitted, measured))
    return SocketReport(tuple(models), fixtures, distances, dataset.source,
                        prediction.joint_error if prediction is not None else 0.0)


def _of_this_arm(fixtures: list[FixtureSpread], dataset: Dataset) -> None:
    """Refuse samples no model keeps within :data:`MAX_SPREAD` at some socket (naming its rows): they cannot be
    of this arm, and the spreads and 'WORSE than nominal' that followed said nothing (exit 0)."""
    for f in fixtures:
        spreads = [v for v in f.mean.values() if v is not None]
        if spreads and min(spreads) > MAX_SPREAD:
            where = samples_location(dataset.select(dataset.labels == f.name))
            figures = ", ".join(f"{k} {v * 1e3:.0f} mm" for k, v in f.mean.items())
            raise DatasetError(
                f"{where}, field 'q*': at socket {f.name} every model spreads the tool points {figures} about their "
                f"mean (a ball held in a socket stays within millimetres; at most {MAX_SPREAD * 1e3:.0f} mm): samples "
                "of another arm or tool, or joint angles in another unit or order")


def remarks(report: SocketReport, calibrated: RobotModel, nominal: RobotModel | None = None) -> list[str]:
    """What a user must not miss, one line each: a calibration written with ``--force`` although its
    self-check found the data inconsistent, a calibration of ``nominal`` whose samples put the ball centimetres from
    its tool point (the nominal's spreads then hold that offset, not the arm's error), a calibrated file whose tool
    ``spherecal tool`` replaced (the samples must then be of the new tool), a calibrated file without its
    ``calibration`` block (nothing says which sockets trained it), a calibrated model worse than nominal on these
    samples, else a held-out spread over :data:`BAND` x the predicted one."""
    forced = forced_calibration(calibrated)
    out = [forced] if forced else []
    offset = tip_moved(calibrated, nominal) if nominal is not None else 0.0
    if offset > TIP_MOVED:  # MUKCa's panda_1_with_sensor on panda.urdf: 'nominal' 19.9 mm, the arm's own ~8
        out.append(f"the calibration found the ball {offset * 1e3:.0f} mm from the nominal file's tool point (an "
                   "adapter or sensor the file lacks): the nominal columns measure the file as given, that offset "
                   "included, not the arm's own error")
    if "calibration" not in calibrated.extras:  # deleted by hand, or a robot file that was never calibrated here
        out.append("the calibrated file has no 'calibration' block: nothing records which samples trained it, so every "
                   "socket is counted as held out (one it was trained on looks better than a held-out one would) "
                   "and there is no prediction to compare with")
    moved = float(np.linalg.norm(calibrated.tool - calibrated_tool(calibrated)))
    if moved > 0.0:  # a tool swap: the sockets' data must be of the new tool
        out.append(f"the calibrated file's tool was replaced by `spherecal tool` ({moved * 1e3:.1f} mm from the tool "
                   "it was calibrated with): these samples must have been recorded with the new tool; for data of the "
                   "old one, validate the calibrated file it was made from")
    held = any(f.held_out and f.measurable for f in report.fixtures)
    chosen = [f for f in report.fixtures if f.measurable and (f.held_out or not held)]
    worse = False
    if chosen:
        nominal = float(np.mean([f.mean["nominal"] for f in chosen]))
        calibrated_ = float(np.mean([f.mean["calibrated"] for f in chosen]))
        worse = calibrated_ > nominal
        if worse:
            which = "held-out" if held else "(training)"
            out.append(
                f"the calibrated model is WORSE than nominal on these samples: {which} mean spread "
                f"{calibrated_ * 1e3:.3f} mm against {nominal * 1e3:.3f} mm nominal ({len(chosen)} sockets)"
            )
    measured, predicted = report.summary("calibrated")[0], report.predicted_summary()
    if not worse and measured is not None and predicted and measured > BAND * predicted:  # WORSE says more
        out.append(f"the calibrated model's held-out spread {measured * 1e3:.3f} mm is {measured / predicted:.2g}x the "
                   f"{predicted * 1e3:.3f} mm it predicts there (beyond {BAND:g}x): these sockets differ from the "
                   "training ones in more than the calibration allows for (a socket or the ball that moved, another "
                   "tool or payload, or poses it extrapolates to poorly); calibrate with some of them as well")
    return out


def record_sockets(recording, report: SocketReport, models: dict[str, RobotModel], dataset: Dataset) -> None:
    """Log a socket validation into a :class:`validation.recording.Recording`, in the layout of every
    recording: the calibrated robot through the recorded configurations on ``time`` and each socket
    at its calibrated mean point (``world/*``); per socket, both models' predicted tool points in mm,
    each around its own mean point (``sockets/<fixture>/*``, :meth:`Recording.socket_spread`); each model's
    predicted points coloured by their distance from their socket's mean (``errors/<model>/*``, one
    colour scale); the joint coverage per socket and the printed table.
    """
    index = dataset.fixture_index
    names = [f.name for f in report.fixtures]
    calibrated = models["calibrated"]
    times = dataset.t if dataset.t is not None and np.all(np.diff(dataset.t) > 0) else np.arange(len(index)) * 0.02
    recording.self_motion(calibrated, times, dataset.q)
    labels = [f"{f.name}{'' if f.held_out else ' (fit)'}" for f in report.fixtures]
    recording.fixtures(labels, np.array([f.centre["calibrated"] for f in report.fixtures]))
    points = {key: tool_point(model, dataset.q) for key, model in models.items()}
    recording.samples(points["calibrated"], [labels[k] for k in index])  # the scatter about each socket's centre
    spread = {}
    for key, p in points.items():
        centres = np.array([f.centre[key] for f in report.fixtures])
        spread[key] = np.linalg.norm(p - centres[index], axis=1)
    for k, name in enumerate(names):
        recording.socket_spread(name, points["nominal"][index == k], points["calibrated"][index == k])
    top = max(float(np.quantile(e, 0.99)) for e in spread.values()) * 1e3
    for key in models:
        recording.workspace_errors(key, points[key], spread[key], "its socket's mean point", top)
    recording.coverage({name: dataset.q[index == k] for k, name in enumerate(names)}, calibrated.lower,
                       calibrated.upper)
    recording.text("sockets", report.format(), "Socket validation table (mm)")
