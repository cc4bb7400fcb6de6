"""Model selection by cross-validation: rigid DH (``dh``) or DH plus joint compliance (``elastic``).

Folds leave one *placement* out: fixtures named ``<placement>_h<k>`` (several sockets of one plate, as
MUKCa records them) form one group; otherwise every fixture is its own group (leave-one-fixture-out).
For each fold both models are fitted on the other groups and judged on the held-out one, whose centre
is unknown to them::

    error(fold) = mean over its fixtures of  mean_k |p_k - mean(p)|     (the predicted points' spread)
                  and over known distances within the fold of  | |mean_a - mean_b| - D_ab |

``auto`` keeps ``elastic`` only when the mean per-fold improvement over ``dh`` exceeds its standard
error (the fold-to-fold spread of the differences): a richer model must earn its place.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import Dataset, FixtureSpec, RobotModel, tool_point
from spherecal.correction.elastic import with_compliance
from spherecal.correction.errors import SpherecalError
from spherecal.correction.gravity import has_inertials

MODELS: tuple[str, ...] = ("dh", "elastic", "auto")
#: Samples per fixture of every fold's fits (the final fit uses all): keeps `calibrate` interactive.
CV_SAMPLES = 150


def groups_of(names: tuple[str, ...] | list[str]) -> dict[str, str]:
    """Fixture name -> its group: the placement before the last ``_h`` when names carry one, else itself."""
    out = {}
    for name in names:
        head, sep, tail = name.rpartition("_h")
        out[name] = head if sep and head and tail.isdigit() else name
    return out


def held_out_error(model: RobotModel, dataset: Dataset, spec: FixtureSpec | None) -> float:
    """Mean spread [m] of ``model``'s tool points around their mean at each fixture of ``dataset``,
    averaged with the errors of the known distances between them (see the module docstring)."""
    points = tool_point(model, dataset.q)
    index = dataset.fixture_index
    means, errors = {}, []
    for j, name in enumerate(dataset.fixture_names):
        p = points[index == j]
        means[name] = p.mean(axis=0)
        errors.append(float(np.linalg.norm(p - means[name], axis=1).mean()))
    for a, b, distance in [] if spec is None else spec.distances:
        if a in means and b in means:
            errors.append(abs(float(np.linalg.norm(means[a] - means[b])) - distance))
    return float(np.mean(errors))


def elastic_start(nominal: RobotModel) -> RobotModel:
    """``nominal`` with every compliance free to be identified (start: rigid, or its own compliance)."""
    c = nominal.extras.get("compliance")
    return with_compliance(nominal, np.zeros(nominal.n_joints) if c is None else c)


def rigid(nominal: RobotModel) -> RobotModel:
    """``nominal`` without compliance (the geometric model)."""
    return with_compliance(nominal, None)


@dataclass(frozen=True)
class ModelSelection:
    """What cross-validation found.

    Attributes:
        requested: ``dh``, ``elastic`` or ``auto``.
        chosen: the model calibrated: ``dh`` or ``elastic``.
        reason: one sentence.
        folds: held-out group names, in order.
        errors: model -> (folds,) held-out error [m] (empty when no cross-validation ran).
        samples_per_fixture: samples per fixture of the fold fits.
        seconds: wall time of the cross-validation [s].
    """

    requested: str
    chosen: str
    reason: str
    folds: tuple[str, ...] = ()
    errors: dict[str, np.ndarray] | None = None
    samples_per_fixture: int = 0
    seconds: float = 0.0

    def stats(self) -> tuple[float, float, float, float] | None:
        """(mean dh, mean elastic, mean improvement, its standard error) [m], or None without folds."""
        if not self.errors:
            return None
        dh, el = self.errors["dh"], self.errors["elastic"]
        diff = dh - el
        se = float(np.std(diff, ddof=1) / np.sqrt(diff.size)) if diff.size > 1 else float("inf")
        return float(dh.mean()), float(el.mean()), float(diff.mean()), se

    def summary(self) -> str:
        lines = [f"model: {self.chosen} ({self.reason})"]
        if self.errors:
            dh, el, gain, se = self.stats()
            lines.append(
                f"cross-validation, leave one of {len(self.folds)} groups out ({self.samples_per_fixture} samples per "
                f"fixture per fit, {self.seconds:.2f} s): held-out error [mm] dh {dh * 1e3:.4f}, "
                f"elastic {el * 1e3:.4f}, gain {gain * 1e3:.3g} +- {se * 1e3:.2g}"
            )
            for k, name in enumerate(self.folds):
                dh_k, el_k = self.errors["dh"][k] * 1e3, self.errors["elastic"][k] * 1e3
                lines.append(f"  {name:<16} dh {dh_k:.4f}  elastic {el_k:.4f}")
        return "\n".join(lines)

    def block(self) -> dict:
        """The ``model_selection`` entry of the result file (metres)."""
        out = {"requested": self.requested, "chosen": self.chosen, "reason": self.reason}
        if self.errors:
            dh, el, gain, se = self.stats()
            out.update({
                "folds": list(self.folds),
                "held_out_error_m": {k: [float(v) for v in e] for k, e in self.errors.items()},
                "mean_m": {"dh": dh, "elastic": el}, "gain_m": gain, "gain_standard_error_m": se,
                "samples_per_fixture": self.samples_per_fixture, "seconds": self.seconds,
            })
        return out


def _sub_spec(spec: FixtureSpec | None, names: tuple[str, ...]) -> FixtureSpec:
    if spec is None:
        return FixtureSpec.unknown(names)
    keep = set(names)
    return replace(
        spec, names=tuple(n for n in spec.names if n in keep),
        positions={k: v for k, v in spec.positions.items() if k in keep},
        distances=[d for d in spec.distances if d[0] in keep and d[1] in keep],
    )


def cross_validate(fit, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                   samples: int = CV_SAMPLES, seed: int = 0) -> tuple[tuple[str, ...], dict[str, np.ndarray], int]:
    """Held-out errors of both models, one fold per group.

    Args:
        fit: ``fit(start_model, dataset, spec) -> RobotModel`` (the calibration, as the caller runs it).
        samples: samples per fixture of the fold fits (drawn once, seeded); the held-out group is judged on
            all of its samples.

    Returns:
        folds, model -> (folds,) errors [m], samples per fixture used.
    """
    groups = groups_of(dataset.fixture_names)
    folds = tuple(dict.fromkeys(groups.values()))
    small = dataset.subsampled(samples, np.random.default_rng(seed))
    errors = {"dh": [], "elastic": []}
    for fold in folds:
        held = np.array([groups[label] == fold for label in small.labels])
        train = small.select(~held)
        test = dataset.select(np.array([groups[label] == fold for label in dataset.labels]))
        train_spec = _sub_spec(spec, train.fixture_names)
        for name, start in (("dh", rigid(nominal)), ("elastic", elastic_start(nominal))):
            model = fit(start, train, train_spec)
            errors[name].append(held_out_error(model, test, spec))
    used = min(samples, min(dataset.counts().values()))
    return folds, {k: np.array(v) for k, v in errors.items()}, used


def select_model(requested: str, fit, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                 samples: int = CV_SAMPLES, seed: int = 0) -> ModelSelection:
    """Decide between ``dh`` and ``elastic`` (see the module docstring).

    Raises:
        SpherecalError: ``elastic`` requested for a robot without ``inertials``.
        ValueError: unknown ``requested``.
    """
    if requested not in MODELS:
        raise ValueError(f"unknown model {requested!r}, expected one of {MODELS}")
    if requested == "dh":
        return ModelSelection("dh", "dh", "requested")
    if not has_inertials(nominal):
        if requested == "elastic":
            raise SpherecalError(f"{nominal.name}: field 'inertials': --model elastic needs the link masses "
                                 f"(an inertials block in the robot file)")
        return ModelSelection("auto", "dh", "the robot file has no inertials: no gravity torques, no elastic model")
    if requested == "elastic":
        return ModelSelection("elastic", "elastic", "requested")
    groups = set(groups_of(dataset.fixture_names).values())
    if len(groups) < 3:
        return ModelSelection("auto", "dh", f"{len(groups)} fixture group(s): too few to cross-validate (need 3)")
    clock = time.perf_counter()
    try:
        folds, errors, used = cross_validate(fit, nominal, dataset, spec, samples, seed)
    except SpherecalError as error:  # a fold the data cannot calibrate: no evidence for the richer model
        return ModelSelection("auto", "dh", f"a cross-validation fold could not be calibrated ({error})")
    seconds = time.perf_counter() - clock
    selection = ModelSelection("auto", "dh", "", folds, errors, used, seconds)
    _, _, gain, se = selection.stats()
    if gain > se:
        reason = (f"elastic predicts held-out fixtures {gain * 1e3:.3g} mm better, more than the fold spread "
                  f"{se * 1e3:.2g} mm")
        return replace(selection, chosen="elastic", reason=reason)
    reason = (f"elastic's held-out gain {gain * 1e3:.3g} mm does not exceed the fold spread {se * 1e3:.2g} mm; "
              f"the simpler model is kept")
    return replace(selection, reason=reason)
