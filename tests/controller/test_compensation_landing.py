"""Where the TRUE arm lands in MuJoCo when targets are commanded three ways.

(a) through the nominal model (nominal IK from the seed: the uncorrected controller),
(b) through corrected IK (:func:`controller.compensation.corrected_ik`, the calibrated model),
(c) through the nominal model with compensated targets (:func:`controller.compensation.compensate`).

The plant is the controller's MuJoCo arm built from the true model; each joint command is
reached by a joint-space servo on its velocity actuators from the seed configuration, and the
landing is the plant's tool site. The calibrated model is either

* ``identified`` (default): a real calibration through identification's API
  (:func:`identification.calibrate.calibrate`, Levenberg-Marquardt) of kinematic self-motion
  samples of the true robot (:func:`identification.synthetic.make_dataset`, 200 per fixture at
  the three Panda fixtures, 0.05 mm fixture noise, fixture positions known), or
* ``perturbed``: the true model perturbed by a small known error.

The calibration's own accuracy is its mean tool-point error against the true model on 1000
random configurations.

Run the 200-target table: ``python -m tests.controller.test_compensation_landing [perturbed]`` (or the slow
test with ``-s``); the quick test runs 12 targets.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

#: The true robot's spread (the issues' default) and the calibration's residual error.
FIXTURE_NOISE = 5e-5  # [m] std of the fixture noise in the identified calibration's samples
SAMPLES_PER_FIXTURE = 200
CALIBRATION_LENGTH_STD = 3e-5  # [m]
CALIBRATION_ANGLE_STD = float(np.deg2rad(0.003))  # [rad]
SEED_SPREAD = 0.3  # [rad] std of the seed around the configuration the target was drawn from
LIMIT_INSET = 0.1  # [rad] targets are drawn from configurations this far inside the limits
SERVO_GAIN = 40.0  # [1/s]
SERVO_TOL = 1e-11  # [rad] the servo stops when every joint is this close to its command
SERVO_SECONDS = 5.0  # [s] at most


@dataclass
class LandingTable:
    """Landing errors [m] per method (count,), iterations of (c), and the calibration accuracy."""

    calibration: str
    errors: dict[str, np.ndarray]
    iterations: np.ndarray
    residuals: np.ndarray
    notes: list[str]
    skipped: list[str]
    accuracy_random: float
    accuracy_landing: float
    servo_residual: float

    def text(self) -> str:
        width = max(len(name) for name in self.errors) + 2
        at_landings = (
            "" if np.isnan(self.accuracy_landing) else f", {self.accuracy_landing * 1e3:.4f} mm at the (b)/(c) landings"
        )
        rows = [
            f"{len(self.iterations)} targets, true robot = nominal + perturb(1 mm, 0.2 deg, 1 mm tool), "
            f"calibrated model: {self.calibration}",
            f"calibration accuracy |p_cal - p_true|: mean {self.accuracy_random * 1e3:.4f} mm on 1000 random "
            f"configurations{at_landings}",
            f"{'command':<{width}} {'mean [mm]':>10} {'max [mm]':>10}",
        ]
        for name, err in self.errors.items():
            rows.append(f"{name:<{width}} {err.mean() * 1e3:>10.4f} {err.max() * 1e3:>10.4f}")
        converged = self.residuals <= 1e-9
        rows.append(
            f"compensation converged (1e-9 m) on {converged.sum()}/{converged.size} targets: iterations mean "
            f"{self.iterations[converged].mean():.2f}, max {self.iterations[converged].max()}, model residual max "
            f"{self.residuals[converged].max():.1e} m"
            + (f"; servo |q - q_cmd| max {self.servo_residual:.1e} rad" if self.servo_residual > 0 else "")
        )
        rows.extend(f"  note: {note}" for note in self.notes)
        rows.append(f"{len(self.skipped)} drawn targets skipped, not reachable from their seed:")
        rows.extend(f"  {note}" for note in self.skipped)
        return "\n".join(rows)


def _servo(plant, q_start: np.ndarray, q_cmd: np.ndarray) -> tuple[np.ndarray, float]:
    """Drive the plant from ``q_start`` to ``q_cmd`` with its velocity actuators; tool site and |q - q_cmd|."""
    import mujoco

    plant.set_state(q_start)
    m, d, n = plant.mj_model, plant.mj_data, plant.n_joints
    for step in range(int(SERVO_SECONDS / m.opt.timestep)):
        d.ctrl[:n] = SERVO_GAIN * (q_cmd - d.qpos[:n])
        mujoco.mj_step(m, d)
        if step % 100 == 0 and np.abs(d.qpos[:n] - q_cmd).max() < SERVO_TOL:
            break
    mujoco.mj_forward(m, d)
    return plant.tool_position(), float(np.abs(d.qpos[:n] - q_cmd).max())


def calibrated_model(nominal, true, rng: np.random.Generator, calibration: str):
    """The calibrated model and a one-line description of how it was made (see module docstring)."""
    from spherecal.correction import perturb

    if calibration == "perturbed":
        model = perturb(true, rng, CALIBRATION_LENGTH_STD, CALIBRATION_ANGLE_STD, CALIBRATION_LENGTH_STD)
        return model, (f"true + perturb({CALIBRATION_LENGTH_STD * 1e3:g} mm, "
                       f"{np.rad2deg(CALIBRATION_ANGLE_STD):g} deg, {CALIBRATION_LENGTH_STD * 1e3:g} mm tool)")
    if calibration != "identified":
        raise ValueError(f"calibration: expected 'identified' or 'perturbed', got {calibration!r}")
    from spherecal.correction.files.fixtures import FixtureSpec
    from spherecal.identification.calibrate import calibrate
    from spherecal.identification.synthetic import PANDA_FIXTURES, make_dataset

    dataset, _ = make_dataset(true, per_fixture=SAMPLES_PER_FIXTURE, rng=rng, noise=FIXTURE_NOISE)
    positions = {name: np.asarray(centre, dtype=float) for name, centre in PANDA_FIXTURES.items()}
    result = calibrate(nominal, dataset, FixtureSpec(names=tuple(positions), positions=positions, distances=[]))
    return result.model, (
        f"identification.calibrate (lm) on {len(dataset.labels)} kinematic self-motion samples at "
        f"{', '.join(positions)} (known positions, {FIXTURE_NOISE * 1e3:g} mm fixture noise), "
        f"residual rms {result.rms_after * 1e3:.4f} mm"
    )


def _setup(seed: int, calibration: str):
    """Seeded generator, nominal, true and calibrated models, its description, the true plant, and the
    calibration's accuracy [m] (mean tool-point error against the truth on 1000 random configurations)."""
    from spherecal.controller.plant import build_plant
    from spherecal.correction import load_robot, perturb, tool_point

    rng = np.random.default_rng(seed)
    nominal = load_robot("panda")
    true = perturb(nominal, rng)
    calibrated, description = calibrated_model(nominal, true, rng, calibration)
    plant = build_plant(true)
    q_random = true.random_configurations(1000, rng)
    accuracy = np.linalg.norm(tool_point(calibrated, q_random) - tool_point(true, q_random), axis=1).mean()
    return rng, nominal, true, calibrated, description, plant, accuracy


def landing_table(count: int, seed: int = 20261122, calibration: str = "identified") -> LandingTable:
    """Command ``count`` random reachable targets three ways on the true plant (see module docstring)."""
    from spherecal.controller.compensation import compensate, corrected_ik, nominal_ik_controller
    from spherecal.controller.ik import UnreachableError
    from spherecal.correction import tool_point

    rng, nominal, true, calibrated, description, plant, accuracy_random = _setup(seed, calibration)
    lower, upper = nominal.lower + LIMIT_INSET, nominal.upper - LIMIT_INSET
    names = ("(a) nominal model", "(b) corrected IK (calibrated model)", "(c) nominal model, compensated target")
    errors = {name: np.empty(count) for name in names}
    iterations, residuals, landed_q = np.empty(count, dtype=int), np.empty(count), []
    servo, notes, skipped, k = 0.0, [], [], 0
    while k < count:
        q_goal = rng.uniform(lower, upper)
        target = tool_point(true, q_goal)
        q_seed = np.clip(q_goal + rng.normal(0.0, SEED_SPREAD, nominal.n_joints), lower, upper)
        try:  # reachable: by the nominal controller from the seed (a), the corrected IK (b) and (c)
            commands = (
                nominal_ik_controller(nominal, target, q_seed),
                corrected_ik(calibrated, target, q_seed, nominal=nominal),
            )
            result = compensate(target, nominal, calibrated, q_seed, strict=False)
        except UnreachableError as error:
            skipped.append(str(error))
            continue
        if not result.converged:
            notes.append(result.note)
        commands += (nominal_ik_controller(nominal, result.command, q_seed),)  # what the nominal controller does
        for name, q_cmd in zip(names, commands, strict=True):
            landing, residual = _servo(plant, q_seed, q_cmd)
            errors[name][k] = np.linalg.norm(landing - target)
            servo = max(servo, residual)
        iterations[k], residuals[k] = result.iterations, result.position_residual
        landed_q += [commands[1], commands[2]]
        k += 1
    landed_q = np.array(landed_q)
    accuracy_landing = np.linalg.norm(tool_point(calibrated, landed_q) - tool_point(true, landed_q), axis=1).mean()
    return LandingTable(
        description, errors, iterations, residuals, notes, skipped, accuracy_random, accuracy_landing, servo
    )


def _closed_loop(plant, controller, q_start: np.ndarray | None, command: np.ndarray) -> np.ndarray:
    """Run the QP controller on the plant towards ``command`` until its own model is on it (from
    ``q_start`` at rest, or from where the plant is when None); the tool site."""
    import mujoco

    if q_start is not None:
        plant.set_state(q_start)
    m, d, n = plant.mj_model, plant.mj_data, plant.n_joints
    rest = np.zeros(n)
    for step in range(int(SERVO_SECONDS / m.opt.timestep)):
        q = d.qpos[:n].copy()
        d.ctrl[:n] = controller.step(q, rest, command)
        mujoco.mj_step(m, d)
        if step % 100 == 0 and np.linalg.norm(controller.kinematics(q)[0] - command) < 1e-11:
            break
    mujoco.mj_forward(m, d)
    return plant.tool_position()


def qp_landing_table(count: int, seed: int = 20261122, calibration: str = "identified") -> LandingTable:
    """The same comparison with the QP differential-IK controller in closed loop on the plant.

    The controller (:class:`controller.nullspace.NullSpaceController`, no secondary task) picks
    its posture by its own flow from the seed, which nominal IK from the seed only approximates:
    (c) is computed twice, with the default controller model and with
    :class:`controller.compensation.DifferentialIKFlow`.
    """
    import warnings

    from spherecal.controller.compensation import DifferentialIKFlow, compensate
    from spherecal.controller.ik import UnreachableError
    from spherecal.controller.nullspace import NullSpaceController
    from spherecal.controller.qp_ik import ControllerFallbackWarning
    from spherecal.correction import tool_point

    rng, nominal, true, calibrated, description, plant, accuracy = _setup(seed, calibration)
    nominal_qp, calibrated_qp = NullSpaceController(nominal), NullSpaceController(calibrated)
    flow = DifferentialIKFlow()

    def online(model, command, q_seed, orientation):  # the real arm as its own controller model
        _closed_loop(plant, nominal_qp, None, command)
        return plant.q.copy()

    lower, upper = nominal.lower + LIMIT_INSET, nominal.upper - LIMIT_INSET
    names = (
        "(a) QP, nominal model",
        "(b) QP with the calibrated model",
        "(c) QP nominal, compensated (IK model)",
        "(c') QP nominal, compensated (flow model)",
        "(c'') QP nominal, compensated online (measured q)",
    )
    errors = {name: np.empty(count) for name in names}
    iterations, residuals, notes, skipped, k = np.empty(count, dtype=int), np.empty(count), [], [], 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ControllerFallbackWarning)
        while k < count:
            q_goal = rng.uniform(lower, upper)
            target = tool_point(true, q_goal)
            q_seed = np.clip(q_goal + rng.normal(0.0, SEED_SPREAD, nominal.n_joints), lower, upper)
            try:
                by_ik = compensate(target, nominal, calibrated, q_seed, strict=False)
                by_flow = compensate(target, nominal, calibrated, q_seed, controller=flow, strict=False)
            except UnreachableError as error:
                skipped.append(str(error))
                continue
            notes += [r.note for r in (by_ik, by_flow) if not r.converged]
            runs = ((nominal_qp, target), (calibrated_qp, target), (nominal_qp, by_ik.command))
            runs += ((nominal_qp, by_flow.command),)
            for name, (controller, command) in zip(names, runs, strict=False):
                errors[name][k] = np.linalg.norm(_closed_loop(plant, controller, q_seed, command) - target)
            plant.set_state(q_seed)
            live = compensate(target, nominal, calibrated, q_seed, controller=online, tol=1e-8, strict=False)
            errors[names[-1]][k] = np.linalg.norm(_closed_loop(plant, nominal_qp, None, live.command) - target)
            notes += [f"online: {live.note}"] if not live.converged else []
            iterations[k], residuals[k] = by_flow.iterations, by_flow.position_residual
            k += 1
    notes.append(f"QP fallbacks inside the flow model: {flow.fallbacks}")
    return LandingTable(description, errors, iterations, residuals, notes, skipped, accuracy, float("nan"), 0.0)


def _check(table: LandingTable) -> None:
    a, b, c = table.errors.values()
    assert a.mean() > 1e-3  # the nominal model misses by millimetres
    for err in (b, c):  # corrected and compensated land within 0.1 mm (mean) of the calibration's accuracy
        assert abs(err.mean() - table.accuracy_random) < 1e-4
        assert err.mean() < a.mean() / 10
    assert np.mean(table.residuals < 1e-9) > 0.9 and table.servo_residual < 1e-8


@pytest.mark.parametrize("calibration", ["identified", "perturbed"])
def test_landing_quick(calibration) -> None:
    table = landing_table(12, calibration=calibration)
    print("\n" + table.text())
    _check(table)


@pytest.mark.slow
def test_landing_with_the_qp_controller_in_closed_loop() -> None:
    table = qp_landing_table(16)
    print("\n" + table.text())
    a, b, c_ik, c_flow, c_online = table.errors.values()
    assert a.mean() > 1e-3
    for err in (b, c_online):
        assert abs(err.mean() - table.accuracy_random) < 1e-4
    assert c_flow.mean() < c_ik.mean()  # the controller model must be the controller's own flow


@pytest.mark.slow
def test_landing_200_targets() -> None:
    table = landing_table(200)
    print("\n" + table.text())
    _check(table)


if __name__ == "__main__":
    import sys
    import time

    start = time.perf_counter()
    args = sys.argv[1:]
    if args[:1] == ["qp"]:  # python -m tests.controller.test_compensation_landing qp [COUNT]
        print(qp_landing_table(int(args[1]) if len(args) > 1 else 50).text())
    else:
        print(landing_table(200, calibration=(args or ["identified"])[0]).text())
    print(f"({time.perf_counter() - start:.1f} s)")
