"""Predicted against measured held-out error on simulated arms, where the truth is known.

The counterpart of ``bench/prediction_real.py``: MUKCa's protocol (two sockets 50 mm apart at one placement, with
their distance known) on a simulated Panda, three held-out sockets elsewhere (30 configurations each), calibrated
by ``run_workflow`` (geometric model, written whatever the self-check says), and the held-out test MAE measured
against the one ``validate`` predicts from the calibrated file (``validation.sockets.recorded_prediction``).
Setups: the arm off nominal by 1x or 3x the prior spread (1 mm, 0.2 deg), white socket noise, and an unmodelled
joint-angle error (the Gaussian process of ``identification/joint_error.py``, length 1 rad) below or above the
declared 0.3 mm; few samples at 0.3 mm, where parameters are left at nominal. Printed per setup: the ratio
measured / predicted (median, range, how many within 0.5x-2x) and the recorded socket noise and joint-angle error
against the truth.

    .venv/bin/python bench/prediction_sim.py [--seeds 6] [--out bench/prediction_sim.json]
"""

from __future__ import annotations

import argparse
import subprocess
import time
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread
import numpy as np  # noqa: E402

from spherecal.correction import load_robot, perturb  # noqa: E402
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
}
TRAIN = {"a": (0.5, 0.1, 0.3), "b": (0.5, 0.15, 0.3)}
HELD = {"c": (-0.1, 0.5, 0.4), "d": (0.35, -0.35, 0.75), "e": (0.3, 0.3, 0.3)}


def one(nominal, seed: int, share: float, noise: float, joint: float, count: int) -> dict:
    true = perturb(nominal, np.random.default_rng(seed), share * 1e-3, np.deg2rad(0.2 * share), share * 1e-3)
    train, _ = make_dataset(true, TRAIN, count, np.random.default_rng(100 + seed), noise)
    held, _ = make_dataset(true, HELD, 30, np.random.default_rng(200 + seed), noise)
    if joint:  # recorded angles off by a smooth error of the configuration, one draw over training and held out
        q = np.concatenate([train.q, held.q])
        root = field_root(q, LENGTH)
        recorded = q - joint * root @ np.random.default_rng(300 + seed).standard_normal((root.shape[1], q.shape[1]))
        train = Dataset(labels=train.labels, q=recorded[: len(train.q)], fixture_names=train.fixture_names)
        held = Dataset(labels=held.labels, q=recorded[len(train.q):], fixture_names=held.fixture_names)
    spec = FixtureSpec(names=tuple(TRAIN), distances=[("a", "b", float(np.linalg.norm(np.subtract(*TRAIN.values()))))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        calibrated = run_workflow(nominal, train, spec, WorkflowOptions(force=True, model="dh")).model
    prediction = recorded_prediction(calibrated)
    report = socket_validation({"nominal": nominal, "calibrated": calibrated}, held, prediction=prediction)
    measured, _ = report.summary("calibrated")
    predicted = report.predicted_summary()
    return {"seed": seed, "measured_mm": measured * 1e3, "predicted_mm": predicted * 1e3, "ratio": measured / predicted,
            "socket_noise_mm": prediction.noise * 1e3, "joint_error_mrad": prediction.joint_error * 1e3}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("prediction_sim.json"))
    args = parser.parse_args()
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    clock = time.perf_counter()
    nominal = load_robot("panda")
    results = {}
    print(f"{'setup':<32} {'ratio median':>12} {'range':>13} {'in 0.5-2x':>9} {'socket noise':>13} {'joint error':>12}"
          "  (ratio = measured / predicted held-out test MAE; noise [mm] and error [mrad]: recorded, median)")
    for name, (share, noise, joint, count) in SETUPS.items():
        rows = [one(nominal, seed, share, noise, joint, count) for seed in range(args.seeds)]
        ratios = np.array([r["ratio"] for r in rows])
        inside = int(((ratios >= 0.5) & (ratios <= 2.0)).sum())
        print(f"{name:<32} {np.median(ratios):12.2f} {ratios.min():6.2f}..{ratios.max():<5.2f} "
              f"{inside:>5}/{len(rows):<3} "
              f"{np.median([r['socket_noise_mm'] for r in rows]):7.3f} ({noise * 1e3:.1f}) "
              f"{np.median([r['joint_error_mrad'] for r in rows]):6.2f} ({joint * 1e3:.1f})")
        results[name] = {"share": share, "noise_m": noise, "joint_error_rad": joint, "samples": count, "rows": rows}
    print(f"{time.perf_counter() - clock:.0f} s")
    bench_common.write_json(args.out, {"setups": results}, seed=0, inputs={"seeds": args.seeds})
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
