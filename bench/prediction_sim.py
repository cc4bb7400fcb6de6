"""Predicted against measured held-out error on simulated arms, where the truth is known.

The counterpart of ``bench/prediction_real.py``: MUKCa's protocol (two sockets 50 mm apart at one placement, with
their distance known) on a simulated Panda, three held-out sockets elsewhere (30 configurations each), calibrated
by ``run_workflow`` (geometric model, written whatever the self-check says), and the held-out test MAE measured
against the one ``validate`` predicts from the calibrated file (``validation.sockets.recorded_prediction``).
Setups: the arm off nominal by 1x or 3x the prior spread (1 mm, 0.2 deg), white socket noise, and an unmodelled
joint-angle error (the Gaussian process of ``identification/joint_error.py``, length 1 rad) below or above the
declared 0.3 mm; few samples at 0.3 mm, where parameters are left at nominal; noise-free samples (the Panda and a
UR-like 6-joint arm, with and without a joint-angle error); MuJoCo self-motion as ``spherecal simulate --seconds 2
--per-fixture 50`` records it (compliance noise 0.3 mm correlated over 0.05 s, its three sockets without a known
distance, ``calibrate``'s defaults, two sockets held out), without and with a 1 mrad joint-angle error.
Printed per setup: the ratio measured / predicted (median, range, how many within 0.5x-2x) and the recorded socket
noise and joint-angle error against the truth.

    .venv/bin/python bench/prediction_sim.py [--seeds 6] [--only TEXT] [--out bench/prediction_sim.json]
"""

from __future__ import annotations

import argparse
import subprocess
import time
import warnings
from dataclasses import replace
from pathlib import Path

import bench_common  # first: one BLAS thread
import numpy as np  # noqa: E402

from spherecal.correction import RobotModel, load_robot, perturb  # noqa: E402
from spherecal.correction.files.fixtures import FixtureSpec  # noqa: E402
from spherecal.correction.files.samples import Dataset  # noqa: E402
from spherecal.identification.joint_error import LENGTH, field_root  # noqa: E402
from spherecal.identification.synthetic import make_dataset  # noqa: E402
from spherecal.identification.workflow import WorkflowOptions, run_workflow  # noqa: E402
from spherecal.validation.sockets import recorded_prediction, socket_validation  # noqa: E402

#: name -> (arm off nominal [prior spreads], socket noise per axis [m], joint-angle error [rad], samples per socket)
SETUPS = {
    "prior arm, 0.1 mm": (1.0, 1e-4, 0.0, 30),
    "3x arm, 0.1 mm": (3.0, 1e-4, 0.0, 30),
    "prior arm, 0.1 mm + 0.2 mrad": (1.0, 1e-4, 2e-4, 30),
    "3x arm, 0.1 mm + 0.3 mrad": (3.0, 1e-4, 3e-4, 30),
    "prior arm, 0.1 mm + 3 mrad": (1.0, 1e-4, 3e-3, 40),
    "prior arm, 0.3 mm, 8 samples": (1.0, 3e-4, 0.0, 8),
    "3x arm, 0.3 mm, 8 samples": (3.0, 3e-4, 0.0, 8),
    "prior arm, noise-free": (1.0, 0.0, 0.0, 30),
    "3x arm, noise-free": (3.0, 0.0, 0.0, 30),
    "prior arm, noise-free + 0.3 mrad": (1.0, 0.0, 3e-4, 30),
}
HALF_PI = np.pi / 2
#: A UR5-like arm (standard DH, the tool point off the last axis; tests/controller/test_generic_arm.py's), its
#: sockets within its reach.
UR_LIKE = RobotModel(
    name="ur5", convention="standard", a=[0.0, -0.425, -0.39225, 0.0, 0.0, 0.0],
    alpha=[HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0], d=[0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823],
    theta=np.zeros(6), lower=[-6.28, -6.28, -3.14, -6.28, -6.28, -6.28], upper=[6.28, 6.28, 3.14, 6.28, 6.28, 6.28],
    tool=[0.0, 0.05, 0.1])
UR_TRAIN = {"a": (0.45, 0.2, 0.3), "b": (0.45, 0.25, 0.3)}
UR_HELD = {"c": (0.3, -0.4, 0.2), "d": (-0.2, 0.45, 0.4)}
#: name -> (arm off nominal [prior spreads], noise [m], joint-angle error [rad]) on the UR-like arm
UR_SETUPS = {
    "UR-like, prior arm, noise-free": (1.0, 0.0, 0.0),
    "UR-like, 3x arm, noise-free": (3.0, 0.0, 0.0),
    "UR-like, prior arm, noise-free + 0.3 mrad": (1.0, 0.0, 3e-4),
}
#: MuJoCo self-motion (``spherecal simulate``'s: compliance noise 0.3 mm per axis correlated over 0.05 s), 2 s and
#: 50 samples per socket, three training sockets (its defaults, no known distance), two held out; name ->
#: joint-angle error [rad] added to the recorded angles
MUJOCO_SETUPS = {"MuJoCo 2 s, 0.3 mm correlated": 0.0, "MuJoCo 2 s, 0.3 mm correlated + 1 mrad": 1e-3}
MUJOCO_HELD = {"Q1": (0.4, 0.35, 0.3), "Q2": (0.3, -0.4, 0.45)}
TRAIN = {"a": (0.5, 0.1, 0.3), "b": (0.5, 0.15, 0.3)}
HELD = {"c": (-0.1, 0.5, 0.4), "d": (0.35, -0.35, 0.75), "e": (0.3, 0.3, 0.3)}


def _joint_error(train: Dataset, held: Dataset, joint: float, seed: int) -> tuple[Dataset, Dataset]:
    """Recorded angles off by a smooth error of the configuration (std ``joint`` [rad]), one draw over training and
    held out."""
    if not joint:
        return train, held
    q = np.concatenate([train.q, held.q])
    root = field_root(q, LENGTH)
    recorded = q - joint * root @ np.random.default_rng(300 + seed).standard_normal((root.shape[1], q.shape[1]))
    return replace(train, q=recorded[: len(train.q)]), replace(held, q=recorded[len(train.q):])


def one(nominal, seed: int, share: float, noise: float, joint: float, count: int, train_at: dict = TRAIN,
        held_at: dict = HELD) -> dict:
    true = perturb(nominal, np.random.default_rng(seed), share * 1e-3, np.deg2rad(0.2 * share), share * 1e-3)
    train, _ = make_dataset(true, train_at, count, np.random.default_rng(100 + seed), noise)
    held, _ = make_dataset(true, held_at, 30, np.random.default_rng(200 + seed), noise)
    train, held = _joint_error(train, held, joint, seed)
    apart = float(np.linalg.norm(np.subtract(*train_at.values())))
    spec = FixtureSpec(names=tuple(train_at), distances=[("a", "b", apart)])
    return _measure(nominal, train, held, spec, WorkflowOptions(force=True, model="dh"), seed)


def one_mujoco(nominal, seed: int, joint: float) -> dict:
    """``spherecal simulate --seconds 2 --per-fixture 50``'s recording at its three sockets and two more held out,
    calibrated with ``calibrate``'s defaults."""
    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion  # MuJoCo: this setup only
    from spherecal.validation.experiments.experiment import default_fixtures

    rng = np.random.default_rng(seed)
    true = perturb(nominal, rng, 1e-3, np.deg2rad(0.2), 1e-3)
    train_at = default_fixtures()
    fixtures = {**train_at, **{k: np.array(v) for k, v in MUJOCO_HELD.items()}}
    run = collect_self_motion(true, nominal, fixtures, rng, SelfMotionSettings(seconds=2.0, samples=50, noise=3e-4))
    data = run.dataset()
    train = data.select(np.flatnonzero(np.isin(data.labels, list(train_at))))
    train = Dataset(labels=train.labels, q=train.q, t=train.t, fixture_names=tuple(train_at))
    held = data.select(np.flatnonzero(np.isin(data.labels, list(MUJOCO_HELD))))
    held = Dataset(labels=held.labels, q=held.q, t=held.t, fixture_names=tuple(MUJOCO_HELD))
    train, held = _joint_error(train, held, joint, seed)
    return _measure(nominal, train, held, FixtureSpec(names=tuple(train_at)), WorkflowOptions(force=True), seed)


def _measure(nominal, train: Dataset, held: Dataset, spec: FixtureSpec, options: WorkflowOptions, seed: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calibrated = run_workflow(nominal, train, spec, options).model
    prediction = recorded_prediction(calibrated)
    report = socket_validation({"nominal": nominal, "calibrated": calibrated}, held, prediction=prediction)
    measured, _ = report.summary("calibrated")
    predicted = report.predicted_summary()
    return {"seed": seed, "measured_mm": measured * 1e3, "predicted_mm": predicted * 1e3, "ratio": measured / predicted,
            "socket_noise_mm": prediction.noise * 1e3, "joint_error_mrad": prediction.joint_error * 1e3}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--only", default="", help="only the setups whose name holds this text")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("prediction_sim.json"))
    args = parser.parse_args()
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    clock = time.perf_counter()
    nominal = load_robot("panda")
    results = {}
    print(f"{'setup':<42} {'ratio median':>12} {'range':>13} {'in 0.5-2x':>9} {'socket noise':>13} {'joint error':>12}"
          "  (ratio = measured / predicted held-out test MAE; noise [mm] and error [mrad]: recorded, median)")
    runs = [(name, share, noise, joint, count, lambda s, a=(share, noise, joint, count): one(nominal, s, *a))
            for name, (share, noise, joint, count) in SETUPS.items()]
    runs += [(name, share, noise, joint, 30, lambda s, a=(share, noise, joint): one(UR_LIKE, s, *a, 30, UR_TRAIN,
                                                                                     UR_HELD))
             for name, (share, noise, joint) in UR_SETUPS.items()]
    runs += [(name, 1.0, 3e-4, joint, 50, lambda s, j=joint: one_mujoco(nominal, s, j))
             for name, joint in MUJOCO_SETUPS.items()]
    for name, share, noise, joint, count, run in runs:
        if args.only and args.only not in name:
            continue
        rows = [run(seed) for seed in range(args.seeds)]
        ratios = np.array([r["ratio"] for r in rows])
        inside = int(((ratios >= 0.5) & (ratios <= 2.0)).sum())
        print(f"{name:<42} {np.median(ratios):12.2f} {ratios.min():6.2f}..{ratios.max():<5.2f} "
              f"{inside:>5}/{len(rows):<3} "
              f"{np.median([r['socket_noise_mm'] for r in rows]):7.3f} ({noise * 1e3:.1f}) "
              f"{np.median([r['joint_error_mrad'] for r in rows]):6.2f} ({joint * 1e3:.1f})")
        results[name] = {"share": share, "noise_m": noise, "joint_error_rad": joint, "samples": count, "rows": rows}
    print(f"{time.perf_counter() - clock:.0f} s")
    bench_common.write_json(args.out, {"setups": results}, seed=0, inputs={"seeds": args.seeds})
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
